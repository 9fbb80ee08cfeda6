//! The cylinder of radius 1 about the y axis, y ∈ [−1, 1], open or capped. The side uses
//! the same stable quadratic as the sphere, in the xz plane.

use super::{azimuth, local_hit, stable_roots};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// Closest hit. Side normal (x, 0, z); cap normals ±y. uv: side (azimuth, (y+1)/2), caps
/// ((x+1)/2, (z+1)/2).
#[inline]
pub fn intersect(ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> Option<Hit> {
    let c = Crossing::of(ray.o, ray.d);
    let (t, part) = c.pick(capped, t_min, t_max);
    if part == MISSED {
        return None;
    }
    let (p, err, n, mut uv) = c.record(ray.o, ray.d, part, t);
    if on_side(part) {
        uv.x = azimuth(p.x, p.z);
    }
    Some(local_hit(t, p, err, n, uv))
}

/// Whether the cylinder is hit with `t_min < t < t_max`: [`intersect`]'s choice without
/// its record (shadow rays).
#[inline]
pub fn hits(ray: &Ray, capped: bool, t_min: Real, t_max: Real) -> bool {
    Crossing::of(ray.o, ray.d).pick(capped, t_min, t_max).1 != MISSED
}

/// Which of the cylinder's candidates a ray takes ([`Crossing::pick`]): the side's first
/// or second root, the cap at y = −1 or at y = 1, or none.
const SIDE_NEAR: u32 = 0;
const SIDE_FAR: u32 = 1;
const CAP_LOW: u32 = 2;
const CAP_HIGH: u32 = 3;
const MISSED: u32 = 4;

/// Whether the candidate `part` lies on the side, whose u is the azimuth of its point.
#[inline(always)]
pub(crate) fn on_side(part: u32) -> bool {
    part <= SIDE_FAR
}

/// What the test computes for a ray before it chooses: the slab −1 ≤ y ≤ 1 as an interval
/// of t ([`slab`]), whose ends are the caps' distances, and the infinite cylinder's
/// roots. Written without branches (selects on computed values, `&` for `&&`), so that
/// the lanes (aggregate/lanes.rs), which call it lane by lane, stay vector code.
///
/// The side's line is in f64, in both builds, as for the sphere: in f32 the products
/// d·(b/a), of size |o|, move l by ε·|o|, so a far cylinder (|o| ≫ 1 in object space) got
/// wrong hits and misses near its silhouette.
pub(crate) struct Crossing {
    ty: (Real, Real),
    caps: (Real, Real),
    parallel: bool,
    /// `a = dx² + dz²`, in f64 and in `Real`.
    a64: f64,
    a: Real,
    /// The point of the line nearest the axis, in xz.
    l: (f64, f64),
    d: (f64, f64),
    disc64: f64,
    /// `x² + z²` of the origin.
    rr: Real,
    t: (Real, Real),
    /// Whether the side has roots: `a > 0` and `disc ≥ 0` (else `t` holds values that
    /// [`Crossing::pick`] masks out).
    roots: bool,
}

impl Crossing {
    #[inline(always)]
    pub(crate) fn of(o: Vec3, d: Vec3) -> Crossing {
        let (ya, yb) = ((-1.0 - o.y) / d.y, (1.0 - o.y) / d.y);
        let parallel = d.y == 0.0;
        let ty = slab(o.y, d.y);
        let (ox, oz, dx, dz) = (o.x as f64, o.z as f64, d.x as f64, d.z as f64);
        let a64 = dx * dx + dz * dz;
        let a = a64 as Real;
        let b64 = ox * dx + oz * dz;
        let (lx, lz) = (ox - dx * (b64 / a64), oz - dz * (b64 / a64));
        let disc64 = a64 * (1.0 - (lx * lx + lz * lz));
        let (b, disc) = (b64 as Real, disc64 as Real);
        let rr = o.x * o.x + o.z * o.z;
        Crossing {
            ty,
            caps: (ya, yb),
            parallel,
            a64,
            a,
            l: (lx, lz),
            d: (dx, dz),
            disc64,
            rr,
            t: stable_roots(a, b, rr - 1.0, disc),
            roots: (a > 0.0) & (disc >= 0.0),
        }
    }

    /// The candidate the test keeps in `(t_min, t_max)`: its distance (infinity for none)
    /// and which it is ([`SIDE_NEAR`] to [`MISSED`]). The side's first root inside the
    /// slab; then each cap (y = −1, then 1) whose distance is closer and lies between the
    /// side's roots (or, parallel to the axis, whose ray runs inside the radius). The same
    /// computed values decide the side and the caps, so a ray entering exactly at a rim
    /// takes the later of the two entries, as in the box's slab test. (Testing the y of
    /// one rounded point and the radius of another left a gap: 1.8 % of the rays aimed
    /// at a rim from inside the solid's tangent cone missed in f32.)
    #[inline(always)]
    pub(crate) fn pick(&self, capped: bool, t_min: Real, t_max: Real) -> (Real, u32) {
        let (t0, t1) = self.t;
        let kept = |t: Real| (t > t_min) & (t < t_max) & (self.ty.0 <= t) & (t <= self.ty.1);
        let (in0, in1) = (self.roots & kept(t0), self.roots & kept(t1));
        let (mut bound, mut part) = if in0 {
            (t0, SIDE_NEAR)
        } else if in1 {
            (t1, SIDE_FAR)
        } else {
            (t_max, MISSED)
        };
        let along_axis = (self.a == 0.0) & (self.rr <= 1.0);
        for (t, cap) in [(self.caps.0, CAP_LOW), (self.caps.1, CAP_HIGH)] {
            let inside = if self.roots {
                (t0 <= t) & (t <= t1)
            } else {
                along_axis
            };
            let take = capped & !self.parallel & (t > t_min) & (t < bound) & inside;
            bound = if take { t } else { bound };
            part = if take { cap } else { part };
        }
        if part == MISSED {
            (Real::INFINITY, MISSED)
        } else {
            (bound, part)
        }
    }

    /// The record of the candidate `part` at `t` for the ray `(o, d)`: the point, its
    /// error bound, the normal and the uv, with a side point's u left at `(x + 1)/2` (the
    /// caller takes the azimuth, an `atan2`, once it knows the hit is kept).
    /// - On the side, the point in xz is l ∓ d·√disc/a (l: the line's closest point to
    ///   the axis), not o + t·d, which cancels when |o| ≫ 1 (a far or flattened instance
    ///   seen in object space), down to the axis itself and a NaN; with nothing left of
    ///   it, the side facing the ray. Re-projected onto radius 1 in xz (pbrt), error
    ///   γ(3)·|x|, γ(3)·|z|; y is `o.y + t·d.y` clamped to the slab, error γ(4)·|y|.
    /// - On a cap, `o + t·d` put on the cap's plane, error γ(4)·|x|, γ(4)·|z|.
    #[inline(always)]
    pub(crate) fn record(&self, o: Vec3, d: Vec3, part: u32, t: Real) -> (Vec3, Vec3, Vec3, Vec2) {
        let side: f64 = if part == SIDE_NEAR { -1.0 } else { 1.0 };
        let k = side * self.disc64.sqrt() / self.a64;
        let x = (self.l.0 + self.d.0 * k) as Real;
        let z = (self.l.1 + self.d.1 * k) as Real;
        let r = (x * x + z * z).sqrt();
        let kept = (r > 0.0) & (r.abs() < Real::INFINITY);
        let (x, z, r) = if kept {
            (x, z, r)
        } else {
            (-d.x, -d.z, self.a.sqrt())
        };
        let y = (o.y + t * d.y).clamp(-1.0, 1.0);
        let side_hit = on_side(part);
        let cap_y: Real = if part == CAP_LOW { -1.0 } else { 1.0 };
        let at = o + d * t;
        let p = if side_hit {
            Vec3::new(x / r, y, z / r)
        } else {
            Vec3::new(at.x, cap_y, at.z)
        };
        let (g3, g4) = (gamma(3), gamma(4));
        let g = if side_hit {
            Vec3::new(g3, g4, g3)
        } else {
            Vec3::new(g4, 0.0, g4)
        };
        let n = if side_hit {
            Vec3::new(p.x, 0.0, p.z)
        } else {
            Vec3::new(0.0, cap_y, 0.0)
        };
        let v = if side_hit { p.y } else { p.z };
        (
            p,
            p.abs() * g,
            n,
            Vec2::new((p.x + 1.0) * 0.5, (v + 1.0) * 0.5),
        )
    }
}

/// The interval of t in which `o_y + t·d_y` lies in [−1, 1] (empty when `d_y = 0` and the
/// ray is outside). Its ends are computed exactly as the caps' t. Written with selects,
/// not branches, for the lanes ([`Crossing`]).
#[inline(always)]
pub(crate) fn slab(o_y: Real, d_y: Real) -> (Real, Real) {
    let (a, b) = ((-1.0 - o_y) / d_y, (1.0 - o_y) / d_y);
    let within = (-1.0 <= o_y) & (o_y <= 1.0);
    let (lo, hi) = if within {
        (Real::NEG_INFINITY, Real::INFINITY)
    } else {
        (Real::INFINITY, Real::NEG_INFINITY)
    };
    if d_y != 0.0 {
        (a.min(b), a.max(b))
    } else {
        (lo, hi)
    }
}
