//! The cube [−1, 1]³, by the slab method. The normal is that of the slab the ray enters
//! through (or leaves through, when it starts inside).

use super::local_hit;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// Closest hit on the cube.
#[inline]
pub fn intersect(ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
    let c = Crossing::of(ray.o, ray.d);
    let (t, entering) = c.pick(t_min, t_max);
    if t == Real::INFINITY {
        return None;
    }
    let (p, err, n, uv) = c.record(ray.o, ray.d, entering, t);
    Some(local_hit(t, p, err, n, uv))
}

/// Whether the ray hits the cube with `t_min < t < t_max`: exactly when [`intersect`]
/// returns a hit.
#[inline]
pub fn hits(ray: &Ray, t_min: Real, t_max: Real) -> bool {
    Crossing::of(ray.o, ray.d).pick(t_min, t_max).0 != Real::INFINITY
}

/// What the slab test computes for a ray before it chooses: the entry and exit distances
/// over the slabs of the axes the ray is not parallel to, the axes they come from (the
/// first axis on a tie), and whether the ray is parallel to an axis and outside its slab
/// (a miss). Written without branches (selects on computed values, `&` for `&&`), so that
/// the lanes (aggregate/lanes.rs), which call it lane by lane, stay vector code; the
/// scalar test, which took a branch for each axis and kept its record's fields in memory
/// to index them by the face's axis, is the same code.
pub(crate) struct Crossing {
    near: Real,
    far: Real,
    near_axis: usize,
    far_axis: usize,
    outside: bool,
}

impl Crossing {
    #[inline(always)]
    pub(crate) fn of(o: Vec3, d: Vec3) -> Crossing {
        let (mut near, mut far) = (Real::NEG_INFINITY, Real::INFINITY);
        let (mut near_axis, mut far_axis) = (0usize, 0usize);
        let mut outside = false;
        for k in 0..3 {
            let (o, d) = (o[k], d[k]);
            let parallel = d == 0.0;
            outside |= parallel & !((-1.0 <= o) & (o <= 1.0));
            let inv = 1.0 / d;
            let (a, b) = ((-1.0 - o) * inv, (1.0 - o) * inv);
            let (a, b) = if a > b { (b, a) } else { (a, b) };
            let nearer = !parallel & (a > near);
            let farther = !parallel & (b < far);
            near = if nearer { a } else { near };
            near_axis = if nearer { k } else { near_axis };
            far = if farther { b } else { far };
            far_axis = if farther { k } else { far_axis };
        }
        Crossing {
            near,
            far,
            near_axis,
            far_axis,
            outside,
        }
    }

    /// The crossing the test keeps in `(t_min, t_max)`: its distance (infinity for none)
    /// and whether the ray enters there (else it leaves: it starts inside). The entry when
    /// it lies in the interval, else the exit.
    #[inline(always)]
    pub(crate) fn pick(&self, t_min: Real, t_max: Real) -> (Real, bool) {
        let (near, far) = (self.near, self.far);
        let in_near = (near > t_min) & (near < t_max);
        let in_far = (far > t_min) & (far < t_max);
        let hit = !self.outside & !(near > far) & (in_near | in_far);
        let t = if in_near { near } else { far };
        (if hit { t } else { Real::INFINITY }, in_near)
    }

    /// The record of the crossing at `t` for the ray `(o, d)`, entering or leaving: the
    /// point `o + t·d` snapped onto the face (the face's coordinate ±1 exactly, the other
    /// two with error γ(4)·|x|), the face's normal, and the uv of the two other
    /// coordinates in the axes' cyclic order, each mapped to [0, 1]. The face's
    /// coordinate is chosen by selects, not read from memory by index.
    #[inline(always)]
    pub(crate) fn record(
        &self,
        o: Vec3,
        d: Vec3,
        entering: bool,
        t: Real,
    ) -> (Vec3, Vec3, Vec3, Vec2) {
        let axis = if entering {
            self.near_axis
        } else {
            self.far_axis
        };
        let on = [axis == 0, axis == 1, axis == 2];
        let da = if on[0] {
            d.x
        } else if on[1] {
            d.y
        } else {
            d.z
        };
        let side = if entering { -da.signum() } else { da.signum() };
        let at = o + d * t;
        let g4 = gamma(4);
        let (mut p, mut err, mut n) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        for c in 0..3 {
            p[c] = if on[c] { side } else { at[c] };
            err[c] = if on[c] { 0.0 } else { p[c].abs() * g4 };
            n[c] = if on[c] { side } else { 0.0 };
        }
        // The coordinates after the face's axis: (y, z), (z, x) or (x, y).
        let (u, v) = if on[0] {
            (p[1], p[2])
        } else if on[1] {
            (p[2], p[0])
        } else {
            (p[0], p[1])
        };
        (
            Vec3::from(p),
            Vec3::from(err),
            Vec3::from(n),
            Vec2::new((u + 1.0) * 0.5, (v + 1.0) * 0.5),
        )
    }
}
