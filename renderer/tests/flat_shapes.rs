//! The flat primitives (plane, box, disk, rectangle) against hand-worked closed forms, one
//! `check` line per case.
//!
//! For each hit the helper checks: t against the closed form, the normalized geometric
//! normal against the analytic outward normal, uv against the mapping documented in the
//! shape's source, that `Hit.p` is the point o + t·d and lies on the surface within its own
//! error bound `Hit.err` (finite, non-negative), that scaling the direction by 3 divides t
//! by 3, that the interval `(t_min, t_max)` is honoured, and that `occluded` agrees.

use renderer::aggregate::Shape;

mod common;
use common::primitives::*;

#[test]
fn plane() {
    let s = Shape::Plane;
    // uv are the hit's x and z.
    check(
        &s,
        [1., 2., 3.],
        [0., -1., 0.],
        hit(2.0, [0., 1., 0.], [1.0, 3.0]),
    );
    check(
        &s,
        [0., 4., 0.],
        [1., -2., 0.5],
        hit(2.0, [0., 1., 0.], [2.0, 1.0]),
    );
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    check(&s, [0., 1., 0.], [1., 0., 0.], Miss);
    // In the plane: parallel, so never a hit (and never NaN).
    graze(&s, [0., 0., 0.], [1., 0., 0.], None);
    check(&s, [0., 0., 0.], [1., 0., 0.], Miss);
    // From below: the normal stays +y.
    check(
        &s,
        [0., -1., 0.],
        [0.5, 1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.0]),
    );
}

#[test]
fn cube() {
    let s = Shape::Cube;
    // uv on the face of axis k: ((p[k+1]+1)/2, (p[k+2]+1)/2).
    check(
        &s,
        [0.2, 0.3, -5.],
        [0., 0., 1.],
        hit(4.0, [0., 0., -1.], [0.6, 0.65]),
    );
    check(
        &s,
        [5., 0., 0.],
        [-2., 0.2, 0.1],
        hit(2.0, [1., 0., 0.], [0.7, 0.6]),
    );
    check(
        &s,
        [0.5, 4., -0.5],
        [0., -1., 0.],
        hit(3.0, [0., 1., 0.], [0.25, 0.75]),
    );
    check(&s, [0., 1.5, -5.], [0., 0., 1.], Miss);
    check(&s, [3., 3., 3.], [1., 0., 0.], Miss);
    check(&s, [2.5, 0., 0.], [-1., 1., 0.], Miss); // passes beside the edge x = y = 1
                                                   // Along an edge and along a face plane: a miss or a hit on the boundary.
    graze(&s, [-5., 1., 1.], [1., 0., 0.], Some([-1., 1., 1.]));
    graze(&s, [-5., 1., 0.], [1., 0., 0.], Some([-1., 1., 0.]));
    check(&s, [-5., 1.001, 0.], [1., 0., 0.], Miss);
    check(
        &s,
        [-5., 0.999, 0.],
        [1., 0., 0.],
        hit(4.0, [-1., 0., 0.], [0.9995, 0.5]),
    );
    // From inside: the exit face, outward normal.
    check(
        &s,
        [0., 0., 0.],
        [0., 0., 1.],
        hit(1.0, [0., 0., 1.], [0.5, 0.5]),
    );
    check(
        &s,
        [0.5, -0.5, 0.25],
        [0., -1., 0.],
        hit(0.5, [0., -1., 0.], [0.625, 0.75]),
    );
}

#[test]
fn disk() {
    let s = Shape::Disk;
    // uv ((x+1)/2, (z+1)/2).
    check(
        &s,
        [0.3, 2., 0.4],
        [0., -1., 0.],
        hit(2.0, [0., 1., 0.], [0.65, 0.7]),
    );
    check(
        &s,
        [0., 1., 0.],
        [0.5, -1., -0.5],
        hit(1.0, [0., 1., 0.], [0.75, 0.25]),
    );
    // Inside the square but outside the unit circle.
    check(&s, [0.8, 1., 0.8], [0., -1., 0.], Miss);
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    // In the plane, and through the rim.
    graze(&s, [-5., 0., 0.], [1., 0., 0.], None);
    check(&s, [-5., 0., 0.], [1., 0., 0.], Miss);
    graze(&s, [1., 1., 0.], [0., -1., 0.], Some([1., 0., 0.]));
    // From the far side: the normal is not flipped.
    check(
        &s,
        [0.2, -1., 0.],
        [0., 1., 0.],
        hit(1.0, [0., 1., 0.], [0.6, 0.5]),
    );
}

#[test]
fn rectangle() {
    let s = Shape::Rectangle;
    check(
        &s,
        [0.8, 1., 0.8],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.9, 0.9]),
    );
    check(
        &s,
        [0., 3., 0.],
        [-0.25, -1.5, 0.25],
        hit(2.0, [0., 1., 0.], [0.25, 0.75]),
    );
    check(&s, [1.2, 1., 0.], [0., -1., 0.], Miss);
    check(&s, [0., 1., -1.01], [0., -1., 0.], Miss);
    graze(&s, [-5., 0., 0.5], [1., 0., 0.], None);
    check(&s, [-5., 0., 0.5], [1., 0., 0.], Miss);
    graze(&s, [1., 1., 1.], [0., -1., 0.], Some([1., 0., 1.]));
    check(
        &s,
        [-0.5, -2., 0.5],
        [0., 2., 0.],
        hit(1.0, [0., 1., 0.], [0.25, 0.75]),
    );
}

/// The rectangle is closed: a ray that meets its plane exactly on an edge or a corner
/// (|x| = 1 or |z| = 1) hits it, so two rectangles sharing an edge leave no gap there.
#[test]
fn rays_exactly_on_a_rectangle_edge_hit() {
    for (x, z) in [
        (1.0, 0.3),
        (-1.0, -0.7),
        (0.2, 1.0),
        (0.5, -1.0),
        (1.0, 1.0),
        (-1.0, 1.0),
    ] {
        let down = ray([x, 2.0, z], [0.0, -1.0, 0.0]);
        let h = Shape::Rectangle.intersect(&down, 0.0, INF).unwrap_or_else(|| {
            panic!("a ray onto the rectangle's edge at ({x}, {z}) missed (renderer/src/shapes/flat.rs)")
        });
        assert_eq!(h.t, 2.0);
        check_record(&Shape::Rectangle, &down, &h);
    }
}

/// A shadow ray's test (`Shape::occluded`, which for these shapes decides from `t` and
/// the point alone, without building the hit record) says hit exactly when the full test
/// returns a hit, over random rays and intervals: intervals that end just before or just
/// after the hit's `t`, rays aimed at the edges and corners, and rays starting inside the
/// box.
#[test]
fn shadow_tests_agree_with_the_full_tests() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let shapes = [Shape::Plane, Shape::Rectangle, Shape::Disk, Shape::Cube];
    let mut hits = [0usize; 4];
    for i in 0..20_000 {
        let mut v = |s: f64| [(); 3].map(|_| (next() * 2.0 - 1.0) * s);
        let o = if i % 4 == 0 { v(0.9) } else { v(4.0) };
        // Aimed at a point near the shapes' edges (|x|, |z| about 1) or anywhere.
        let mut aim = v(1.2);
        if i % 3 == 0 {
            aim[0] = aim[0].signum();
        }
        let d = [aim[0] - o[0], aim[1] - o[1], aim[2] - o[2]];
        let r = ray(o, d);
        for (k, s) in shapes.iter().enumerate() {
            let Some(h) = s.intersect(&r, 0.0, INF) else {
                assert!(
                    !s.occluded(&r, 0.0, INF),
                    "{s:?}: occluded but no hit, ray {i}"
                );
                continue;
            };
            hits[k] += 1;
            let t = h.t;
            for (lo, hi) in [
                (0.0, INF),
                (0.0, t),
                (0.0, t.next_up()),
                (t, INF),
                (t.next_down(), INF),
                (t * 0.5, t * 2.0),
                (t * 0.999, t * 1.001),
            ] {
                assert_eq!(
                    s.occluded(&r, lo, hi),
                    s.intersect(&r, lo, hi).is_some(),
                    "{s:?}, ray {i} ({o:?} + t {d:?}), interval ({lo}, {hi}): the shadow test \
                     and the full test disagree (renderer/src/shapes/flat.rs, cube.rs)"
                );
            }
        }
    }
    assert!(
        hits.iter().all(|&h| h > 1000),
        "too few hits to compare: {hits:?}"
    );
}
