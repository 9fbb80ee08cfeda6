//! Affine instances of the canonical unit rectangle and sphere, searched eight rays at a
//! time: the ray goes into object space by the inverse map (not renormalised, so t is the
//! same in both spaces), the normal comes out by the inverse's transpose.
use crate::lanes::V;
use wide::*;

/// `world = m·object + t`, with `m`'s inverse.
#[derive(Clone, Copy)]
pub struct Affine {
    pub m: [[f32; 3]; 3],
    pub inv: [[f32; 3]; 3],
    pub t: [f32; 3],
}

impl Affine {
    /// A diagonal map (scales, and turns by 180 degrees as signs) and a translation.
    pub fn diagonal(d: [f32; 3], t: [f32; 3]) -> Affine {
        let diag = |d: [f32; 3]| [[d[0], 0., 0.], [0., d[1], 0.], [0., 0., d[2]]];
        Affine { m: diag(d), inv: diag(d.map(|x| 1.0 / x)), t }
    }
    fn apply(m: &[[f32; 3]; 3], v: V) -> V {
        let row = |k: usize| {
            f32x8::splat(m[k][0]) * v.x + f32x8::splat(m[k][1]) * v.y + f32x8::splat(m[k][2]) * v.z
        };
        V { x: row(0), y: row(1), z: row(2) }
    }
    pub fn ray_in(&self, o: V, d: V) -> (V, V) {
        let t = V::splat(self.t[0], self.t[1], self.t[2]);
        (Self::apply(&self.inv, o.sub(t)), Self::apply(&self.inv, d))
    }
    pub fn normal_out(&self, n: V) -> V {
        let i = &self.inv;
        let it = [[i[0][0], i[1][0], i[2][0]], [i[0][1], i[1][1], i[2][1]], [i[0][2], i[1][2], i[2][2]]];
        Self::apply(&it, n)
    }
}

#[derive(Clone, Copy)]
pub enum Shape {
    /// y = 0, |x| and |z| at most 1, normal +y.
    Rectangle,
    /// The unit sphere.
    Sphere,
}

pub struct Object {
    pub shape: Shape,
    pub xf: Affine,
    pub albedo: [f32; 3],
    pub radiance: f32,
}

/// The hit distance in (t_min, t_max) (infinity where none) and the object-space normal.
fn hit(shape: Shape, o: V, d: V, t_min: f32x8, t_max: f32x8) -> (f32x8, V) {
    let none = f32x8::splat(f32::INFINITY);
    match shape {
        Shape::Rectangle => {
            let t = -o.y / d.y;
            let (x, z) = (o.x + t * d.x, o.z + t * d.z);
            let inside = x.abs().cmp_le(f32x8::ONE) & z.abs().cmp_le(f32x8::ONE);
            let ok = t.cmp_gt(t_min) & t.cmp_lt(t_max) & inside;
            (ok.blend(t, none), V::splat(0., 1., 0.))
        }
        Shape::Sphere => {
            let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - f32x8::ONE);
            let disc = b * b - a * c;
            let root = disc.max(f32x8::ZERO).sqrt();
            let (near, far) = ((-b - root) / a, (-b + root) / a);
            let t = near.cmp_gt(t_min).blend(near, far);
            let ok = disc.cmp_ge(f32x8::ZERO) & t.cmp_gt(t_min) & t.cmp_lt(t_max);
            let t = ok.blend(t, none);
            (t, o.add(d.mul(t)))
        }
    }
}

pub struct Scene {
    pub objects: Vec<Object>,
}

impl Scene {
    /// Closest hits: distance (infinity for a miss), object index (-1), world normal (not
    /// normalised).
    pub fn closest(&self, o: V, d: V, t_min: f32x8) -> (f32x8, i32x8, V) {
        let mut best = f32x8::splat(f32::INFINITY);
        let mut id = i32x8::splat(-1);
        let mut n = V::splat(0., 1., 0.);
        for (k, obj) in self.objects.iter().enumerate() {
            let (lo, ld) = obj.xf.ray_in(o, d);
            let (t, ln) = hit(obj.shape, lo, ld, t_min, best);
            let closer = t.cmp_lt(best);
            if closer.any() {
                best = closer.blend(t, best);
                id = bytemuck::cast::<f32x8, i32x8>(closer).blend(i32x8::splat(k as i32), id);
                n = V::blend(closer, obj.xf.normal_out(ln), n);
            }
        }
        (best, id, n)
    }

    /// Whether anything but object `skip` lies in (t_min, t_max), as a lane mask.
    pub fn occluded(&self, o: V, d: V, t_min: f32x8, t_max: f32x8, skip: usize) -> f32x8 {
        let mut blocked = f32x8::ZERO;
        for (k, obj) in self.objects.iter().enumerate() {
            if k == skip {
                continue;
            }
            let (lo, ld) = obj.xf.ray_in(o, d);
            blocked = blocked | hit(obj.shape, lo, ld, t_min, t_max).0.cmp_lt(t_max);
            if blocked.move_mask() == 0xff {
                break;
            }
        }
        blocked
    }
}
