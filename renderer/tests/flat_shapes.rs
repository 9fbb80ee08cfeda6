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
