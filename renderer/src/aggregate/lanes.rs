//! The closest-hit search of a small aggregate for [`BATCH`] rays at once, in lanes: each
//! instance is tested against every ray with element-wise operations over arrays of the
//! rays' components, which the compiler turns into vector instructions (8 `f32` a
//! register with AVX2, the build's target; where the processor has AVX-512, a copy of
//! the search compiled for it takes the whole `BATCH` of 16 in one, chosen at run time).
//!
//! A scene of a few canonical primitives (a floor, a light, a sphere, a box: most of the
//! physical catalog) pays more for the tree walk than for the tests themselves. Here every
//! instance is tested in turn with no tree at all, and each ray keeps the smallest `t`;
//! a sphere, cube or cylinder whose box (widened by a margin for rounding, `Reach`) no ray
//! of the batch meets is passed over, which cannot change a result. The
//! module reads nothing of the aggregate (whose module uses it): the aggregate hands it
//! each instance's shape and maps as an [`Item`], and answers the tied rays itself. The
//! tests are the scalar ones written lane by lane with the same operations in the same
//! order (`shapes::flat`, `shapes::sphere`, the transform's `inv_ray`, the lead's
//! `object_ray`; the cube's and the cylinder's are the scalar tests themselves,
//! `shapes::cube`'s and `shapes::cylinder`'s `Crossing`, written without branches and called
//! lane by lane), so each lane computes the
//! bits the scalar test computes; so is the winner's record, built and mapped out of object
//! space in lanes as the shape and the instance build and map it (`map_point_with_error`,
//! `map_normal`), for each instance that some lane's ray hits first (the cylinder's
//! azimuth, an `atan2`, lane by lane for the lanes it wins). The scalar search keeps the
//! first of equal distances in the order it visits, which depends on the tree; a lane whose
//! smallest distance is shared by two instances does not know that order and takes the
//! scalar search. So each ray gets what testing every instance in turn gives it
//! (`Aggregate::intersect_brute_force`, the reference the tree is tested against), which is
//! `Aggregate::intersect`'s hit on every ray of the tests (tests/bvh.rs, ray by ray) and of
//! every catalog scene (`scripts/same-bits.sh`). The two can differ where the tree's box
//! test, which the lanes do not make, rejects a ray that an instance's own test accepts: a
//! ray nearly parallel to a rectangle's plane through its edge, within half a unit in the
//! last place (`lanes_are_the_brute_force_search_at_a_box_edge`). There the lanes give the
//! brute-force answer.

use crate::aabb::Aabb;
use crate::bvh::BATCH;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Mat3, Real, Vec2, Vec3};
use crate::shapes;
use crate::shapes::{cube, cylinder};

/// The most instances an aggregate may hold to be searched in lanes: above it, the tree
/// skips more tests than the lanes save. (The lanes skip a sphere, cube or cylinder whose
/// box no ray of the batch meets, [`Reach`]: without that skip, 8 was the most that paid;
/// with it, 16 take 3.8 % fewer instructions on a room of 10 instances, 1.5 % fewer on a
/// floor, a light and 14 small spheres, renderer/docs/performance.md.)
pub(super) const MAX_INSTANCES: usize = 16;

/// What lanes can test: the canonical shapes whose tests are written lane by lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    Sphere,
    Cube,
    Cylinder { capped: bool },
    Rectangle,
    Disk,
    Plane,
}

/// An instance as the lanes test it and finish its hits.
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    kind: Kind,
    /// `(m⁻¹, m, c)`: the ray goes into object space by `m⁻¹·(o − c)` and `m⁻¹·d`, the
    /// hit point comes out by `m·p + c` with its error bound, the normal by `m⁻ᵀ` (none:
    /// object space is this space).
    xf: Option<(Mat3, Mat3, Vec3)>,
    material: u32,
    object_id: u32,
    /// [`Hit::surface`] of its hits.
    surface: u64,
    /// Where its hits can lie ([`Reach`]; none: unbounded, tested for every batch).
    reach: Option<Reach>,
}

/// A box that holds every hit an instance's own test can report, for the skip in
/// [`search`]: the instance's world bounds (`lo`, `hi`) widened by `per_origin` times
/// their own size, and, for each batch, by `per_origin` times the largest coordinate of
/// its rays' origins. Every error between the ray an instance's test sees and the world
/// ray (the ray taken into object space, the shape's rounded hit point, the bounds' own
/// rounding) is a few units in the last place of those magnitudes, times the condition
/// number κ = ‖m‖·‖m⁻¹‖ of its map; `per_origin` is [`REACH_ULPS`] units in the last
/// place times κ, and the box test that uses it rounds by less still. So a batch none of
/// whose rays meets the box has no hit on the instance.
#[derive(Clone, Copy, Debug)]
struct Reach {
    lo: Vec3,
    hi: Vec3,
    per_origin: Real,
}

/// How many units in the last place, times κ, the reach of an instance's box widens it
/// by ([`Reach`]): a margin of about 25 over the errors it covers.
const REACH_ULPS: Real = 256.0;

impl Reach {
    /// The reach of an instance of world bounds `b` placed by `xf` (`(m⁻¹, m, c)`),
    /// none when `b` is not finite.
    fn of(b: &Aabb, xf: &Option<(Mat3, Mat3, Vec3)>) -> Option<Reach> {
        if !b.is_finite() || b.is_empty() {
            return None;
        }
        // The maximum absolute row sum (‖·‖∞) of each map.
        let norm = |m: &Mat3| {
            let t = m.transpose();
            [t.x_axis, t.y_axis, t.z_axis]
                .map(|r| r.abs().element_sum())
                .into_iter()
                .fold(0.0, Real::max)
        };
        let kappa = xf.map_or(1.0, |(inv, m, _)| (norm(&m) * norm(&inv)).max(1.0));
        let per_origin = REACH_ULPS * Real::EPSILON * kappa;
        let size = (b.max - b.min).max_element() + b.min.abs().max(b.max.abs()).max_element();
        let pad = Vec3::splat(size * per_origin);
        let (lo, hi) = (b.min - pad, b.max + pad);
        (lo.is_finite() && hi.is_finite() && per_origin.is_finite()).then_some(Reach {
            lo,
            hi,
            per_origin,
        })
    }

    /// Whether some lane's ray may meet the box (widened by `per_origin` times `omag`,
    /// the batch's largest origin coordinate) at a distance in `[min(t_min, 0), bound]`:
    /// the slab test, in which a NaN never rules a ray out (an axis whose distances hold
    /// a NaN, as a direction of a subnormal component from a point on a face gives, is
    /// left out of the interval) and a ray parallel to a slab meets it everywhere or
    /// nowhere.
    #[inline(always)]
    fn met(&self, r: &Rays, omag: Real, t_min: Real, bound: &L) -> bool {
        let widen = Vec3::splat(omag * self.per_origin);
        let (lo, hi) = (self.lo - widen, self.hi + widen);
        let start = t_min.min(0.0);
        let mut any = false;
        for l in 0..BATCH {
            let (mut near, mut far) = (Real::NEG_INFINITY, Real::INFINITY);
            for c in 0..3 {
                let (o, d) = (r.o[c][l], r.d[c][l]);
                let inv = 1.0 / d;
                let (t0, t1) = ((lo[c] - o) * inv, (hi[c] - o) * inv);
                let (a, b) = if t0 > t1 { (t1, t0) } else { (t0, t1) };
                let inside = (lo[c] <= o) & (o <= hi[c]);
                // Everything or nothing for a ray parallel to the slab. And everything when
                // the exit is a NaN (0·∞: from a point on the widened face, with a
                // reciprocal that overflowed), for then the pair is not swapped and the
                // entry is the other distance, an infinity that says nothing. (A NaN entry
                // is passed over by the comparisons below.)
                let all = (d == 0.0) & inside | t1.is_nan();
                let none = (d == 0.0) & !inside;
                let (a, b) = if all {
                    (Real::NEG_INFINITY, Real::INFINITY)
                } else if none {
                    (Real::INFINITY, Real::NEG_INFINITY)
                } else {
                    (a, b)
                };
                near = if a > near { a } else { near };
                far = if b < far { b } else { far };
            }
            any |= !((near > far) | (far < start) | (near > bound[l]));
        }
        any
    }
}

impl Item {
    /// An instance of shape `kind`, placed by `xf` (`(m⁻¹, m, c)`), of world bounds
    /// `bounds`, with the material, object id and surface number its hits carry.
    pub(super) fn new(
        kind: Kind,
        xf: Option<(Mat3, Mat3, Vec3)>,
        bounds: &Aabb,
        material: u32,
        object_id: u32,
        surface: u64,
    ) -> Item {
        Item {
            kind,
            xf,
            material,
            object_id,
            surface,
            // A flat shape's own test (one division, two products) costs what the box
            // test would: it has none.
            reach: match kind {
                Kind::Rectangle | Kind::Disk | Kind::Plane => None,
                _ => Reach::of(bounds, &xf),
            },
        }
    }
}

/// `BATCH` values, one a lane.
type L = [Real; BATCH];

/// Rays as lanes: each component an array.
struct Rays {
    o: [L; 3],
    d: [L; 3],
}

impl Rays {
    const ZERO: Rays = Rays {
        o: [[0.0; BATCH]; 3],
        d: [[0.0; BATCH]; 3],
    };

    /// Lane `l`'s origin and direction.
    #[inline(always)]
    fn lane(&self, l: usize) -> (Vec3, Vec3) {
        let (o, d) = (&self.o, &self.d);
        (
            Vec3::new(o[0][l], o[1][l], o[2][l]),
            Vec3::new(d[0][l], d[1][l], d[2][l]),
        )
    }

    /// The largest magnitude of the origins' coordinates, for the items' reach (by
    /// selects, which vectorize; a NaN is passed over).
    #[inline(always)]
    fn largest_origin(&self) -> Real {
        let mut lane_max = [0.0; BATCH];
        for c in 0..3 {
            for (m, o) in lane_max.iter_mut().zip(&self.o[c]) {
                *m = if o.abs() > *m { o.abs() } else { *m };
            }
        }
        lane_max
            .iter()
            .fold(0.0, |m: Real, &x| if x > m { x } else { m })
    }

    /// `rays` (at most `BATCH`) as lanes; the lanes past the last ray repeat it.
    fn of(rays: &[Ray]) -> Rays {
        let mut r = Rays::ZERO;
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
    fn mapped(&self, xf: &Option<(Mat3, Mat3, Vec3)>) -> Rays {
        let Some((m, _, c)) = xf else {
            return Rays {
                o: self.o,
                d: self.d,
            };
        };
        let cols = [m.x_axis, m.y_axis, m.z_axis];
        let mut out = Rays::ZERO;
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

/// The lanes' rays against the unit sphere as `shapes::sphere`'s `solve` computes them in
/// `f64`, lane by lane: the squared length of the direction `a`, `b = o·d`, the line's
/// point `l` nearest the centre, the direction `d`, and the discriminant.
struct SphereLines {
    a: [f64; BATCH],
    b: [f64; BATCH],
    l: [[f64; BATCH]; 3],
    d: [[f64; BATCH]; 3],
    disc: [f64; BATCH],
}

impl SphereLines {
    #[inline(always)]
    fn of(r: &Rays) -> SphereLines {
        let mut s = SphereLines {
            a: [0.0; BATCH],
            b: [0.0; BATCH],
            l: [[0.0; BATCH]; 3],
            d: [[0.0; BATCH]; 3],
            disc: [0.0; BATCH],
        };
        for l in 0..BATCH {
            let (ox, oy, oz) = (r.o[0][l] as f64, r.o[1][l] as f64, r.o[2][l] as f64);
            let (dx, dy, dz) = (r.d[0][l] as f64, r.d[1][l] as f64, r.d[2][l] as f64);
            let a = dx * dx + dy * dy + dz * dz;
            let b = ox * dx + oy * dy + oz * dz;
            let k = b / a;
            let (lx, ly, lz) = (ox - dx * k, oy - dy * k, oz - dz * k);
            s.disc[l] = a * (1.0 - (lx * lx + ly * ly + lz * lz));
            (s.a[l], s.b[l]) = (a, b);
            (s.l[0][l], s.l[1][l], s.l[2][l]) = (lx, ly, lz);
            (s.d[0][l], s.d[1][l], s.d[2][l]) = (dx, dy, dz);
        }
        s
    }

    /// Lane `l`'s two roots in `Real`, ascending, as `stable_roots` finds them.
    #[inline(always)]
    fn roots(&self, r: &Rays, l: usize) -> (Real, Real) {
        let disc = self.disc[l] as Real;
        let (a, b) = (self.a[l] as Real, self.b[l] as Real);
        let (ox, oy, oz) = (r.o[0][l], r.o[1][l], r.o[2][l]);
        let c = ox * ox + oy * oy + oz * oz - 1.0;
        shapes::stable_roots(a, b, c, disc)
    }
}

/// The distance of an item's candidate for each lane (`shapes::flat`, `shapes::sphere`'s
/// `solve`, `shapes::cube`'s and `shapes::cylinder`'s `Crossing`), or infinity
/// where it has none in `(t_min, t_max)`.
#[inline(always)]
fn distances(kind: Kind, r: &Rays, t_min: Real, t_max: &L) -> L {
    let mut t = [Real::INFINITY; BATCH];
    match kind {
        Kind::Sphere => {
            // In f64 up to the discriminant, then in `Real`, as `solve`.
            let line = SphereLines::of(r);
            for l in 0..BATCH {
                let disc = line.disc[l] as Real;
                let (t0, t1) = line.roots(r, l);
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
                let (o, d) = r.lane(l);
                t[l] = cube::Crossing::of(o, d).pick(t_min, t_max[l]).0;
            }
        }
        Kind::Cylinder { capped } => {
            for l in 0..BATCH {
                let (o, d) = r.lane(l);
                t[l] = cylinder::Crossing::of(o, d).pick(capped, t_min, t_max[l]).0;
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

/// For each lane, the instance whose candidate is closest ([`NONE`], or [`TIE`]), and its
/// distance.
#[inline(always)]
fn winners(items: &[Item], lanes: &Rays, t_min: Real, bound: &L) -> ([u32; BATCH], L) {
    let mut best_t = [Real::INFINITY; BATCH];
    let mut best = [NONE; BATCH];
    let omag = lanes.largest_origin();
    for (k, item) in items.iter().enumerate() {
        // An item whose box no ray meets has no hit to offer (`Reach`).
        if item
            .reach
            .is_some_and(|r| !r.met(lanes, omag, t_min, bound))
        {
            continue;
        }
        let t = distances(item.kind, &lanes.mapped(&item.xf), t_min, bound);
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

/// The hit records of the lanes, field by field, in object space or mapped out of it.
struct Records {
    p: [L; 3],
    err: [L; 3],
    n: [L; 3],
    uv: [L; 2],
    /// The lanes on a cylinder's side, whose u is the azimuth of their point in object
    /// space: an `atan2` that [`search`] takes for the lanes the cylinder wins.
    side: [bool; BATCH],
}

impl Records {
    const ZERO: Records = Records {
        p: [[0.0; BATCH]; 3],
        err: [[0.0; BATCH]; 3],
        n: [[0.0; BATCH]; 3],
        uv: [[0.0; BATCH]; 2],
        side: [false; BATCH],
    };

    /// Lane `l`'s point, error bound, normal and uv, as a shape's `Crossing::record`
    /// gives them.
    #[inline(always)]
    fn put(&mut self, l: usize, (p, err, n, uv): (Vec3, Vec3, Vec3, Vec2)) {
        for (field, v) in [(&mut self.p, p), (&mut self.err, err), (&mut self.n, n)] {
            (field[0][l], field[1][l], field[2][l]) = (v.x, v.y, v.z);
        }
        (self.uv[0][l], self.uv[1][l]) = (uv.x, uv.y);
    }
}

/// Each lane's candidate record of a `kind` at the distance `t` it found (`r` in object
/// space): the point, its error bound, the normal and the uv that `shapes::flat`,
/// `shapes::sphere::intersect_bare`, `shapes::cube` and `shapes::cylinder` build,
/// operation for operation (the cylinder's side leaves u to the caller).
/// (A lane the shape missed gets values nobody reads.)
#[inline(always)]
fn records(kind: Kind, r: &Rays, t_min: Real, t_max: &L, t: &L) -> Records {
    let mut rec = Records::ZERO;
    match kind {
        Kind::Sphere => {
            let g5 = gamma(5);
            let line = SphereLines::of(r);
            for l in 0..BATCH {
                // `solve` again, to learn which root the lane took, then `intersect_bare`.
                let (t0, _) = line.roots(r, l);
                let [lx, ly, lz] = [0, 1, 2].map(|c| line.l[c][l]);
                let [dx, dy, dz] = [0, 1, 2].map(|c| line.d[c][l]);
                let (a64, disc64) = (line.a[l], line.disc[l]);
                let first = (t0 > t_min) & (t0 < t_max[l]);
                let side: f64 = if first { -1.0 } else { 1.0 };
                let f = side * disc64.sqrt() / a64;
                let p = [
                    (lx + dx * f) as Real,
                    (ly + dy * f) as Real,
                    (lz + dz * f) as Real,
                ];
                // `normalize_or(p)`.
                let rcp = 1.0 / (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                let unit = (rcp.abs() < Real::INFINITY) & (rcp > 0.0);
                for c in 0..3 {
                    let v = if unit { p[c] * rcp } else { p[c] };
                    rec.p[c][l] = v;
                    rec.n[c][l] = v;
                    rec.err[c][l] = v.abs() * g5;
                }
            }
        }
        Kind::Cube => {
            for l in 0..BATCH {
                // `pick` again, for whether the ray enters, then the record.
                let (o, d) = r.lane(l);
                let c = cube::Crossing::of(o, d);
                let (_, entering) = c.pick(t_min, t_max[l]);
                rec.put(l, c.record(o, d, entering, t[l]));
            }
        }
        Kind::Cylinder { capped } => {
            for l in 0..BATCH {
                // `pick` again, for the candidate, then its record.
                let (o, d) = r.lane(l);
                let c = cylinder::Crossing::of(o, d);
                let (_, part) = c.pick(capped, t_min, t_max[l]);
                rec.put(l, c.record(o, d, part, t[l]));
                rec.side[l] = cylinder::on_side(part);
            }
        }
        Kind::Rectangle | Kind::Disk | Kind::Plane => {
            let g4 = gamma(4);
            for l in 0..BATCH {
                // `ray.at(t)` put on the plane (`on_plane`).
                let x = r.o[0][l] + r.d[0][l] * t[l];
                let z = r.o[2][l] + r.d[2][l] * t[l];
                rec.p[0][l] = x;
                rec.p[2][l] = z;
                rec.err[0][l] = x.abs() * g4;
                rec.err[1][l] = 0.0 * g4;
                rec.err[2][l] = z.abs() * g4;
                rec.n[1][l] = 1.0;
                let (u, v) = match kind {
                    Kind::Plane => (x, z),
                    _ => ((x + 1.0) * 0.5, (z + 1.0) * 0.5),
                };
                rec.uv[0][l] = u;
                rec.uv[1][l] = v;
            }
        }
    }
    rec
}

/// `rec` mapped out of object space by `(m⁻¹, m, c)`: the point and its error bound by
/// `map_point_with_error` (`γ(3)·(|m|·|p| + |c|) + (1 + γ(3))·|m|·err`), the normal by
/// `map_normal` (`m⁻ᵀ·n`), each sum in glam's order.
#[inline(always)]
fn mapped_out(rec: &mut Records, (inv, m, c): &(Mat3, Mat3, Vec3)) {
    let g = gamma(3);
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    let am = cols.map(|v| v.abs());
    let rows = [inv.x_axis, inv.y_axis, inv.z_axis];
    for l in 0..BATCH {
        let p = [rec.p[0][l], rec.p[1][l], rec.p[2][l]];
        let e = [rec.err[0][l], rec.err[1][l], rec.err[2][l]];
        let n = [rec.n[0][l], rec.n[1][l], rec.n[2][l]];
        for r in 0..3 {
            let bound = am[0][r] * p[0].abs() + am[1][r] * p[1].abs() + am[2][r] * p[2].abs();
            let carried = am[0][r] * e[0] + am[1][r] * e[1] + am[2][r] * e[2];
            rec.err[r][l] = (bound + c[r].abs()) * g + carried * (1.0 + g);
            rec.p[r][l] = cols[0][r] * p[0] + cols[1][r] * p[1] + cols[2][r] * p[2] + c[r];
            // Row r of m⁻ᵀ is column r of m⁻¹.
            rec.n[r][l] = rows[r].x * n[0] + rows[r].y * n[1] + rows[r].z * n[2];
        }
    }
}

/// The closest hits of `rays` (at most [`BATCH`]) among `items`, each with its own
/// `t_max`, into `out` (`out[r]` for `rays[r]`), as `Aggregate::intersect` finds them
/// (with the sphere's uv when `UV`); returns the mask of the rays whose closest distance
/// two instances share, which the caller's scalar search answers (`out` is left alone
/// there).
pub(super) fn intersect<const UV: bool>(
    items: &[Item],
    rays: &[Ray],
    t_min: Real,
    t_max: &[Real],
    out: &mut [Option<Hit>],
) -> u64 {
    #[cfg(target_arch = "x86_64")]
    if wide() {
        // SAFETY: the processor has the features `intersect_wide` is compiled for.
        return unsafe { intersect_wide::<UV>(items, rays, t_min, t_max, out) };
    }
    search::<UV>(items, rays, t_min, t_max, out)
}

/// Whether the processor has AVX-512 (F, VL, DQ, BW), for which [`intersect_wide`] is
/// compiled.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn wide() -> bool {
    std::is_x86_feature_detected!("avx512f")
        && std::is_x86_feature_detected!("avx512vl")
        && std::is_x86_feature_detected!("avx512dq")
        && std::is_x86_feature_detected!("avx512bw")
}

/// [`search`] compiled for AVX-512: 16 `f32` (8 `f64`) a register, so a `BATCH` of
/// `f32` values is one register. The same operations on the same values, so the same bits
/// (IEEE 754 arithmetic, square roots and conversions are exact in both encodings; Rust
/// fuses no multiply and add); `wide_search_gives_the_bits_of_the_search` compares the
/// two. (Its signature repeats [`intersect`]'s: a `#[target_feature]` function is its own
/// item.)
///
/// # Safety
/// The processor must have AVX-512 F, VL, DQ and BW ([`wide`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
unsafe fn intersect_wide<const UV: bool>(
    items: &[Item],
    rays: &[Ray],
    t_min: Real,
    t_max: &[Real],
    out: &mut [Option<Hit>],
) -> u64 {
    search::<UV>(items, rays, t_min, t_max, out)
}

/// [`intersect`] in the encoding the caller was compiled for.
#[inline(always)]
fn search<const UV: bool>(
    items: &[Item],
    rays: &[Ray],
    t_min: Real,
    t_max: &[Real],
    out: &mut [Option<Hit>],
) -> u64 {
    let lanes = Rays::of(rays);
    // The lanes past the last ray repeat it, its bound included (so that they do not
    // keep an instance it cannot reach from being passed over).
    let mut bound = [t_max[t_max.len() - 1]; BATCH];
    bound[..t_max.len()].copy_from_slice(t_max);
    let (best, best_t) = winners(items, &lanes, t_min, &bound);
    // Each winning instance's records, for the lanes it won.
    let mut won = Records::ZERO;
    for (k, item) in items.iter().enumerate() {
        if !best[..rays.len()].contains(&(k as u32)) {
            continue;
        }
        let object = lanes.mapped(&item.xf);
        let mut rec = records(item.kind, &object, t_min, &bound, &best_t);
        // What the scalar search takes only for its winner, lane by lane for the lanes
        // this item won, in object space: the sphere's uv (`Shape::complete`, when `UV`)
        // and the cylinder side's u, the azimuth of its point.
        if matches!(
            (UV, item.kind),
            (true, Kind::Sphere) | (_, Kind::Cylinder { .. })
        ) {
            for (l, _) in best[..rays.len()]
                .iter()
                .enumerate()
                .filter(|&(_, &b)| b == k as u32)
            {
                let p = Vec3::new(rec.p[0][l], rec.p[1][l], rec.p[2][l]);
                match item.kind {
                    Kind::Sphere => (rec.uv[0][l], rec.uv[1][l]) = shapes::sphere::uv(p).into(),
                    _ if rec.side[l] => rec.uv[0][l] = shapes::azimuth(p.x, p.z),
                    _ => {}
                }
            }
        }
        if let Some(xf) = &item.xf {
            mapped_out(&mut rec, xf);
        }
        for l in 0..BATCH {
            let mine = best[l] == k as u32;
            for c in 0..3 {
                won.p[c][l] = if mine { rec.p[c][l] } else { won.p[c][l] };
                won.err[c][l] = if mine { rec.err[c][l] } else { won.err[c][l] };
                won.n[c][l] = if mine { rec.n[c][l] } else { won.n[c][l] };
            }
            for c in 0..2 {
                won.uv[c][l] = if mine { rec.uv[c][l] } else { won.uv[c][l] };
            }
        }
    }
    let mut ties = 0u64;
    for (l, o) in out[..rays.len()].iter_mut().enumerate() {
        *o = match best[l] {
            NONE => None,
            TIE => {
                ties |= 1 << l;
                continue;
            }
            k => {
                let item = &items[k as usize];
                let n = Vec3::new(won.n[0][l], won.n[1][l], won.n[2][l]);
                Some(Hit {
                    t: best_t[l],
                    p: Vec3::new(won.p[0][l], won.p[1][l], won.p[2][l]),
                    err: Vec3::new(won.err[0][l], won.err[1][l], won.err[2][l]),
                    n_geo: n,
                    n_shade: n,
                    uv: Vec2::new(won.uv[0][l], won.uv[1][l]),
                    material: item.material,
                    object_id: item.object_id,
                    surface: item.surface,
                    prim: 0,
                })
            }
        };
    }
    ties
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::sampler::{mix64, to_unit};

    /// Every field of a hit, floats by their bits.
    fn hit_bits(h: &Hit) -> Vec<u64> {
        let v = |v: Vec3| v.to_array().map(|x| x.to_bits() as u64);
        let mut b = vec![h.t.to_bits() as u64];
        for x in [h.p, h.err, h.n_geo, h.n_shade] {
            b.extend(v(x));
        }
        b.extend(h.uv.to_array().map(|x| x.to_bits() as u64));
        b.extend([h.material, h.object_id, h.prim].map(u64::from));
        b.push(h.surface);
        b
    }

    /// The plain search's and the AVX-512 search's answers (tied lanes, hits) for `rays`.
    /// The processor must have AVX-512 ([`wide`]).
    #[allow(clippy::type_complexity)]
    fn both_searches<const UV: bool>(
        items: &[Item],
        rays: &[Ray],
        t_min: Real,
        t_max: &[Real],
    ) -> ((u64, Vec<Option<Hit>>), (u64, Vec<Option<Hit>>)) {
        let (mut plain, mut wide_out) = (vec![None; rays.len()], vec![None; rays.len()]);
        let ties = search::<UV>(items, rays, t_min, t_max, &mut plain);
        // SAFETY: the caller checked `wide()`: the processor has the features.
        let wide_ties = unsafe { intersect_wide::<UV>(items, rays, t_min, t_max, &mut wide_out) };
        ((ties, plain), (wide_ties, wide_out))
    }

    /// The search compiled for AVX-512 gives the bits of the search compiled for the
    /// build's target, hit by hit and field by field (with uv and without), on random
    /// items of every kind under random maps (any matrices: both read the same values)
    /// and random rays, ties included (copies of an item). Skipped on a processor without
    /// AVX-512, where only the plain search runs.
    #[test]
    fn wide_search_gives_the_bits_of_the_search() {
        if !wide() {
            eprintln!("no AVX-512 here: only the plain search runs");
            return;
        }
        let mut state = 7u64;
        let mut next = move |lo: f64, hi: f64| {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            (lo + (hi - lo) * to_unit(mix64(state))) as Real
        };
        let kinds = [
            Kind::Sphere,
            Kind::Cube,
            Kind::Cylinder { capped: true },
            Kind::Cylinder { capped: false },
            Kind::Rectangle,
            Kind::Disk,
            Kind::Plane,
        ];
        let mut compared = 0;
        for scene in 0..200 {
            // At most `MAX_INSTANCES` items, the copy included.
            let n = 1 + (scene % (MAX_INSTANCES - 1));
            let mut items: Vec<Item> = (0..n)
                .map(|k| {
                    let kind = kinds[(next(0.0, 7.0) as usize).min(6)];
                    let xf = (k % 4 != 0).then(|| {
                        let m = [0.0; 9].map(|_| next(-2.0, 2.0));
                        let inv = [0.0; 9].map(|_| next(-2.0, 2.0));
                        let c = Vec3::new(next(-3.0, 3.0), next(-3.0, 3.0), next(-3.0, 3.0));
                        (Mat3::from_cols_array(&inv), Mat3::from_cols_array(&m), c)
                    });
                    // A box about the item's place, which the skip of both searches
                    // reads alike (these maps are any matrices, not the box's).
                    let c = xf.map_or(Vec3::ZERO, |x| x.2);
                    let r = next(0.5, 4.0);
                    let b = Aabb::from_points(c - Vec3::splat(r), c + Vec3::splat(r));
                    Item::new(kind, xf, &b, k as u32, k as u32 + 1, k as u64)
                })
                .collect();
            if scene % 5 == 0 {
                items.push(items[0]);
            }
            let rays: Vec<Ray> = (0..1 + scene % BATCH)
                .map(|_| {
                    let o = Vec3::new(next(-4.0, 4.0), next(-4.0, 4.0), next(-4.0, 4.0));
                    let d = Vec3::new(next(-1.0, 1.0), next(-1.0, 1.0), next(-1.0, 1.0));
                    Ray::new(o, d)
                })
                .collect();
            let t_max: Vec<Real> = rays.iter().map(|_| next(0.5, 20.0)).collect();
            let t_min = if scene % 2 == 0 { 0.0 } else { 1e-3 };
            let both = [
                both_searches::<false>(&items, &rays, t_min, &t_max),
                both_searches::<true>(&items, &rays, t_min, &t_max),
            ];
            for (uv, ((ties, plain), (wide_ties, wide_out))) in [false, true].into_iter().zip(both)
            {
                assert_eq!(ties, wide_ties, "scene {scene}: the tied lanes differ");
                for (l, (a, b)) in plain.iter().zip(&wide_out).enumerate() {
                    assert_eq!(
                        a.as_ref().map(hit_bits),
                        b.as_ref().map(hit_bits),
                        "scene {scene}, ray {l} ({:?}), uv {uv}: the AVX-512 search \
                         (aggregate/lanes.rs intersect_wide) differs from the plain one",
                        rays[l]
                    );
                    compared += a.is_some() as usize;
                }
            }
        }
        assert!(compared > 300, "only {compared} hits compared");
    }

    /// A random rotation (a unit quaternion from four uniform numbers, Shoemake's method).
    fn rotation(u: [f64; 3]) -> glam::DMat3 {
        use std::f64::consts::TAU;
        let (a, b) = ((1.0 - u[0]).sqrt(), u[0].sqrt());
        let q = glam::DQuat::from_xyzw(
            a * (TAU * u[1]).sin(),
            a * (TAU * u[1]).cos(),
            b * (TAU * u[2]).sin(),
            b * (TAU * u[2]).cos(),
        );
        glam::DMat3::from_quat(q.normalize())
    }

    /// The skip of [`search`] never passes over an item that some ray of the batch hits:
    /// spheres, cubes and cylinders under rotations and scales of condition number up to
    /// 10⁴, up to 10³ from the origin, and batches of rays (of one ray, repeated in every
    /// lane, or sixteen) from near and far (up to 5·10⁴ times the item's size) aimed at
    /// the placed shape, or with every ray just past the item's box (its corners, edges
    /// and faces, by 1 to 10⁵ units in the last place, where a ray grazes it), with and
    /// without an interval's end. And it does pass over more than half of the batches
    /// aimed elsewhere (some of whose origins lie about the item). (The widening is a
    /// margin this test does not measure: without it, no exact test here hits a ray that
    /// the box test rules out. It stands for the error bounds in [`Reach`], which no test
    /// can make tight. `reach_keeps_nan_parallel_and_backward_rays` has the edge cases.)
    #[test]
    fn reach_rules_out_only_batches_that_miss() {
        use crate::transform::{Affine64, Transform};
        let mut state = 11u64;
        let mut u = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            to_unit(mix64(state))
        };
        let kinds = [
            Kind::Sphere,
            Kind::Cube,
            Kind::Cylinder { capped: true },
            Kind::Cylinder { capped: false },
        ];
        let (mut hits, mut skipped, mut away_skipped, mut away) = (0, 0, 0, 0);
        for case in 0..3000 {
            let kind = kinds[(case / 4) % 4];
            let scale = glam::DVec3::new(
                10f64.powf(4.0 * u() - 2.0),
                10f64.powf(4.0 * u() - 2.0),
                10f64.powf(4.0 * u() - 2.0),
            );
            let m = rotation([u(), u(), u()])
                * glam::DMat3::from_diagonal(scale)
                * rotation([u(), u(), u()]);
            let d = (glam::DVec3::new(u(), u(), u()) * 2.0 - 1.0) * 10f64.powf(3.0 * u());
            let Ok(x) = Transform::new(&Affine64 { m, d }) else {
                continue;
            };
            let xf = Some((x.inverse_matrix(), x.matrix(), x.translation()));
            let unit = Aabb::from_points(Vec3::splat(-1.0), Vec3::ONE);
            let b = x.bounds(&unit);
            let item = Item::new(kind, xf, &b, 0, 1, 0);
            let reach = item.reach.expect("a bounded item has a reach");
            let size = (b.max - b.min).max_element() as f64;
            let centre = crate::real::dvec3(b.centroid());
            // Half the batches aim at the item: at points of the placed unit sphere (on
            // the sphere, in the cube, about the cylinder), or every ray just past its
            // box (points of its surface, its corners, edges and faces, pushed out by a
            // few units in the last place or more, where a ray grazes it); half at points
            // well away from it.
            let aimed = case % 2 == 0;
            let dist = size * 10f64.powf(5.0 * u() - 0.3);
            let from = centre
                + (glam::DVec3::new(u(), u(), u()) * 2.0 - 1.0).normalize_or(glam::DVec3::X) * dist;
            // A batch of one ray (repeated in every lane) in a third of the cases: the
            // batch misses the box as often as the ray does.
            let n = if case % 3 == 1 { 1 } else { BATCH };
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    let o = if u() < 0.8 {
                        from
                    } else {
                        centre + (glam::DVec3::new(u(), u(), u()) * 2.0 - 1.0) * dist
                    };
                    let on_shape = case % 4 < 2;
                    let target = if aimed && on_shape {
                        // A point of the unit sphere in object space (on the sphere, in
                        // the cube and about the cylinder), placed.
                        let p = (glam::DVec3::new(u(), u(), u()) * 2.0 - 1.0)
                            .normalize_or(glam::DVec3::X);
                        m * p + d
                    } else if aimed {
                        // A point of the box's surface: each coordinate at an end or
                        // anywhere between, then moved by up to 4 ulps of its size.
                        let lo = crate::real::dvec3(b.min);
                        let hi = crate::real::dvec3(b.max);
                        let pick = |lo: f64, hi: f64, w: f64, f: f64| match (w * 3.0) as u32 {
                            0 => lo,
                            1 => hi,
                            _ => lo + (hi - lo) * f,
                        };
                        let w = [u(), u(), u(), u(), u(), u()];
                        let p = glam::DVec3::new(
                            pick(lo.x, hi.x, w[0], w[1]),
                            pick(lo.y, hi.y, w[2], w[3]),
                            pick(lo.z, hi.z, w[4], w[5]),
                        );
                        // Pushed out of the box by 1 to 10⁵ units in the last place.
                        let out = (p - centre).normalize_or(glam::DVec3::X);
                        p + out
                            * (Real::EPSILON as f64
                                * 10f64.powf(5.0 * u())
                                * (size + p.abs().max_element()))
                    } else {
                        centre
                            + (glam::DVec3::new(u(), u(), u()) * 2.0 - 1.0)
                                .normalize_or(glam::DVec3::Y)
                                * size
                                * 50.0
                    };
                    Ray::new(crate::real::vec3(o), crate::real::vec3(target - o))
                })
                .collect();
            let lanes = Rays::of(&rays);
            let mut bound = [Real::INFINITY; BATCH];
            if case % 3 == 0 {
                for b in bound.iter_mut() {
                    *b = (2.0 * u()) as Real;
                }
            }
            let t_min = if case % 5 == 0 { 0.0 } else { 1e-4 };
            let t = distances(kind, &lanes.mapped(&item.xf), t_min, &bound);
            let lanes_hit = t.iter().filter(|t| **t < Real::INFINITY).count();
            hits += lanes_hit;
            let met = reach.met(&lanes, lanes.largest_origin(), t_min, &bound);
            assert!(
                met || lanes_hit == 0,
                "case {case}: the reach (aggregate/lanes.rs Reach) rules out a batch of which \
                 {lanes_hit} rays hit the {kind:?} placed by {m:?} + {d:?}: {rays:?}"
            );
            skipped += !met as usize;
            if !aimed {
                away += 1;
                away_skipped += !met as usize;
            }
        }
        assert!(hits > 5000, "only {hits} rays hit");
        assert!(
            away_skipped * 2 > away,
            "the reach ruled out only {away_skipped} of {away} batches aimed away from the item"
        );
        assert!(skipped > 0);
    }

    /// The reach's edge cases, each a ray that an item's own test hits and that the
    /// reach must keep: a ray from a point exactly on the widened box's face with a
    /// subnormal direction component (whose reciprocal overflows, so that one of the
    /// face's distances is 0·∞, a NaN), rays parallel to a slab and inside it, and an
    /// interval that starts behind the origin (`intersect_many` takes any `t_min`).
    #[test]
    fn reach_keeps_nan_parallel_and_backward_rays() {
        use crate::transform::{Affine64, Transform};
        let placed = |kind: Kind, scale: f64, at: glam::DVec3| {
            let x = Transform::new(&Affine64 {
                m: glam::DMat3::from_diagonal(glam::DVec3::splat(scale)),
                d: at,
            })
            .unwrap();
            let unit = Aabb::from_points(Vec3::splat(-1.0), Vec3::ONE);
            let xf = Some((x.inverse_matrix(), x.matrix(), x.translation()));
            Item::new(kind, xf, &x.bounds(&unit), 0, 1, 0)
        };
        let hit_and_met = |item: &Item, ray: Ray, t_min: Real| {
            let lanes = Rays::of(&[ray]);
            let bound = [Real::INFINITY; BATCH];
            let t = distances(item.kind, &lanes.mapped(&item.xf), t_min, &bound)[0];
            let reach = item.reach.unwrap();
            (
                t < Real::INFINITY,
                reach.met(&lanes, lanes.largest_origin(), t_min, &bound),
            )
        };
        // A cube of half-size 0.01 at the origin; a ray from a point exactly on its
        // widened +x face, and one from its −x face (the origin's own coordinate widens
        // it: found by stepping out from the face), back towards it at a subnormal speed,
        // parallel to y.
        let cube = placed(Kind::Cube, 0.01, glam::DVec3::ZERO);
        let reach = cube.reach.unwrap();
        // Each face: its side, and the point's step outward from the unwidened face.
        for (side, face) in [(1.0, reach.hi.x), (-1.0, reach.lo.x)] {
            let mut x = face;
            let on_face = (0..100_000).find_map(|_| {
                x = if side > 0.0 {
                    x.next_up()
                } else {
                    x.next_down()
                };
                (face + side * (x.abs() * reach.per_origin) == x).then_some(x)
            });
            let x = on_face.expect("a point exactly on the widened face");
            // (Its z, small but not subnormal, gives the interval a finite end, far
            // beyond the hit, which a +∞ entry from the NaN'd axis would pass.)
            let d = Vec3::new(
                -side * Real::MIN_POSITIVE / 4.0,
                0.0,
                Real::MIN_POSITIVE * 16.0,
            );
            let slow = Ray::new(Vec3::new(x, 0.0, 0.0), d);
            assert_eq!(
                hit_and_met(&cube, slow, 0.0),
                (true, true),
                "aggregate/lanes.rs Reach::met: a ray from the widened face at a subnormal \
                 speed, whose slab distances are ∞ and 0·∞ (a NaN), hits the cube ({slow:?})"
            );
        }
        // Parallel to two axes, inside their slabs, through a sphere and a cylinder.
        for kind in [Kind::Sphere, Kind::Cylinder { capped: true }] {
            let item = placed(kind, 0.5, glam::DVec3::new(3.0, 0.0, 0.0));
            let ray = Ray::new(Vec3::new(0.0, 0.1, 0.0), Vec3::X);
            assert_eq!(
                hit_and_met(&item, ray, 0.0),
                (true, true),
                "{kind:?}, parallel: {ray:?}"
            );
        }
        // Behind the origin, found from t_min = −10.
        let behind = placed(Kind::Sphere, 0.5, glam::DVec3::new(-5.0, 0.0, 0.0));
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(
            hit_and_met(&behind, ray, -10.0),
            (true, true),
            "aggregate/lanes.rs Reach::met: a sphere behind the origin, with t_min = −10"
        );
        // And the same sphere from t_min = 0: neither.
        assert_eq!(hit_and_met(&behind, ray, 0.0), (false, false));
    }

    /// The skip does its work: a batch that passes beside a box is ruled out even when
    /// its rays start inside one of the box's slabs, parallel to it or not, and so is one
    /// whose search ends before it reaches the box. (cargo-mutants
    /// found these unpinned: a slab that counts a ray inside it as meeting it everywhere
    /// whatever its direction, a parallel ray outside it as meeting it, or a search's end
    /// as ruling out only a box entered exactly there, never rules out a wrong batch, so
    /// `reach_rules_out_only_batches_that_miss` passes; it only stops skipping.)
    #[test]
    fn reach_rules_out_rays_beside_it_from_inside_a_slab() {
        use crate::transform::{Affine64, Transform};
        // A cube of half-size 0.5 at the origin.
        let x = Transform::new(&Affine64 {
            m: glam::DMat3::from_diagonal(glam::DVec3::splat(0.5)),
            d: glam::DVec3::ZERO,
        })
        .unwrap();
        let unit = Aabb::from_points(Vec3::splat(-1.0), Vec3::ONE);
        let xf = Some((x.inverse_matrix(), x.matrix(), x.translation()));
        let cube = Item::new(Kind::Cube, xf, &x.bounds(&unit), 0, 1, 0);
        let reach = cube.reach.unwrap();
        let cases = [
            // Inside the x and z slabs, above the box, leaving the x slab (at t = 0.5)
            // before it comes down into the y slab (at t = 1).
            (
                "from inside the x slab, leaving it first",
                Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(1.0, -0.5, 0.0)),
                Real::INFINITY,
            ),
            // Parallel to the x and y slabs, inside x's and above y's.
            (
                "parallel to y's slab, outside it",
                Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z),
                Real::INFINITY,
            ),
            // Straight at the box (entered at t = 4.5), its search ending at t = 2.
            (
                "whose search ends before the box",
                Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z),
                2.0,
            ),
        ];
        for (what, ray, end) in cases {
            let bound = [end; BATCH];
            let lanes = Rays::of(&[ray]);
            let t = distances(cube.kind, &lanes.mapped(&cube.xf), 0.0, &bound)[0];
            assert_eq!(
                t,
                Real::INFINITY,
                "{what}: the ray misses the cube ({ray:?})"
            );
            assert!(
                !reach.met(&lanes, lanes.largest_origin(), 0.0, &bound),
                "aggregate/lanes.rs Reach::met: a batch {what} passes beside the cube and must \
                 be ruled out ({ray:?})"
            );
        }
    }
}
