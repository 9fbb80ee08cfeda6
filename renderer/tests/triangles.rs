//! Triangles and meshes against hand-worked closed forms, one `check` line per case.
//!
//! For each hit the helper checks: t against the closed form, the normalized geometric
//! normal against the analytic outward normal, uv against the mapping documented in the
//! shape's source, that `Hit.p` is the point o + t·d and lies on the surface within its own
//! error bound `Hit.err` (finite, non-negative), that scaling the direction by 3 divides t
//! by 3, that the interval `(t_min, t_max)` is honoured, and that `occluded` agrees.

mod common;
use common::primitives::*;

#[test]
fn triangle_cases() {
    let s = triangle();
    // The plane x + y/2 + z/3 = 1 meets the diagonal at (6/11)(1,1,1); barycentrics
    // (6/11, 3/11, 2/11); default uv = (b1, b2).
    let uv = [3.0 / 11.0, 2.0 / 11.0];
    check(
        &s,
        [2., 2., 2.],
        [-1., -1., -1.],
        hit(2.0 - 6.0 / 11.0, [6., 3., 2.], uv),
    );
    // From behind: same t formula, normal still (p1 − p0) × (p2 − p0).
    check(
        &s,
        [0., 0., 0.],
        [1., 1., 1.],
        hit(6.0 / 11.0, [6., 3., 2.], uv),
    );
    check(
        &s,
        [0., 0., 0.],
        [3., 3., 3.],
        hit(2.0 / 11.0, [6., 3., 2.], uv),
    );
    // Vertex uvs are interpolated: (0,0)·b0 + (1,0)·b1 + (0.5,1)·b2.
    let s_uv = triangle_with_uv();
    check(
        &s_uv,
        [0., 0., 0.],
        [1., 1., 1.],
        hit(6.0 / 11.0, [6., 3., 2.], [4.0 / 11.0, 2.0 / 11.0]),
    );
    // Misses: away, and through the plane outside the triangle (y < 0).
    check(&s, [0., 0., 0.], [-1., -1., -1.], Miss);
    check(&s, [0., 0., 0.], [1., -0.1, 1.], Miss);
    // In the plane along an edge (parallel), and exactly through an edge's midpoint.
    graze(&s, [2., -2., 0.], [-1., 2., 0.], None);
    check(&s, [2., -2., 0.], [-1., 2., 0.], Miss);
    graze(&s, [6.5, 4., 2.], [-6., -3., -2.], Some([0.5, 1., 0.]));
}

#[test]
fn mesh_quad() {
    let s = quad_mesh(true);
    check(
        &s,
        [0.2, 1., -0.4],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.6, 0.3]),
    );
    check(
        &s,
        [0., 2., 0.],
        [0.25, -1., -0.25],
        hit(2.0, [0., 1., 0.], [0.75, 0.25]),
    );
    // Exactly on the shared diagonal: watertight, so it must hit.
    check(
        &s,
        [0.3, 1., 0.3],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.65, 0.65]),
    );
    check(
        &s,
        [0., 1., 0.],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.5]),
    );
    check(
        &s,
        [-0.9, 1., 0.9],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.05, 0.95]),
    );
    check(&s, [1.5, 1., 0.], [0., -1., 0.], Miss);
    check(&s, [0., 1., 0.], [0., 1., 0.], Miss);
    graze(&s, [-5., 0., 0.3], [1., 0., 0.], None);
    graze(&s, [1., 1., 0.2], [0., -1., 0.], Some([1., 0., 0.2]));
    // From the far side.
    check(
        &s,
        [-0.5, -1., 0.5],
        [0., 1., 0.],
        hit(1.0, [0., 1., 0.], [0.25, 0.75]),
    );
    // Without vertex uvs, uv = (b1, b2) of the triangle hit: (−0.5, 0, 0.5) in triangle
    // (−1,0,−1), (−1,0,1), (1,0,1) has b = (0.25, 0.5, 0.25).
    let s = quad_mesh(false);
    check(
        &s,
        [-0.5, 1., 0.5],
        [0., -1., 0.],
        hit(1.0, [0., 1., 0.], [0.5, 0.25]),
    );
}

/// A hit names the triangle it found by its number in the order the mesh was given
/// (`Hit::prim`, Embree's primID, which the peers benchmark compares ray by ray), not by
/// the BVH's order: a 16 × 16 grid of quads (512 triangles, given in a scrambled order so
/// that the tree reorders them), each triangle hit at its centroid from above.
#[test]
fn mesh_hits_name_their_triangle_as_given() {
    use renderer::aggregate::Shape;
    use renderer::shapes::Mesh;
    use renderer::{Ray, Real, Vec3};
    use std::sync::Arc;
    let n = 16u32;
    let pos: Vec<Vec3> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| Vec3::new(i as Real, 0.0, j as Real)))
        .collect();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            tris.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    // Scrambled: triangle k goes to place (k · 97) mod 512 (97 is prime to 512).
    let m = tris.len();
    let mut given = vec![[0u32; 3]; m];
    for (k, t) in tris.iter().enumerate() {
        given[k * 97 % m] = *t;
    }
    let s = Shape::Mesh(Arc::new(
        Mesh::new(pos.clone(), None, None, given.clone()).expect("valid mesh"),
    ));
    for (k, t) in given.iter().enumerate() {
        let c = t.iter().map(|&v| pos[v as usize]).sum::<Vec3>() / 3.0;
        let r = Ray::new(c + Vec3::Y, -Vec3::Y);
        let h = s
            .intersect(&r, 0.0, Real::INFINITY)
            .unwrap_or_else(|| panic!("the ray down to triangle {k}'s centroid {c} missed"));
        assert_eq!(
            h.prim, k as u32,
            "the hit at triangle {k}'s centroid {c} names triangle {}: Hit::prim must be \
             the number as given (Mesh::finish, renderer/src/shapes/mesh.rs)",
            h.prim
        );
    }
}
