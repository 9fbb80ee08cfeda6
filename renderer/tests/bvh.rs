//! The BVH against brute force: random scenes of transformed primitives (the instance-level
//! BVH of `Aggregate`), axis-aligned rays lying in box planes, and a large mesh (the
//! per-mesh BVH) against testing every triangle on its own.

use glam::{DMat3, DQuat, DVec3};
use renderer::aggregate::Shape;
use renderer::bvh::Visit;
use renderer::real::{dvec3, vec3};
use renderer::shapes::{Mesh, Triangle};
use renderer::{Affine64, Aggregate, Hit, Instance, Ray, Real, Transform, Vec3};
use std::sync::Arc;

mod common;
use common::SplitMix;

const INF: Real = Real::INFINITY;

/// A random affine map: rotation, non-uniform scale, sometimes a shear, translation.
fn random_affine(rng: &mut SplitMix, extent: f64, size: f64) -> Affine64 {
    let q = loop {
        let v = glam::DVec4::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if v.length_squared() > 1e-3 {
            break DQuat::from_vec4(v.normalize());
        }
    };
    let scale = DVec3::new(
        rng.range(0.05, 1.0),
        rng.range(0.05, 1.0),
        rng.range(0.05, 1.0),
    ) * size;
    let mut m = DMat3::from_quat(q) * DMat3::from_diagonal(scale);
    if rng.chance(0.3) {
        let shear = DMat3::from_cols(
            DVec3::X,
            DVec3::new(rng.range(-0.6, 0.6), 1.0, 0.0),
            DVec3::new(rng.range(-0.6, 0.6), rng.range(-0.6, 0.6), 1.0),
        );
        m = shear * m;
    }
    Affine64 {
        m,
        d: rng.vec(-extent, extent),
    }
}

/// A UV sphere of radius ~1 with a deterministic bumpy (non-convex) radius, outward winding,
/// shared vertices (so it is closed).
fn bumpy_sphere(n_lat: usize, n_lon: usize, seed: u64) -> Mesh {
    let mut rng = SplitMix(seed);
    let mut pos = vec![Vec3::new(0.0, 1.0, 0.0)];
    for i in 1..n_lat {
        let theta = std::f64::consts::PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let phi = 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64;
            let r = 1.0 + 0.15 * (5.0 * theta).sin() * (3.0 * phi).cos() + rng.range(-0.02, 0.02);
            let p = DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ) * r;
            pos.push(vec3(p));
        }
    }
    pos.push(Vec3::new(0.0, -1.0, 0.0));
    let south = (pos.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut tris = Vec::new();
    for j in 0..n_lon {
        tris.push([0, ring(1, j + 1), ring(1, j)]);
        tris.push([south, ring(n_lat - 1, j), ring(n_lat - 1, j + 1)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    Mesh::new(pos, None, None, tris).expect("valid mesh")
}

fn random_shape(rng: &mut SplitMix, mesh: &Arc<Mesh>, group: &Arc<Aggregate>) -> Shape {
    match rng.below(11) {
        0 => Shape::Sphere,
        1 => Shape::Cube,
        2 => Shape::Cylinder { capped: true },
        3 => Shape::Cylinder { capped: false },
        4 => Shape::Cone { capped: true },
        5 => Shape::Cone { capped: false },
        6 => Shape::Disk,
        7 => Shape::Rectangle,
        8 => Shape::Mesh(mesh.clone()),
        9 => Shape::Group(group.clone()),
        _ => Shape::Triangle(Box::new(Triangle {
            p: [0, 1, 2].map(|_| vec3(rng.vec(-1.0, 1.0))),
            n: None,
            uv: None,
        })),
    }
}

/// A scene of `n` bounded instances (object ids 1..=n), plus sometimes a plane.
fn random_scene(rng: &mut SplitMix, n: usize, with_plane: bool) -> (Aggregate, f64) {
    let mesh = Arc::new(bumpy_sphere(8, 12, 3));
    let group = small_group(rng, |_| 0);
    // Keep the density roughly constant.
    let extent = 2.0 + 2.0 * (n as f64).cbrt();
    let mut instances: Vec<Instance> = (0..n)
        .map(|i| {
            let shape = random_shape(rng, &mesh, &group);
            let xf = if rng.chance(0.05) {
                None
            } else {
                Some(Transform::new(&random_affine(rng, extent, 1.0)).unwrap())
            };
            Instance {
                shape,
                xf,
                material: 0,
                object_id: i as u32 + 1,
            }
        })
        .collect();
    if with_plane {
        // Inserted somewhere in the middle so scene order is not special.
        let at = rng.below(instances.len() + 1);
        let plane = tilted_plane(rng, extent, 0);
        instances.insert(at, plane);
    }
    (Aggregate::new(instances), extent)
}

/// A definition of a sphere, a cube and a cone, each placed at random within a unit
/// extent; member `k` has material `material(k)`. Object ids are 0: each member inherits
/// the id of the instance that places the group.
fn small_group(rng: &mut SplitMix, material: impl Fn(usize) -> u32) -> Arc<Aggregate> {
    Arc::new(Aggregate::new(
        (0..3)
            .map(|k| Instance {
                shape: [Shape::Sphere, Shape::Cube, Shape::Cone { capped: true }][k].clone(),
                xf: Some(Transform::new(&random_affine(rng, 1.0, 0.6)).unwrap()),
                material: material(k),
                object_id: 0,
            })
            .collect(),
    ))
}

/// A plane below the scene (`extent` down), slightly tilted at random: an unbounded
/// instance, beside the tree; object id 1,000,000.
fn tilted_plane(rng: &mut SplitMix, extent: f64, material: u32) -> Instance {
    let a = Affine64 {
        m: DMat3::from_quat(DQuat::from_axis_angle(rng.unit(), rng.range(0.0, 0.5))),
        d: DVec3::new(0.0, -extent, 0.0),
    };
    Instance {
        shape: Shape::Plane,
        xf: Some(Transform::new(&a).unwrap()),
        material,
        object_id: 1_000_000,
    }
}

/// A random ray and interval. Some directions have exactly zero components (of either
/// sign), and some origins lie exactly in a plane of an instance's bounding box.
fn random_ray(rng: &mut SplitMix, agg: &Aggregate, extent: f64) -> (Ray, Real, Real) {
    let o = rng.vec(-1.5 * extent, 1.5 * extent);
    let mut d = if rng.chance(0.7) {
        // Towards a random instance.
        let inst = &agg.instances[rng.below(agg.instances.len())];
        let b = inst.bounds();
        let c = if b.is_finite() {
            dvec3(b.centroid()) + rng.vec(-0.5, 0.5)
        } else {
            rng.vec(-extent, extent)
        };
        (c - o).normalize_or(DVec3::X)
    } else {
        rng.unit()
    } * 10f64.powf(rng.range(-2.0, 2.0));
    let mut o = vec3(o);
    let zeros = match rng.below(10) {
        0 | 1 => 1,
        2 => 2,
        _ => 0,
    };
    for _ in 0..zeros {
        let k = rng.below(3);
        d[k] = if rng.chance(0.5) { 0.0 } else { -0.0 };
        // Put the origin in a bounding plane of some instance.
        if rng.chance(0.5) {
            let b = agg.instances[rng.below(agg.instances.len())].bounds();
            if b.is_finite() {
                o[k] = if rng.chance(0.5) { b.min[k] } else { b.max[k] };
            }
        }
    }
    if d == DVec3::ZERO {
        d = DVec3::X;
    }
    let t_min = if rng.chance(0.3) {
        rng.range(0.0, 1.0) as Real
    } else {
        0.0
    };
    let t_max = if rng.chance(0.3) {
        (t_min as f64 + rng.range(0.0, 3.0 * extent / d.length())) as Real
    } else {
        INF
    };
    (Ray::new(o, vec3(d)), t_min, t_max)
}

/// BVH and brute force agree on the first hit and on occlusion, and `Aggregate::nearest`
/// reports the bits of `intersect`'s record.
#[track_caller]
fn agree(agg: &Aggregate, r: &Ray, t_min: Real, t_max: Real, what: &str) -> bool {
    let bf = agg.intersect_brute_force(r, t_min, t_max);
    let bv = agg.intersect(r, t_min, t_max);
    let bits = |v: Vec3| v.to_array().map(Real::to_bits);
    assert_eq!(
        agg.nearest(r, t_min, t_max)
            .map(|h| (h.t.to_bits(), bits(h.n_geo), h.surface, h.prim)),
        bv.map(|h| (h.t.to_bits(), bits(h.n_geo), h.surface, h.prim)),
        "Aggregate::nearest's (t, n_geo, surface, prim) differ from intersect's record \
         (renderer/src/aggregate/mod.rs: nearest, its lone-instance shortcut, nearest_in_tree): \
         {what} {r:?} [{t_min}, {t_max}]"
    );
    match (bv, bf) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            let rel = ((a.t - b.t) as f64).abs() / (b.t as f64).max(Real::MIN_POSITIVE as f64);
            assert!(
                a.object_id == b.object_id || a.t == b.t,
                "BVH hit object {} at t = {}, brute force object {} at t = {}: {what} {r:?} [{t_min}, {t_max}]",
                a.object_id,
                a.t,
                b.object_id,
                b.t
            );
            assert!(rel <= 1e-6, "t {} vs {}: {what} {r:?}", a.t, b.t);
            assert!(
                a.t > t_min && a.t < t_max,
                "t = {} outside the interval",
                a.t
            );
        }
        (a, b) => panic!(
            "BVH {:?}, brute force {:?}: {what} ray {r:?} interval [{t_min}, {t_max}]",
            a.map(|h| (h.object_id, h.t)),
            b.map(|h| (h.object_id, h.t))
        ),
    }
    assert_eq!(
        agg.occluded(r, t_min, t_max),
        bf.is_some(),
        "occluded disagrees with brute force ({:?}): {what} ray {r:?} interval [{t_min}, {t_max}]",
        bf.map(|h| (h.object_id, h.t))
    );
    bf.is_some()
}

#[test]
fn random_scenes_match_brute_force() {
    let mut rng = SplitMix(2024);
    for (k, &n) in [1usize, 2, 3, 5, 17, 100, 500, 2000].iter().enumerate() {
        for with_plane in [false, true] {
            let (agg, extent) = random_scene(&mut rng, n, with_plane);
            let rays = if n >= 500 { 3000 } else { 5000 };
            let mut hits = 0;
            for i in 0..rays {
                let (r, t_min, t_max) = random_ray(&mut rng, &agg, extent);
                let what = format!("scene {k} (n = {n}, plane: {with_plane}), ray {i}");
                hits += agree(&agg, &r, t_min, t_max, &what) as usize;
            }
            // Enough rays hit something for the comparison to mean anything.
            assert!(hits * 50 > rays, "n = {n}: only {hits} of {rays} rays hit");
        }
    }
}

/// A scene of one bounded instance sends every search straight to it, without the tree's
/// bounds test: each kind of shape, under a random transform or none, and a compact
/// sphere, with and without a plane beside it, against brute force (closest hit and any
/// hit).
#[test]
fn one_instance_scenes_match_brute_force() {
    let mut rng = SplitMix(77);
    let mut kinds = std::collections::BTreeSet::new();
    for k in 0..88 {
        let with_plane = k % 2 == 1;
        let (agg, extent) = random_scene(&mut rng, 1, with_plane);
        let shape = &agg
            .instances
            .iter()
            .find(|i| i.object_id == 1)
            .unwrap()
            .shape;
        let kind = format!("{shape:?}");
        kinds.insert(kind[..kind.find([' ', '(', '{']).unwrap_or(kind.len())].to_string());
        let mut hits = 0;
        for i in 0..400 {
            let (r, t_min, t_max) = random_ray(&mut rng, &agg, extent);
            let what = format!("one-instance scene {k} ({kind:.40}, plane: {with_plane}), ray {i}");
            hits += agree(&agg, &r, t_min, t_max, &what) as usize;
        }
        assert!(hits > 0, "one-instance scene {k} ({kind:.40}): no ray hit");
    }
    assert_eq!(
        kinds.len(),
        9,
        "not every kind of shape was drawn: {kinds:?}"
    );
    // A sphere placed by a uniform scale and a translation is a compact record (a lead),
    // which the lone search tests by its own path.
    for k in 0..8 {
        let with_plane = k % 2 == 1;
        let r = rng.range(0.3, 3.0);
        let mut instances = vec![Instance {
            shape: Shape::Sphere,
            xf: Some(
                Transform::new(&Affine64 {
                    m: DMat3::from_diagonal(DVec3::splat(r)),
                    d: rng.vec(-2.0, 2.0),
                })
                .unwrap(),
            ),
            material: 0,
            object_id: 1,
        }];
        if with_plane {
            instances.push(Instance {
                shape: Shape::Plane,
                xf: Some(Transform::new(&Affine64::translate(DVec3::new(0.0, -1.0, 0.0))).unwrap()),
                material: 0,
                object_id: 2,
            });
        }
        let agg = Aggregate::new(instances);
        let mut hits = 0;
        for i in 0..400 {
            let (ray, t_min, t_max) = random_ray(&mut rng, &agg, 4.0);
            let what = format!("one compact sphere {k} (radius {r}, plane: {with_plane}), ray {i}");
            hits += agree(&agg, &ray, t_min, t_max, &what) as usize;
        }
        assert!(hits > 0, "one compact sphere {k}: no ray hit");
    }
}

/// Axis-aligned boxes, cylinders and cones with exactly representable bounds, and rays that
/// lie exactly in a plane of those bounds (direction components ±0): the boundary of a box
/// belongs to it, so the BVH must not cull what brute force hits there.
#[test]
fn rays_in_bounding_planes() {
    let mut instances = Vec::new();
    let shapes = [
        Shape::Cube,
        Shape::Cylinder { capped: true },
        Shape::Cone { capped: true },
        Shape::Cube,
    ];
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                let c = DVec3::new(4.0 * i as f64, 4.0 * j as f64, 4.0 * k as f64);
                let id = instances.len() as u32 + 1;
                instances.push(Instance {
                    shape: shapes[(i + j + k) % 4].clone(),
                    xf: (c != DVec3::ZERO)
                        .then(|| Transform::new(&Affine64::translate(c)).unwrap()),
                    material: 0,
                    object_id: id,
                });
            }
        }
    }
    let agg = Aggregate::new(instances);
    let mut rng = SplitMix(77);
    let mut hits = 0;
    let mut count = 0;
    for inst in &agg.instances {
        let b = inst.bounds();
        for plane_axis in 0..3 {
            for side in [b.min, b.max] {
                for move_axis in (0..3).filter(|&a| a != plane_axis) {
                    for sign in [1.0 as Real, -1.0] {
                        for zero in [0.0 as Real, -0.0] {
                            let third = 3 - plane_axis - move_axis;
                            let mut o = Vec3::ZERO;
                            o[plane_axis] = side[plane_axis];
                            o[move_axis] = b.centroid()[move_axis] - sign * 5.0;
                            // Across the face, including its edges.
                            o[third] = match rng.below(4) {
                                0 => b.min[third],
                                1 => b.max[third],
                                _ => b.min[third] + (b.max[third] - b.min[third]) * rng.f() as Real,
                            };
                            let mut d = Vec3::splat(zero);
                            d[move_axis] = sign;
                            let r = Ray::new(o, d);
                            let what = format!("in the plane {plane_axis} of {:?}", b);
                            hits += agree(&agg, &r, 0.0, INF, &what) as usize;
                            count += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(hits * 2 > count, "only {hits} of {count} rays hit");
}

/// Closest hit over every triangle, each tested on its own.
fn brute_force_triangles(tris: &[Triangle], r: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let mut best = None;
    let mut t_max = t_max;
    for t in tris {
        if let Some(h) = t.intersect(r, t_min, t_max) {
            t_max = h.t;
            best = Some(h);
        }
    }
    best
}

#[test]
fn mesh_bvh_matches_brute_force() {
    let mesh = bumpy_sphere(48, 64, 11);
    assert!(mesh.triangles.len() > 5000);
    let tris: Vec<Triangle> = (0..mesh.triangles.len())
        .map(|i| Triangle {
            p: mesh.vertices(i),
            n: None,
            uv: None,
        })
        .collect();
    let mut rng = SplitMix(5);
    let check = |r: &Ray, t_min: Real, t_max: Real, what: &str| -> Option<Hit> {
        let bf = brute_force_triangles(&tris, r, t_min, t_max);
        let bv = mesh.intersect(r, t_min, t_max);
        match (bv, bf) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                let rel = ((a.t - b.t) as f64).abs() / b.t as f64;
                assert!(rel <= 1e-6, "t {} vs {}: {what} {r:?}", a.t, b.t);
                let scale = 1.0 + dvec3(b.p).length();
                assert!(
                    (dvec3(a.p) - dvec3(b.p)).length() <= 1e-5 * scale,
                    "p {:?} vs {:?}: {what}",
                    a.p,
                    b.p
                );
            }
            (a, b) => panic!(
                "mesh {:?}, brute force {:?}: {what} {r:?} [{t_min}, {t_max}]",
                a.map(|h| h.t),
                b.map(|h| h.t)
            ),
        }
        assert_eq!(
            mesh.occluded(r, t_min, t_max),
            bf.is_some(),
            "occluded: {what} {r:?} [{t_min}, {t_max}]"
        );
        bf
    };
    // Random rays from around the mesh, random intervals.
    let mut hits = 0;
    for i in 0..20_000 {
        let o = rng.unit() * rng.range(0.0, 4.0);
        let d = (rng.vec(-1.2, 1.2) - o).normalize_or(DVec3::Y) * rng.range(0.1, 10.0);
        let t_min = if i % 4 == 0 { rng.range(0.0, 0.5) } else { 0.0 } as Real;
        let t_max = if i % 5 == 0 {
            rng.range(0.1, 3.0) as Real
        } else {
            INF
        };
        let r = Ray::new(vec3(o), vec3(d));
        hits += check(&r, t_min, t_max, &format!("random ray {i}")).is_some() as usize;
    }
    assert!(hits > 10_000, "only {hits} hits");
    // The mesh is star-shaped about the origin: every triangle faces away from it, so each
    // ray from the origin crosses the surface exactly once.
    for i in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.vertices(i).map(dvec3);
        assert!(
            (b - a).cross(c - a).dot(a + b + c) > 0.0,
            "triangle {i} faces inward"
        );
    }
    // Watertight: from the centre towards every vertex and every edge midpoint, a ray
    // always hits; along the same line from outside, it hits at the vertex.
    for (i, &v) in mesh.positions.iter().enumerate() {
        let r = Ray::new(Vec3::ZERO, v);
        let h = check(&r, 0.0, INF, &format!("towards vertex {i}"));
        let h = h.unwrap_or_else(|| panic!("a ray from inside through vertex {i} escaped"));
        assert!(
            (h.t - 1.0).abs() <= 1e-5,
            "hit at t = {}, vertex {i} at t = 1",
            h.t
        );
        let s = rng.range(1.5, 4.0);
        let r = Ray::new(vec3(dvec3(v) * s), vec3(dvec3(v) * -(s - 1.0)));
        let h = check(&r, 0.0, INF, &format!("from outside to vertex {i}"));
        let h = h.unwrap_or_else(|| panic!("a ray from outside through vertex {i} missed"));
        assert!(
            (h.t - 1.0).abs() <= 1e-5,
            "hit at t = {}, vertex {i} at t = 1",
            h.t
        );
    }
    for (i, t) in mesh.triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (
                mesh.positions[t[e] as usize],
                mesh.positions[t[(e + 1) % 3] as usize],
            );
            let r = Ray::new(Vec3::ZERO, (a + b) * 0.5);
            let h = check(&r, 0.0, INF, &format!("towards edge {e} of triangle {i}"));
            assert!(
                h.is_some(),
                "a ray from inside through edge {e} of triangle {i} escaped"
            );
        }
    }
}

/// Spheres placed by a uniform scale and a translation take the aggregate's compact path
/// (traversal and the final hit read a 32-byte record, not the instance). The result must
/// be the very hit the general path gives: same t, point, error bound, normals, uv,
/// material and object id, bit for bit. Scales and offsets span tiny to far away, and
/// general instances (non-uniform spheres, cubes) are mixed in.
#[test]
fn compact_spheres_match_the_general_path_bit_for_bit() {
    let mut rng = SplitMix(31);
    for (scene, &(extent, size)) in [(10.0, 1.0), (1e-3, 1e-4), (1e5, 3.0), (1e4, 1e3)]
        .iter()
        .enumerate()
    {
        let instances: Vec<Instance> = (0..400)
            .map(|i| {
                let d = rng.vec(-extent, extent);
                let (shape, m) = match rng.below(4) {
                    0 => (Shape::Cube, DMat3::from_diagonal(rng.vec(0.2, 1.0) * size)),
                    1 => (
                        Shape::Sphere,
                        DMat3::from_diagonal(rng.vec(0.2, 1.0) * size),
                    ),
                    _ => (
                        Shape::Sphere,
                        DMat3::from_diagonal(DVec3::splat(rng.range(0.2, 1.0) * size)),
                    ),
                };
                Instance {
                    shape,
                    xf: Some(Transform::new(&Affine64 { m, d }).unwrap()),
                    material: i as u32 % 7,
                    object_id: i as u32 + 1,
                }
            })
            .collect();
        let agg = Aggregate::new(instances);
        let mut hits = 0;
        for i in 0..4000 {
            let (r, t_min, t_max) = random_ray(&mut rng, &agg, extent);
            let bv = agg.intersect(&r, t_min, t_max);
            let bf = agg.intersect_brute_force(&r, t_min, t_max);
            assert_eq!(
                hit_bits(&bv),
                hit_bits(&bf),
                "scene {scene}, ray {i}: {r:?} [{t_min}, {t_max}]"
            );
            assert_eq!(
                agg.occluded(&r, t_min, t_max),
                bf.is_some(),
                "scene {scene}, ray {i}"
            );
            hits += bf.is_some() as usize;
        }
        assert!(hits > 400, "scene {scene}: only {hits} of 4000 rays hit");
    }
}

/// The bits of a hit, every field but the primitive (which the scalar triangle tests the
/// mesh is compared with do not set).
type HitBits = (u64, [[u64; 3]; 4], [u64; 2], u32, u32, u64);

fn hit_bits(h: &Option<Hit>) -> Option<HitBits> {
    h.map(|h| {
        let v = [h.p, h.err, h.n_geo, h.n_shade].map(|v| v.to_array().map(|x| x.to_bits() as u64));
        (
            h.t.to_bits() as u64,
            v,
            h.uv.to_array().map(|x| x.to_bits() as u64),
            h.material,
            h.object_id,
            h.surface,
        )
    })
}

/// `Aggregate::nearest` (the record Embree reports: what the peers benchmark times) makes
/// `intersect`'s search: its distance, geometric normal, surface and primitive are the
/// bits of `intersect`'s record, and it finds nothing exactly when `intersect` does, on
/// random scenes (meshes, definitions, planes, general and uniformly scaled instances,
/// placed or not) and on one mesh, placed and not (the lone-instance shortcut of
/// `Aggregate::nearest`), where its barycentrics are the record's uv (the mesh has none
/// of its own).
#[test]
fn nearest_reports_the_records_fields() {
    let mut rng = SplitMix(4242);
    let mesh = Arc::new(bumpy_sphere(30, 40, 9));
    let mut scenes: Vec<(Aggregate, f64, &str)> = Vec::new();
    for (n, with_plane) in [
        (1, false),
        (3, true),
        (100, true),
        (2000, false),
        (2000, true),
    ] {
        let (agg, extent) = random_scene(&mut rng, n, with_plane);
        scenes.push((agg, extent, "random"));
    }
    let spheres: Vec<Instance> = (0..300)
        .map(|i| Instance {
            shape: Shape::Sphere,
            xf: Some(
                Transform::new(&Affine64 {
                    m: DMat3::from_diagonal(DVec3::splat(rng.range(0.2, 1.0))),
                    d: rng.vec(-10.0, 10.0),
                })
                .unwrap(),
            ),
            material: 0,
            object_id: i + 1,
        })
        .collect();
    scenes.push((Aggregate::new(spheres), 10.0, "uniformly scaled spheres"));
    let placed = Instance {
        shape: Shape::Mesh(mesh.clone()),
        xf: Some(Transform::new(&random_affine(&mut rng, 1.0, 2.0)).unwrap()),
        material: 0,
        object_id: 1,
    };
    scenes.push((Aggregate::new(vec![placed]), 3.0, "one placed mesh"));
    let unplaced = Instance {
        shape: Shape::Mesh(mesh.clone()),
        xf: None,
        material: 0,
        object_id: 1,
    };
    scenes.push((Aggregate::new(vec![unplaced]), 3.0, "one mesh"));
    for (scene, (agg, extent, what)) in scenes.iter().enumerate() {
        let (mut hits, mut prims) = (0, std::collections::HashSet::new());
        for i in 0..3000 {
            let (r, t_min, t_max) = random_ray(&mut rng, agg, *extent);
            let full = agg.intersect(&r, t_min, t_max);
            let lean = agg.nearest(&r, t_min, t_max);
            let at = format!("scene {scene} ({what}), ray {i}: {r:?} [{t_min}, {t_max}]");
            let (Some(full), Some(lean)) = (full, lean) else {
                assert_eq!(
                    full.is_some(),
                    lean.is_some(),
                    "{at}: Aggregate::nearest and intersect disagree on whether anything is hit"
                );
                continue;
            };
            let bits = |v: Vec3| v.to_array().map(Real::to_bits);
            assert_eq!(
                (lean.t.to_bits(), bits(lean.n_geo), lean.surface, lean.prim),
                (full.t.to_bits(), bits(full.n_geo), full.surface, full.prim),
                "{at}: Aggregate::nearest's (t, n_geo, surface, prim) differ from intersect's \
                 record (its search, or the normal's mapping in finish_nearest)"
            );
            if matches!(*what, "one placed mesh" | "one mesh") {
                assert_eq!(
                    lean.b.to_array().map(Real::to_bits),
                    full.uv.to_array().map(Real::to_bits),
                    "{at}: Mesh::nearest's barycentrics differ from the record's uv"
                );
            }
            hits += 1;
            prims.insert((lean.surface, lean.prim));
        }
        assert!(
            hits > 300,
            "scene {scene} ({what}): only {hits} of 3000 rays hit"
        );
        // Many surfaces and primitives, so that the numbering is compared too (a scene of
        // one primitive has one).
        let want = agg.instances.len().min(20);
        assert!(
            prims.len() >= want,
            "scene {scene} ({what}): only {} (surface, primitive) pairs hit",
            prims.len()
        );
    }
}

/// Camera rays go through `intersect_many`, which walks rays of a large tree interleaved
/// (and shadow rays may go through `occluded_many`, which must answer as `occluded`).
/// Each must get exactly the hit `intersect` gives it alone: same bits in every field,
/// on a tree large enough to interleave (mixed shapes, a plane, nested groups) and on a
/// small one that does not.
#[test]
fn interleaved_rays_match_one_at_a_time() {
    let mut rng = SplitMix(77);
    for (n, interleaved) in [(40_000, true), (300, false)] {
        let (agg, extent) = random_scene(&mut rng, n, true);
        assert_eq!(agg.interleaves(), interleaved, "n = {n}");
        let mut hits = 0;
        // Batches of odd sizes, each with its own interval.
        for call in 0..150 {
            let (_, t_min, t_max) = random_ray(&mut rng, &agg, extent);
            let rays: Vec<Ray> = (0..1 + call % 37)
                .map(|_| random_ray(&mut rng, &agg, extent).0)
                .collect();
            let mut out = vec![None; rays.len()];
            agg.intersect_many(&rays, t_min, t_max, &mut out);
            let mut shadow = vec![false; rays.len()];
            agg.occluded_many(&rays, t_min, t_max, &mut shadow);
            for ((r, got), &occluded) in rays.iter().zip(&out).zip(&shadow) {
                let alone = agg.intersect(r, t_min, t_max);
                assert_eq!(
                    hit_bits(got),
                    hit_bits(&alone),
                    "n = {n}, call {call}: {r:?} [{t_min}, {t_max}]"
                );
                assert_eq!(
                    occluded,
                    agg.occluded(r, t_min, t_max),
                    "n = {n}, call {call}: Aggregate::occluded_many against occluded, {r:?} \
                     [{t_min}, {t_max}]"
                );
                hits += alone.is_some() as usize;
            }
        }
        assert!(hits > 300, "n = {n}: only {hits} rays hit");
    }
}

/// A mesh tests the triangles of a leaf four at a time (one SIMD pack) and builds the hit
/// record once, for the winner. That must be the scalar watertight test exactly: every
/// field of the hit equal, bit for bit, to the closest hit of the triangles tested one by
/// one — also where an edge function is exactly 0 (rays through shared vertices and edges
/// of an integer grid, which the scalar test redoes in f64) and on degenerate triangles.
/// Where two triangles tie at the closest t (a ray through a shared edge), the search
/// may return either: then t itself must be the same bits.
#[test]
fn mesh_packs_match_the_scalar_test_bit_for_bit() {
    // A bumpy sphere, plus an integer grid (exact zero edge functions at its vertices and
    // edges) and degenerate triangles, in one mesh.
    let sphere = bumpy_sphere(40, 56, 23);
    let mut pos = sphere.positions.clone();
    let mut tris = sphere.triangles.clone();
    let base = pos.len() as u32;
    let n = 12;
    for j in 0..=n {
        for i in 0..=n {
            pos.push(Vec3::new(i as Real - 6.0, -2.0, j as Real - 6.0));
        }
    }
    let at = |i: u32, j: u32| base + j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            tris.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            tris.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    tris.push([at(0, 0), at(0, 0), at(1, 1)]); // two equal vertices
    tris.push([at(0, 0), at(1, 1), at(2, 2)]); // collinear
    let mesh = Mesh::new(pos, None, None, tris).unwrap();
    let one_by_one: Vec<Triangle> = (0..mesh.triangles.len())
        .map(|i| Triangle {
            p: mesh.vertices(i),
            n: None,
            uv: None,
        })
        .collect();
    let mut rng = SplitMix(31);
    let mut rays = Vec::new();
    for _ in 0..6000 {
        let o = rng.unit() * rng.range(0.0, 5.0);
        let d = rng.vec(-1.5, 1.5) - o;
        rays.push(Ray::new(vec3(o), vec3(d)));
    }
    // Straight down onto grid vertices and edge midpoints, and through the sphere's
    // vertices from its centre.
    for j in 0..=2 * n {
        for i in 0..=2 * n {
            let (x, z) = (i as f64 * 0.5 - 6.0, j as f64 * 0.5 - 6.0);
            rays.push(Ray::new(
                vec3(DVec3::new(x, 3.0, z)),
                vec3(DVec3::new(0.0, -1.0, 0.0)),
            ));
        }
    }
    for &v in sphere.positions.iter().step_by(3) {
        rays.push(Ray::new(Vec3::ZERO, v));
    }
    let (mut unique, mut ties) = (0, 0);
    for (k, r) in rays.iter().enumerate() {
        let got = mesh.intersect(r, 0.0, INF);
        let want = brute_force_triangles(&one_by_one, r, 0.0, INF);
        let tied = want.is_some_and(|w| {
            one_by_one
                .iter()
                .filter(|t| t.intersect(r, 0.0, INF).is_some_and(|h| h.t == w.t))
                .count()
                > 1
        });
        if tied {
            ties += 1;
            assert_eq!(
                got.map(|h| h.t.to_bits()),
                want.map(|h| h.t.to_bits()),
                "ray {k} (a tie): {r:?}"
            );
        } else {
            unique += want.is_some() as usize;
            assert_eq!(hit_bits(&got), hit_bits(&want), "ray {k}: {r:?}");
        }
        assert_eq!(mesh.occluded(r, 0.0, INF), want.is_some(), "ray {k}");
    }
    assert!(
        unique > 3000 && ties > 100,
        "{unique} unique hits, {ties} ties"
    );
}

/// A large mesh walks the rays of a batch together (`Mesh::intersect_batch`, through
/// `Aggregate::intersect_many` when the mesh is the scene's one bounded instance; and
/// `Mesh::occluded_batch`, through `Aggregate::occluded_many`, for any hit). Each ray must
/// get exactly what `intersect` (or `occluded`) gives it alone, with its own interval; on
/// a small mesh that does not interleave too, with a transform, beside a plane and inside
/// a definition.
#[test]
fn mesh_batches_match_one_ray_at_a_time() {
    let mut rng = SplitMix(41);
    for (mesh, interleaved) in [
        (bumpy_sphere(200, 300, 3), true),
        (bumpy_sphere(12, 16, 4), false),
    ] {
        let mesh = Arc::new(mesh);
        assert_eq!(mesh.interleaves(), interleaved);
        let placed = |xf: Option<Transform>| Instance {
            shape: Shape::Mesh(mesh.clone()),
            xf,
            material: 1,
            object_id: 1,
        };
        let plane = Instance {
            shape: Shape::Plane,
            xf: Some(Transform::new(&Affine64::translate(DVec3::new(0.0, -0.9, 0.0))).unwrap()),
            material: 2,
            object_id: 2,
        };
        let turned = Transform::new(&random_affine(&mut rng, 0.3, 1.0)).unwrap();
        let defined = Instance {
            shape: Shape::Group(Arc::new(Aggregate::new(vec![placed(Some(turned))]))),
            xf: None,
            material: 1,
            object_id: 1,
        };
        for agg in [
            Aggregate::new(vec![placed(None)]),
            Aggregate::new(vec![placed(Some(turned))]),
            Aggregate::new(vec![placed(None), plane.clone()]),
            Aggregate::new(vec![defined]),
        ] {
            let mut hits = 0;
            let mut occluded = [0, 0];
            for call in 0..120 {
                let rays: Vec<Ray> = (0..1 + call % 37)
                    .map(|_| {
                        let o = rng.unit() * rng.range(1.5, 4.0);
                        Ray::new(vec3(o), vec3(rng.vec(-1.0, 1.0) - o))
                    })
                    .collect();
                let t_max = if call % 3 == 0 {
                    rng.range(0.5, 3.0) as Real
                } else {
                    INF
                };
                let mut out = vec![None; rays.len()];
                agg.intersect_many(&rays, 0.0, t_max, &mut out);
                let mut direct = vec![None; rays.len()];
                let bounds = vec![t_max; rays.len()];
                let mut shadow = vec![false; rays.len()];
                agg.occluded_many(&rays, 0.0, t_max, &mut shadow);
                let mut shadow_direct = 0u128;
                for (chunk, (rs, o)) in rays.chunks(16).zip(direct.chunks_mut(16)).enumerate() {
                    let bounds = &bounds[16 * chunk..16 * chunk + rs.len()];
                    mesh.intersect_batch(rs, 0.0, bounds, o);
                    shadow_direct |= (mesh.occluded_batch(rs, 0.0, bounds) as u128) << (16 * chunk);
                }
                for (k, r) in rays.iter().enumerate() {
                    let alone = agg.intersect(r, 0.0, t_max);
                    assert_eq!(hit_bits(&out[k]), hit_bits(&alone), "call {call}, ray {k}");
                    assert_eq!(
                        hit_bits(&direct[k]),
                        hit_bits(&mesh.intersect(r, 0.0, t_max)),
                        "call {call}, ray {k}, mesh batch"
                    );
                    hits += alone.is_some() as usize;
                    let alone = agg.occluded(r, 0.0, t_max);
                    assert_eq!(
                        shadow[k], alone,
                        "call {call}, ray {k}: Aggregate::occluded_many against occluded"
                    );
                    assert_eq!(
                        (shadow_direct >> k) & 1 == 1,
                        mesh.occluded(r, 0.0, t_max),
                        "call {call}, ray {k}: Mesh::occluded_batch against Mesh::occluded"
                    );
                    occluded[alone as usize] += 1;
                }
            }
            assert!(hits > 500, "only {hits} hits");
            assert!(
                occluded.iter().all(|&n| n > 50),
                "occluded and clear rays both: {occluded:?}"
            );
        }
    }
}

/// Boxes along the x axis at geometrically growing distances: the SAH peels the farthest
/// ones off one level at a time, so the tree is as deep as the build allows, and a ray
/// from the origin along +x meets every box, nearest first, with the far siblings of each
/// level waiting on the traversal stack.
fn geometric_row<const W: usize>(n: usize) -> (renderer::bvh::Bvh<W>, Vec<usize>) {
    let boxes: Vec<renderer::aabb::Aabb> = (0..n)
        .map(|k| {
            let x = 1.25f64.powi(k as i32);
            renderer::aabb::Aabb::from_points(
                vec3(DVec3::new(x, -0.5, -0.5)),
                vec3(DVec3::new(x * 1.05, 0.5, 0.5)),
            )
        })
        .collect();
    renderer::bvh::Bvh::build((0..n).collect(), &boxes, 1.0)
}

/// Every traversal picks a fixed-capacity stack by the tree's depth (tiny, short, long);
/// a deep tree given a shallow tree's stack would overflow it (a panic). Rows of 2 to 320
/// boxes, every count (so that every depth, and the last depth each stack serves, is
/// built), make trees from one level to the build's depth limit, 8 and 4 wide; the ray
/// must visit every box, alone and in a batch. (An undercounted stack, one entry short
/// per tree, overflowed 8-wide rows of 53 to 57 and 115 to 119 boxes.)
#[test]
fn deep_degenerate_trees_visit_every_leaf_alone_and_in_batches() {
    for n in 2..=320 {
        visit_every_leaf::<8>(n);
        visit_every_leaf::<4>(n);
    }
}

fn visit_every_leaf<const W: usize>(n: usize) {
    {
        let (bvh, order) = geometric_row::<W>(n);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let mut seen = vec![0u32; n];
        let hit = bvh.traverse(&ray, 0.0, INF, false, |i, _| {
            seen[order[i as usize]] += 1;
            Visit::Miss
        });
        assert!(
            !hit,
            "{n} boxes, {W} wide: nothing reported a hit, yet the walk found one"
        );
        assert!(
            seen.iter().all(|&c| c == 1),
            "{n} boxes in a row, {W} wide: the ray along the row visited them {seen:?} times \
             (each exactly once expected; see Bvh::traverse_leaves in renderer/src/bvh/traverse.rs)"
        );
        let rays = vec![ray; renderer::bvh::BATCH];
        let t_max = vec![INF; rays.len()];
        let mut seen = vec![vec![0u32; n]; rays.len()];
        bvh.traverse_batch(
            &rays,
            0.0,
            &t_max,
            |r, i, _| {
                seen[r][order[i as usize]] += 1;
                Visit::Miss
            },
            |_| std::ptr::null(),
        );
        for (r, s) in seen.iter().enumerate() {
            assert!(
                s.iter().all(|&c| c == 1),
                "{n} boxes in a row, {W} wide, batch ray {r}: visited {s:?} times (each exactly once \
                 expected; see Bvh::traverse_batch_leaves in renderer/src/bvh/traverse.rs)"
            );
        }
    }
}

/// The six walls of a room, as instances see them: thin boxes, any two of which span the
/// whole room. `Bvh::build_spread` puts them in one node, a wall per lane, so a ray from
/// the middle tests only the wall it faces; `Bvh::build` leaves them in leaves of three
/// (every binary split looks as dear as a leaf to the SAH), where the ray tests three.
#[test]
fn spread_walls_cost_a_ray_one_test() {
    let wall = |axis: usize, side: f64| {
        let (mut lo, mut hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        lo[axis] = side;
        hi[axis] = side;
        renderer::aabb::Aabb::from_points(vec3(lo), vec3(hi))
    };
    let boxes: Vec<renderer::aabb::Aabb> = (0..6)
        .map(|k| wall(k / 2, if k % 2 == 0 { -1.0 } else { 1.0 }))
        .collect();
    let spread = renderer::bvh::Bvh::<8>::build_spread((0..6usize).collect(), &boxes, 1.0);
    let plain = renderer::bvh::Bvh::<8>::build((0..6usize).collect(), &boxes, 1.0);
    let tests = |(bvh, order): &(renderer::bvh::Bvh<8>, Vec<usize>), d: DVec3| {
        let ray = Ray::new(Vec3::ZERO, vec3(d));
        let mut tested = Vec::new();
        bvh.traverse(&ray, 0.0, INF, false, |i, _| {
            tested.push(order[i as usize]);
            // Each wall is hit at distance 1 along an axis direction.
            Visit::Hit(1.0)
        });
        tested
    };
    for k in 0..6 {
        let mut d = DVec3::ZERO;
        d[k / 2] = if k % 2 == 0 { -1.0 } else { 1.0 };
        let s = tests(&spread, d);
        assert_eq!(
            s,
            vec![k],
            "a ray from the middle of the room along {d}: build_spread tested walls {s:?}, \
             only the one it faces ({k}) expected (renderer/src/bvh/build.rs build_binary)"
        );
        let p = tests(&plain, d);
        assert!(
            p.len() > 1 && p.contains(&k),
            "along {d}, the plain build tested {p:?}: a leaf of several walls expected \
             (if the SAH now spreads them itself, this test and Bvh::build_spread need a \
             look)"
        );
    }
    assert_eq!(spread.0.node_count(), 1, "one node holds the six walls");
}

/// The box from `lo` to `hi`.
fn aabb(lo: DVec3, hi: DVec3) -> renderer::aabb::Aabb {
    renderer::aabb::Aabb::from_points(vec3(lo), vec3(hi))
}

/// The sizes of the leaves a ray from `o` along `d` visits, nearest first.
fn leaf_sizes(bvh: &renderer::bvh::Bvh<8>, o: DVec3, d: DVec3) -> Vec<u8> {
    let mut sizes = Vec::new();
    bvh.traverse_leaves(
        &Ray::new(vec3(o), vec3(d)),
        0.0,
        INF,
        false,
        |_, count, _| {
            sizes.push(count);
            Visit::Miss
        },
    );
    sizes
}

/// `Bvh::build_spread` spreads a set only when the SAH says so: one node plus each box's
/// share of the set's box must cost less than testing them all. Four boxes that each
/// fill 7/8 of the set's box (cost 1 + 3.5 against 4) stay one leaf, and so do two slabs
/// that make the cost exactly 2 for 2 (a tie keeps the leaf). Three slabs crossing at a
/// common centre (cost 2 against 3) are spread though their centroids coincide and no
/// binned split exists: the set is cut by halves instead.
#[test]
fn spread_only_where_the_sah_says() {
    let aabb = |lo: [f64; 3], hi: [f64; 3]| aabb(DVec3::from(lo), DVec3::from(hi));
    let build = |boxes: &[renderer::aabb::Aabb]| {
        renderer::bvh::Bvh::<8>::build_spread((0..boxes.len()).collect::<Vec<_>>(), boxes, 1.0).0
    };
    // Area of [0, a] x [0, 1] x [0, 1] over the unit cube's: (2a + 1) / 3 = 7/8.
    let a = 0.8125;
    let fill = build(&[
        aabb([0.0; 3], [a, 1.0, 1.0]),
        aabb([0.0; 3], [a, 1.0, 1.0]),
        aabb([1.0 - a, 0.0, 0.0], [1.0; 3]),
        aabb([1.0 - a, 0.0, 0.0], [1.0; 3]),
    ]);
    let s = leaf_sizes(&fill, DVec3::new(0.5, 0.5, -1.0), DVec3::Z);
    assert_eq!(
        s,
        vec![4],
        "four boxes of 7/8 of the set's box: one leaf of four expected, got leaves {s:?} \
         (the SAH price of a spread node in renderer/src/bvh/build.rs build_binary)"
    );
    // Slabs z in [0, 1/4] and [3/4, 1] of the unit cube: each 3/6 of its area.
    let tie = build(&[
        aabb([0.0; 3], [1.0, 1.0, 0.25]),
        aabb([0.0, 0.0, 0.75], [1.0; 3]),
    ]);
    let s = leaf_sizes(&tie, DVec3::new(0.5, 0.5, -1.0), DVec3::Z);
    assert_eq!(
        s,
        vec![2],
        "two slabs whose spread node costs exactly the leaf's 2: the leaf expected, got \
         leaves {s:?} (renderer/src/bvh/build.rs build_binary: a tie keeps the leaf)"
    );
    let cross = build(&[
        aabb([0.0, -1.0, -1.0], [0.0, 1.0, 1.0]),
        aabb([-1.0, 0.0, -1.0], [1.0, 0.0, 1.0]),
        aabb([-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]),
    ]);
    let s = leaf_sizes(&cross, DVec3::new(-2.0, 0.5, 0.5), DVec3::X);
    assert_eq!(
        s,
        vec![1],
        "three crossing slabs with one centroid, a ray through one of them: one leaf of \
         one expected, got leaves {s:?} (renderer/src/bvh/build.rs build_binary: a spread set \
         with no binned split is cut by halves)"
    );
}

/// A mesh's leaves are tested a pack of four triangles at a time, so `Bvh::build_aligned`
/// prices a leaf by its packs: splitting four triangles into two leaves buys nothing
/// unless the two halves' boxes are much smaller. On a grid of equal small triangles the
/// packs then come out nearly full. (Priced by triangles, the SAH split most fours into
/// leaves of one to three, and filled 43 % of the slots of the benchmark mesh.)
#[test]
fn aligned_leaves_fill_their_packs() {
    let n = 64;
    let boxes: Vec<renderer::aabb::Aabb> = (0..n * n)
        .flat_map(|k| {
            let (x, y) = ((k % n) as f64, (k / n) as f64);
            // Two triangles per cell, each the box of its half.
            [
                (DVec3::new(x, y, 0.0), DVec3::new(x + 1.0, y + 1.0, 0.0)),
                (DVec3::new(x, y, 0.0), DVec3::new(x + 1.0, y + 1.0, 0.01)),
            ]
        })
        .map(|(lo, hi)| aabb(lo, hi))
        .collect();
    // Packs of four as a mesh uses; other sizes likewise.
    fill_packs::<4>(&boxes);
    fill_packs::<1>(&boxes);
    fill_packs::<2>(&boxes);
    fill_packs::<8>(&boxes);
}

/// Builds `boxes` in packs of `ALIGN` and checks that the packs are over 90 % full.
fn fill_packs<const ALIGN: usize>(boxes: &[renderer::aabb::Aabb]) {
    let (_, slots) =
        renderer::bvh::Bvh::<8>::build_aligned::<_, ALIGN>((0..boxes.len()).collect(), boxes, 1.0);
    let used = slots.iter().filter(|s| s.is_some()).count();
    assert_eq!(used, boxes.len(), "every triangle has one slot");
    let fill = used as f64 / slots.len() as f64;
    assert!(
        fill > 0.9,
        "{used} triangles took {} slots in packs of {ALIGN} ({:.0} % full, over 90 % \
         expected): the SAH of Bvh::build_aligned (renderer/src/bvh/build.rs, build_binary and \
         best_split) should price a leaf by its packs",
        slots.len(),
        100.0 * fill
    );
}

/// The triangle counts of the leaves that rays along −z meet, one ray through the middle
/// of each of `cells` (x, y) points, on a tree of `build_aligned` with packs of four.
fn leaf_counts(boxes: &[renderer::aabb::Aabb], cells: &[(f64, f64)]) -> Vec<u8> {
    let (bvh, _) =
        renderer::bvh::Bvh::<8>::build_aligned::<_, 4>((0..boxes.len()).collect(), boxes, 1.0);
    cells
        .iter()
        .flat_map(|&(x, y)| leaf_sizes(&bvh, DVec3::new(x, y, 10.0), DVec3::NEG_Z))
        .collect()
}

/// `build_aligned` keeps a leaf to two packs, splits a set the SAH finds cheaper split
/// even when it would fit in two packs, and makes leaves of two packs where they pay.
/// (The fill test above cannot tell these apart: they change the tree, not the padding.)
#[test]
fn aligned_leaves_hold_at_most_two_packs() {
    // Twelve long boxes over the same square, each nudged: any split leaves both sides
    // nearly the whole square, so the SAH prices every split above one leaf of three
    // packs. A leaf holds two at most, so the set must be split anyway.
    let long: Vec<_> = (0..12)
        .map(|k| {
            let e = 1e-3 * k as f64;
            aabb(DVec3::new(e, e, 0.0), DVec3::new(1.0 + e, 1.0 + e, 0.1))
        })
        .collect();
    let counts = leaf_counts(&long, &[(0.5, 0.5)]);
    assert_eq!(
        counts.iter().map(|&c| c as usize).sum::<usize>(),
        12,
        "a ray through twelve overlapping triangles met leaves of {counts:?}: it should \
         meet each triangle once (Bvh::traverse_leaves in renderer/src/bvh/traverse.rs)"
    );
    assert!(
        counts.iter().all(|&c| c <= 8),
        "twelve overlapping triangles went to leaves of {counts:?}: a leaf of a mesh holds \
         at most two packs of four (build_binary in renderer/src/bvh/build.rs)"
    );
    // Two clusters of three small boxes, far apart: six would fit in one leaf of two
    // packs, but two leaves of one pack each cost far less by the SAH.
    let clusters: Vec<_> = [0.0, 100.0]
        .iter()
        .flat_map(|&x0| {
            (0..3).map(move |k| {
                let x = x0 + 0.1 * k as f64;
                aabb(DVec3::new(x, 0.0, 0.0), DVec3::new(x + 0.1, 0.1, 0.0))
            })
        })
        .collect();
    let counts = leaf_counts(&clusters, &[(0.15, 0.05)]);
    assert_eq!(
        counts,
        [3],
        "a ray through one of two far-apart clusters of three met leaves of {counts:?}: \
         the SAH should split them apart (build_binary in renderer/src/bvh/build.rs)"
    );
    // Sixteen far-apart clusters of eight overlapping triangles: split, a cluster's halves
    // would each cover nearly all of it (a node plus two packs' tests, against two packs
    // for the leaf), so each cluster is one leaf of two full packs.
    let clusters: Vec<_> = (0..16)
        .flat_map(|c| {
            (0..8).map(move |k| {
                let (x, e) = (10.0 * c as f64, 1e-3 * k as f64);
                aabb(
                    DVec3::new(x + e, e, 0.0),
                    DVec3::new(x + 1.0 + e, 1.0 + e, 0.1),
                )
            })
        })
        .collect();
    let cells: Vec<_> = (0..16).map(|c| (10.0 * c as f64 + 0.5, 0.5)).collect();
    let counts = leaf_counts(&clusters, &cells);
    assert!(
        counts.iter().all(|&c| c == 8),
        "rays through sixteen clusters of eight overlapping triangles met leaves of \
         {counts:?} (8 each, two full packs, expected: build_binary in renderer/src/bvh/build.rs \
         lets a leaf hold two packs)"
    );
}

/// A mesh keeps its triangles in the BVH's leaf order, but gives them back in the order
/// they came in: the exporters write that order, so an export (and the hash of it that a
/// reference records, references/manifest.toml) does not change when the tree does.
#[test]
fn meshes_give_their_triangles_back_in_the_given_order() {
    let n = 20u32;
    let positions: Vec<Vec3> = (0..(n + 1) * (n + 1))
        .map(|k| vec3(DVec3::new((k % (n + 1)) as f64, (k / (n + 1)) as f64, 0.0)))
        .collect();
    let given: Vec<[u32; 3]> = (0..n * n)
        .flat_map(|c| {
            let (x, y) = (c % n, c / n);
            let v = |dx: u32, dy: u32| (y + dy) * (n + 1) + x + dx;
            [[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]]
        })
        .collect();
    let mesh = Mesh::new(positions, None, None, given.clone()).unwrap();
    assert_ne!(mesh.triangles, given, "the tree should reorder this grid");
    assert_eq!(
        mesh.triangles_as_given(),
        given,
        "Mesh::triangles_as_given (renderer/src/shapes/mesh.rs) lost the given order"
    );
    // A hit's `prim` is its triangle's number as given (Embree's primID), which each pack
    // keeps beside its triangles: a ray down through every triangle's centroid, from the
    // full search, the lean one and the batch.
    let batch_len = renderer::bvh::BATCH;
    let rays: Vec<Ray> = given
        .iter()
        .map(|t| {
            let c = t
                .iter()
                .fold(Vec3::ZERO, |a, &k| a + mesh.positions[k as usize])
                / 3.0;
            Ray::new(c + Vec3::Z, Vec3::new(0.0, 0.0, -1.0))
        })
        .collect();
    let mut batch = vec![None; batch_len];
    for (chunk, rays) in rays.chunks(batch_len).enumerate() {
        let ends = vec![Real::INFINITY; rays.len()];
        mesh.intersect_batch(rays, 0.0, &ends, &mut batch);
        for (k, ray) in rays.iter().enumerate() {
            let want = (chunk * batch_len + k) as u32;
            let got = (
                mesh.intersect(ray, 0.0, Real::INFINITY).map(|h| h.prim),
                mesh.nearest(ray, 0.0, Real::INFINITY).map(|h| h.prim),
                batch[k].as_ref().map(|h| h.prim),
            );
            assert_eq!(
                got,
                (Some(want), Some(want), Some(want)),
                "a ray through triangle {want}'s centroid: the hit's prim from Mesh::intersect, \
                 Mesh::nearest and Mesh::intersect_batch (renderer/src/shapes/mesh.rs) is not \
                 that triangle's number as given (TriPack::number)"
            );
        }
    }
}

/// A small scene of spheres, cubes, cylinders (capped or open), rectangles, disks and
/// planes is searched in lanes by `intersect_many` (aggregate/lanes.rs): every ray must get
/// exactly the hit `intersect` gives it alone, on scenes with general affine instances,
/// unplaced ones, spheres placed by a scale and a translation (the aggregate's leads),
/// planes beside the tree, and copies of one instance, where every hit is a tie that the
/// scalar search decides.
#[test]
fn small_scenes_in_lanes_match_one_at_a_time() {
    let mut rng = SplitMix(2611);
    let mut hits = 0;
    let mut scenes_in_lanes = 0;
    for scene in 0..300 {
        // Up to 16 instances, the most the lanes take (`lanes::MAX_INSTANCES`).
        let n = 1 + rng.below(16);
        let extent = 2.0 + 2.0 * (n as f64).cbrt();
        let mut instances: Vec<Instance> = (0..n)
            .map(|i| {
                let shape = [
                    Shape::Sphere,
                    Shape::Cube,
                    Shape::Cylinder { capped: true },
                    Shape::Cylinder { capped: false },
                    Shape::Rectangle,
                    Shape::Disk,
                    Shape::Plane,
                ][rng.below(7)]
                .clone();
                let xf = match rng.below(10) {
                    0 => None,
                    // A sphere lead's form: a uniform scale and a translation.
                    1 | 2 => Some(Affine64 {
                        m: DMat3::from_diagonal(DVec3::splat(rng.range(0.1, 2.0))),
                        d: rng.vec(-extent, extent),
                    }),
                    _ => Some(random_affine(&mut rng, extent, 1.0)),
                };
                Instance {
                    shape,
                    xf: xf.map(|a| Transform::new(&a).unwrap()),
                    material: i as u32,
                    object_id: i as u32 + 1,
                }
            })
            .collect();
        if scene % 5 == 0 {
            // A copy of an instance: its hits tie.
            let mut copy = instances[rng.below(n)].clone();
            copy.object_id = 99;
            instances.push(copy);
        }
        let agg = Aggregate::new(instances);
        let in_lanes = agg.searches_in_lanes();
        scenes_in_lanes += in_lanes as usize;
        for call in 0..20 {
            let (_, t_min, t_max) = random_ray(&mut rng, &agg, extent);
            let mut rays: Vec<Ray> = (0..1 + (call * 7) % 23)
                .map(|_| random_ray(&mut rng, &agg, extent).0)
                .collect();
            if call == 0 {
                rays.push(Ray::new(Vec3::splat(Real::NAN), Vec3::X));
                rays.push(Ray::new(Vec3::ZERO, Vec3::new(0.0, Real::INFINITY, 1.0)));
            }
            if call < 4 {
                // From points exactly on the unplaced sphere, cube and plane y = 0: a
                // root exactly at t = 0, on the interval's open end when t_min is 0.
                for o in [Vec3::X, Vec3::NEG_Y, Vec3::new(0.25, 0.0, -0.5), Vec3::ONE] {
                    rays.push(Ray::new(o, vec3(rng.unit())));
                }
                // From the unplaced cylinder's cap, rim and side, and along its axis
                // (no side roots: a cap counts when the ray runs inside the radius).
                for o in [
                    Vec3::new(0.25, 1.0, -0.5),
                    Vec3::new(0.0, -1.0, 1.0),
                    Vec3::Z,
                ] {
                    rays.push(Ray::new(o, vec3(rng.unit())));
                }
                for (x, dy) in [(0.5, 1.0), (0.5, -1.0), (1.0, 1.0), (1.5, -1.0)] {
                    rays.push(Ray::new(
                        Vec3::new(x, 3.0 * dy, 0.0),
                        Vec3::new(0.0, -dy, 0.0),
                    ));
                }
            }
            let mut out = vec![None; rays.len()];
            agg.intersect_many_for_shading(&rays, t_min, t_max, &mut out);
            let mut with_uv = vec![None; rays.len()];
            agg.intersect_many(&rays, t_min, t_max, &mut with_uv);
            for ((r, got), got_uv) in rays.iter().zip(&out).zip(&with_uv) {
                let alone = agg.intersect_for_shading(r, t_min, t_max);
                assert_eq!(
                    hit_bits(got),
                    hit_bits(&alone),
                    "scene {scene} (in lanes: {in_lanes}), call {call}: {r:?} [{t_min}, {t_max}]: \
                     the lanes' search (renderer/src/aggregate/lanes.rs) differs from \
                     intersect_for_shading"
                );
                assert_eq!(
                    hit_bits(got_uv),
                    hit_bits(&agg.intersect(r, t_min, t_max)),
                    "scene {scene} (in lanes: {in_lanes}), call {call}: {r:?} [{t_min}, {t_max}]: \
                     the lanes' search with uv (renderer/src/aggregate/lanes.rs) differs from \
                     intersect"
                );
                hits += alone.is_some() as usize;
            }
        }
    }
    assert!(
        scenes_in_lanes > 200,
        "only {scenes_in_lanes} of 300 scenes in lanes"
    );
    assert!(hits > 1500, "only {hits} rays hit");
}

/// `Aggregate::intersect_for_shading_if`, the search for a path's last vertex, finds what
/// `intersect_for_shading` finds, and finishes the record only when the hit's material is
/// wanted: on scenes of the bounded shapes (`random_shape`), meshes, definitions whose
/// members have materials of their own or inherit the placing instance's, spheres placed
/// by a scale and a translation (the aggregate's leads, which keep their material apart),
/// and a plane beside the tree (an unbounded instance, which has no lead), each ray is
/// asked with the even materials wanted, then the odd ones.
#[test]
fn the_last_vertex_search_finishes_only_wanted_materials() {
    let mut rng = SplitMix(2911);
    let mesh = Arc::new(bumpy_sphere(8, 12, 3));
    // The middle member has its own material; the others inherit.
    let group = small_group(&mut rng, |k| {
        if k == 1 {
            7
        } else {
            renderer::aggregate::INHERIT
        }
    });
    // Finished records by material % 4, those of the member with its own material, and
    // those of the plane.
    let mut seen = [0usize; 6];
    for scene in 0..60 {
        let n = 1 + rng.below(12);
        let extent = 2.0 + 2.0 * (n as f64).cbrt();
        let mut instances: Vec<Instance> = (0..n)
            .map(|i| {
                let (shape, xf) = if rng.chance(0.3) {
                    let a = Affine64 {
                        m: DMat3::from_diagonal(DVec3::splat(rng.range(0.2, 1.5))),
                        d: rng.vec(-extent, extent),
                    };
                    (Shape::Sphere, Some(a))
                } else {
                    let shape = if rng.chance(0.3) {
                        Shape::Group(group.clone())
                    } else {
                        random_shape(&mut rng, &mesh, &group)
                    };
                    (shape, Some(random_affine(&mut rng, extent, 1.0)))
                };
                Instance {
                    shape,
                    xf: xf.map(|a| Transform::new(&a).unwrap()),
                    material: (i % 4) as u32,
                    object_id: i as u32 + 1,
                }
            })
            .collect();
        if scene % 3 == 0 {
            // A plane beside the tree (unbounded: no lead), with a material of its own.
            instances.push(tilted_plane(&mut rng, extent, 5));
        }
        let agg = Aggregate::new(instances);
        for call in 0..60 {
            let (ray, t_min, t_max) = random_ray(&mut rng, &agg, extent);
            let alone = agg.intersect_for_shading(&ray, t_min, t_max);
            for parity in 0..2 {
                let mut h = Hit::default();
                let got =
                    agg.intersect_for_shading_if(&ray, t_min, t_max, &mut h, |m| m % 2 == parity);
                let wanted = alone.map(|a| a.material % 2 == parity);
                assert_eq!(
                    got, wanted,
                    "scene {scene}, call {call}, {ray:?} [{t_min}, {t_max}]: \
                     intersect_for_shading_if (renderer/src/aggregate/mod.rs) reports {got:?} \
                     where intersect_for_shading's hit {alone:?} says {wanted:?}: the winner's \
                     material (Aggregate::material_of) is wrong"
                );
                if got == Some(true) {
                    assert_eq!(
                        hit_bits(&Some(h)),
                        hit_bits(&alone),
                        "scene {scene}, call {call}: intersect_for_shading_if finished another \
                         record than intersect_for_shading's"
                    );
                }
                if let (Some(a), Some(true)) = (alone, got) {
                    seen[a.material as usize % 4] += 1;
                    seen[4] += (a.material == 7) as usize;
                    seen[5] += (a.material == 5) as usize;
                }
            }
        }
    }
    assert!(
        seen.iter().all(|&k| k > 20),
        "every material, the definition's member with its own and the plane must be hit and \
         wanted: {seen:?}"
    );
}

/// The cylinder's edge cases in lanes (`Crossing` of shapes/cylinder.rs, lane by lane),
/// each exactly as `intersect` decides it: rays along the axis (no side roots: a cap counts when the
/// ray runs inside the radius, on it included), rays parallel to the caps (the slab is
/// everything or nothing), rays through a rim (a side root equal to the slab's end), and
/// rays from a point on the cap, the rim and the side, on the unplaced cylinder, capped
/// and open.
#[test]
fn cylinder_edges_in_lanes_match_one_at_a_time() {
    let v = Vec3::new;
    let mut rays = Vec::new();
    for x in [0.0, 0.5, 1.0, 1.5] {
        for dy in [1.0, -1.0] {
            rays.push(Ray::new(v(x, 3.0 * dy, 0.0), v(0.0, -dy, 0.0)));
            rays.push(Ray::new(v(0.0, 0.5 * dy, x), v(0.0, -dy, 0.0)));
        }
    }
    for y in [-1.0, 0.5, 1.0, 1.5] {
        rays.push(Ray::new(v(3.0, y, 0.0), v(-1.0, 0.0, 0.0)));
        rays.push(Ray::new(v(0.0, y, 0.0), v(0.0, 0.0, 1.0)));
    }
    for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        // Through the rim at (sx, sy, 0): the side root and the slab's end are both 2.
        rays.push(Ray::new(v(3.0 * sx, 3.0 * sy, 0.0), v(-sx, -sy, 0.0)));
        // From the axis out through the rim: both 1.
        rays.push(Ray::new(Vec3::ZERO, v(sx, sy, 0.0)));
    }
    // Aimed at points of the rims from anywhere: the side's point lands on either side
    // of y = ±1 in rounding, which the clamp to the slab takes back.
    let mut rng = SplitMix(7);
    for _ in 0..4096 {
        let (o, d) = rng.toward_cylinder_rim();
        rays.push(Ray::new(vec3(o), vec3(d)));
    }
    for o in [v(0.25, 1.0, -0.5), v(0.0, -1.0, 1.0), Vec3::Z] {
        for d in [
            v(0.0, -1.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(-0.6, -0.8, 0.0),
        ] {
            rays.push(Ray::new(o, d));
        }
    }
    for capped in [true, false] {
        let agg = Aggregate::new(vec![Instance {
            shape: Shape::Cylinder { capped },
            xf: None,
            material: 0,
            object_id: 1,
        }]);
        assert!(
            agg.searches_in_lanes(),
            "the cylinder alone is not searched in lanes"
        );
        let mut hits = 0;
        for chunk in rays.chunks(16) {
            let mut out = vec![None; chunk.len()];
            agg.intersect_many(chunk, 0.0, Real::INFINITY, &mut out);
            for (r, got) in chunk.iter().zip(&out) {
                let alone = agg.intersect(r, 0.0, Real::INFINITY);
                assert_eq!(
                    hit_bits(got),
                    hit_bits(&alone),
                    "cylinder (capped: {capped}), {r:?}: the lanes' cylinder \
                     (shapes/cylinder.rs Crossing, lane by lane in aggregate/lanes.rs) differs from \
                     shapes/cylinder.rs"
                );
                hits += alone.is_some() as usize;
            }
        }
        assert!(
            hits > rays.len() / 3,
            "only {hits} of {} rays hit",
            rays.len()
        );
    }
}

/// A ray with a NaN in its origin or its direction does not panic any search, on trees
/// of every size: the searches agree with each other, and a ray whose origin is all NaN
/// (which every shape's test reads) hits nothing. (Such a ray once overflowed the walk's
/// stack: the slab test ignores a NaN product, so every lane overlapped, the empty ones
/// too, whose child was node 0, the root; bvh/node.rs `NO_NODE`, bvh/traverse.rs
/// `Walk::step`. A NaN in one component of the direction may still meet a shape whose
/// test ignores that axis, as the cube's slab test does: the record then carries the NaN,
/// and a render reports its pixel as non-finite.)
#[test]
fn rays_with_a_nan_do_not_panic() {
    let mut rng = SplitMix(5150);
    let nan = Real::NAN;
    let rays = [
        Ray::new(Vec3::splat(nan), Vec3::X),
        Ray::new(Vec3::new(0.0, nan, 0.0), Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::new(1.0, nan, 0.0)),
        Ray::new(Vec3::ONE, Vec3::splat(nan)),
    ];
    for n in [2, 9, 300, 40_000] {
        let (agg, _) = random_scene(&mut rng, n, n % 2 == 1);
        let mut out = vec![None; rays.len()];
        agg.intersect_many(&rays, 0.0, INF, &mut out);
        let mut shadow = vec![true; rays.len()];
        agg.occluded_many(&rays, 0.0, INF, &mut shadow);
        for (k, r) in rays.iter().enumerate() {
            let what = format!("n = {n}, {r:?}");
            let hit = agg.intersect(r, 0.0, INF);
            if k == 0 {
                assert!(hit.is_none(), "{what}: intersect");
            }
            assert_eq!(
                hit.map(|h| h.t.to_bits()),
                agg.nearest(r, 0.0, INF).map(|h| h.t.to_bits()),
                "{what}: nearest"
            );
            assert_eq!(hit_bits(&out[k]), hit_bits(&hit), "{what}: intersect_many");
            let occluded = agg.occluded(r, 0.0, INF);
            assert_eq!(shadow[k], occluded, "{what}: occluded_many");
            if hit.is_some() {
                assert!(occluded, "{what}: a hit, but not occluded");
            }
        }
    }
}

/// Where the tree's box test and an instance's own test disagree, the lanes give what
/// testing every instance gives (aggregate/lanes.rs): an unplaced rectangle and a sphere
/// away from it, and a ray down onto the rectangle's edge x = 1, nearly parallel to the
/// edge's box face: the rectangle's test puts the hit at x = 1 + ε/4, which rounds to 1,
/// on the rectangle, where the box test's slab in x ends at t = 0, before the slab in y
/// begins. The scalar search's answer there is the tree's (it may be none).
#[test]
fn lanes_are_the_brute_force_search_at_a_box_edge() {
    let sphere = Transform::new(&Affine64 {
        m: DMat3::IDENTITY,
        d: DVec3::new(-5.0, 0.0, 0.0),
    })
    .unwrap();
    let agg = Aggregate::new(vec![
        Instance {
            shape: Shape::Rectangle,
            xf: None,
            material: 0,
            object_id: 1,
        },
        Instance {
            shape: Shape::Sphere,
            xf: Some(sphere),
            material: 0,
            object_id: 2,
        },
    ]);
    assert!(agg.searches_in_lanes());
    // A quarter of an ulp of 1 in either build: 1 + it rounds to 1.
    let tiny = Real::EPSILON * 0.25;
    let ray = Ray::new(Vec3::new(1.0, 1.0, 0.0), Vec3::new(tiny, -1.0, 0.0));
    let mut out = [None];
    agg.intersect_many(&[ray], 0.0, INF, &mut out);
    let brute = agg.intersect_brute_force(&ray, 0.0, INF);
    assert!(brute.is_some(), "the rectangle's own test accepts the ray");
    assert_eq!(
        hit_bits(&out[0]),
        hit_bits(&brute),
        "aggregate/lanes.rs: the lanes' hit is not the brute-force search's"
    );
}
