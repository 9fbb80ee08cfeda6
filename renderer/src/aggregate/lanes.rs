//! The closest-hit search of a small aggregate for [`BATCH`] rays at once, in lanes: each
//! instance is tested against every ray with element-wise operations over arrays of the
//! rays' components, which the compiler turns into vector instructions (8 rays a
//! register at `f32`).
//!
//! A scene of a few canonical primitives (a floor, a light, a sphere, a box: most of the physical
//! catalog) pays more for the tree walk than for the tests themselves. Here every instance
//! is tested in turn with no tree at all, and each ray keeps the smallest `t`. The tests
//! are the scalar ones written lane by lane with the same operations in the same order
//! (`shapes::flat`, `shapes::sphere`, the transform's `inv_ray`, the lead's `object_ray`),
//! so each lane computes the bits the scalar test computes; the winner's record is then
//! built by the scalar test itself. The scalar search keeps the first of equal
//! distances in the order it visits, which depends on the tree; a lane whose smallest
//! distance is shared by two instances does not know that order and takes the scalar
//! search. So each ray gets exactly what [`Aggregate::intersect`] gives it
//! (tests/bvh.rs checks it ray by ray).

use super::{Aggregate, Hit, Instance, Shape};
use crate::bvh::BATCH;
use crate::ray::Ray;
use crate::real::{Mat3, Real, Vec3};

/// The most instances an aggregate may hold to be searched in lanes: above it, the tree
/// skips more tests than the lanes save.
pub(super) const MAX_INSTANCES: usize = 8;

/// What lanes can test: the canonical shapes whose tests are written lane by lane.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Sphere,
    Cube,
    Rectangle,
    Disk,
    Plane,
}

/// An instance as the lanes test it: its shape and the map of a ray into its object
/// space, `inv·(o − c)` and `inv·d` (none: the ray as it is).
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    kind: Kind,
    map: Option<(Mat3, Vec3)>,
}

/// The lanes' form of an aggregate's instances, in `instances` order; `None` when the
/// aggregate is too large or holds a shape the lanes cannot test.
pub(super) fn items(instances: &[Instance], leads: &[(Real, Vec3)]) -> Option<Vec<Item>> {
    if instances.len() > MAX_INSTANCES || instances.is_empty() {
        return None;
    }
    instances
        .iter()
        .enumerate()
        .map(|(k, inst)| {
            let kind = match inst.shape {
                Shape::Sphere => Kind::Sphere,
                Shape::Cube => Kind::Cube,
                Shape::Rectangle => Kind::Rectangle,
                Shape::Disk => Kind::Disk,
                Shape::Plane => Kind::Plane,
                _ => return None,
            };
            // A sphere with a lead is searched through it (`Lead::object_ray`): the
            // diagonal matrix of its scale, about its centre.
            let map = match leads.get(k) {
                Some(&(s, c)) if s != 0.0 => Some((Mat3::from_diagonal(Vec3::splat(s)), c)),
                _ => inst.xf.map(|x| (x.inverse_matrix(), x.translation())),
            };
            Some(Item { kind, map })
        })
        .collect()
}

/// `BATCH` values, one a lane.
type L = [Real; BATCH];
/// The same in `f64` (the sphere's test computes its discriminant in `f64`).
type D = [f64; BATCH];

/// Rays as lanes: each component an array.
struct Rays {
    o: [L; 3],
    d: [L; 3],
}

impl Rays {
    /// `rays` (at most `BATCH`) as lanes; the lanes past the last ray repeat it.
    fn of(rays: &[Ray]) -> Rays {
        let mut r = Rays {
            o: [[0.0; BATCH]; 3],
            d: [[0.0; BATCH]; 3],
        };
        let last = rays[rays.len() - 1];
        for l in 0..BATCH {
            let ray = rays.get(l).unwrap_or(&last);
            for c in 0..3 {
                r.o[c][l] = ray.o[c];
                r.d[c][l] = ray.d[c];
            }
        }
        r
    }

    /// The rays in an item's object space, as `Transform::inv_ray` and `Lead::object_ray`
    /// compute them: `m·(o − c)` and `m·d` with glam's `Mat3 · Vec3` (the columns times
    /// the components, added from the first).
    #[inline(always)]
    fn mapped(&self, map: &Option<(Mat3, Vec3)>) -> Rays {
        let Some((m, c)) = map else {
            return Rays {
                o: self.o,
                d: self.d,
            };
        };
        let cols = [m.x_axis, m.y_axis, m.z_axis];
        let mut out = Rays {
            o: [[0.0; BATCH]; 3],
            d: [[0.0; BATCH]; 3],
        };
        for l in 0..BATCH {
            let p = [self.o[0][l] - c.x, self.o[1][l] - c.y, self.o[2][l] - c.z];
            let v = [self.d[0][l], self.d[1][l], self.d[2][l]];
            for r in 0..3 {
                out.o[r][l] = cols[0][r] * p[0] + cols[1][r] * p[1] + cols[2][r] * p[2];
                out.d[r][l] = cols[0][r] * v[0] + cols[1][r] * v[1] + cols[2][r] * v[2];
            }
        }
        out
    }
}

/// The distance of an item's candidate for each lane (`shapes::flat`, `shapes::sphere`'s
/// `solve`), or infinity where it has none in `(t_min, t_max)`.
#[inline(always)]
fn distances(kind: Kind, r: &Rays, t_min: Real, t_max: &L) -> L {
    let mut t = [Real::INFINITY; BATCH];
    match kind {
        Kind::Sphere => {
            // In f64 up to the discriminant, then in `Real`, as `solve`.
            let mut disc64: D = [0.0; BATCH];
            let mut a64: D = [0.0; BATCH];
            let mut b64: D = [0.0; BATCH];
            for l in 0..BATCH {
                let (ox, oy, oz) = (r.o[0][l] as f64, r.o[1][l] as f64, r.o[2][l] as f64);
                let (dx, dy, dz) = (r.d[0][l] as f64, r.d[1][l] as f64, r.d[2][l] as f64);
                let a = dx * dx + dy * dy + dz * dz;
                let b = ox * dx + oy * dy + oz * dz;
                let k = b / a;
                let (lx, ly, lz) = (ox - dx * k, oy - dy * k, oz - dz * k);
                disc64[l] = a * (1.0 - (lx * lx + ly * ly + lz * lz));
                a64[l] = a;
                b64[l] = b;
            }
            for l in 0..BATCH {
                let disc = disc64[l] as Real;
                let (a, b) = (a64[l] as Real, b64[l] as Real);
                let (ox, oy, oz) = (r.o[0][l], r.o[1][l], r.o[2][l]);
                let c = ox * ox + oy * oy + oz * oz - 1.0;
                // `stable_roots`.
                let s = disc.sqrt();
                let q = -(b + s.copysign(b));
                let (r0, r1) = (q / a, c / q);
                let (t0, t1) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
                let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (t0, t1) };
                // (`&` and `|` rather than `&&` and `||` here and below: the same
                // values, without the branches that would keep the loop scalar.)
                let in0 = (t0 > t_min) & (t0 < t_max[l]);
                let in1 = (t1 > t_min) & (t1 < t_max[l]);
                let first = if in0 { t0 } else { t1 };
                t[l] = if (disc >= 0.0) & (in0 | in1) {
                    first
                } else {
                    Real::INFINITY
                };
            }
        }
        Kind::Cube => {
            for l in 0..BATCH {
                // `shapes::cube`'s `crossing`: the slabs of the axes the ray is not
                // parallel to; one it is parallel to and outside of misses.
                let (mut near, mut far) = (Real::NEG_INFINITY, Real::INFINITY);
                let mut outside = false;
                for k in 0..3 {
                    let (o, d) = (r.o[k][l], r.d[k][l]);
                    let parallel = d == 0.0;
                    outside |= parallel & !((-1.0 <= o) & (o <= 1.0));
                    let inv = 1.0 / d;
                    let (a, b) = ((-1.0 - o) * inv, (1.0 - o) * inv);
                    let (a, b) = if a > b { (b, a) } else { (a, b) };
                    near = if !parallel & (a > near) { a } else { near };
                    far = if !parallel & (b < far) { b } else { far };
                }
                let in_near = (near > t_min) & (near < t_max[l]);
                let in_far = (far > t_min) & (far < t_max[l]);
                let first = if in_near { near } else { far };
                t[l] = if !outside & !(near > far) & (in_near | in_far) {
                    first
                } else {
                    Real::INFINITY
                };
            }
        }
        Kind::Rectangle | Kind::Disk | Kind::Plane => {
            for l in 0..BATCH {
                // `plane_t`, then `ray.at(t)` off the shape.
                let (oy, dy) = (r.o[1][l], r.d[1][l]);
                let tl = -oy / dy;
                let on = (dy != 0.0) & (tl > t_min) & (tl < t_max[l]);
                let x = r.o[0][l] + r.d[0][l] * tl;
                let z = r.o[2][l] + r.d[2][l] * tl;
                let off = match kind {
                    Kind::Rectangle => (x.abs() > 1.0) | (z.abs() > 1.0),
                    Kind::Disk => x * x + z * z > 1.0,
                    _ => false,
                };
                t[l] = if on & !off { tl } else { Real::INFINITY };
            }
        }
    }
    t
}

/// A lane's outcome: no instance, the instance `k` (in `instances` order), or a distance
/// shared by two instances (the scalar search decides).
const NONE: u32 = u32::MAX;
const TIE: u32 = u32::MAX - 1;

/// For each ray, the instance whose candidate is closest ([`NONE`], or [`TIE`]), and its
/// distance.
fn winners(items: &[Item], rays: &[Ray], t_min: Real, t_max: &[Real]) -> ([u32; BATCH], L) {
    let lanes = Rays::of(rays);
    let mut bound = [Real::INFINITY; BATCH];
    bound[..t_max.len()].copy_from_slice(t_max);
    let mut best_t = [Real::INFINITY; BATCH];
    let mut best = [NONE; BATCH];
    for (k, item) in items.iter().enumerate() {
        let t = distances(item.kind, &lanes.mapped(&item.map), t_min, &bound);
        for l in 0..BATCH {
            let closer = t[l] < best_t[l];
            let tie = (t[l] == best_t[l]) & (t[l] != Real::INFINITY);
            best[l] = if closer {
                k as u32
            } else if tie {
                TIE
            } else {
                best[l]
            };
            best_t[l] = if closer { t[l] } else { best_t[l] };
        }
    }
    (best, best_t)
}

impl Aggregate {
    /// [`Aggregate::intersect_batch`] in lanes (the module's docs), for an aggregate with
    /// `lanes` items: `out[r]` gets exactly what `intersect` gives `rays[r]`.
    pub(super) fn intersect_lanes<const UV: bool>(
        &self,
        items: &[Item],
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
        out: &mut [Option<Hit>],
    ) {
        let (best, best_t) = winners(items, rays, t_min, t_max);
        for (r, ray) in rays.iter().enumerate() {
            let k = best[r] as usize;
            out[r] = match best[r] {
                NONE => None,
                // The winner's record, from its scalar test (the same distance, unless
                // the lanes and the scalar test disagree, which the tests rule out; the
                // scalar search then decides, as for a tie).
                TIE => self.intersect_with::<UV>(ray, t_min, t_max[r]),
                _ => match self.candidate(k, ray, t_min, t_max[r]) {
                    Some(mut h) if h.t == best_t[r] => {
                        self.finish::<UV>(k, &mut h);
                        Some(h)
                    }
                    other => {
                        debug_assert!(
                            false,
                            "lanes.rs: instance {k}'s lane distance {} is not its scalar \
                             test's {:?} for {ray:?}",
                            best_t[r],
                            other.map(|h| h.t)
                        );
                        self.intersect_with::<UV>(ray, t_min, t_max[r])
                    }
                },
            };
        }
    }
}
