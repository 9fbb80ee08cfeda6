//! The watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013): permute the axes
//! so the largest direction component is z, shear the vertices into ray space, and test
//! 2D edge functions. An edge function that is exactly zero is recomputed in `f64`, so a
//! ray through a shared edge or vertex hits exactly one of the triangles that share it
//! (or both, at the same t), never neither.

use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::ray::Ray;
use crate::real::{gamma, Real, Vec2, Vec3};

/// A ray prepared for many triangle tests.
#[derive(Clone, Copy, Debug)]
pub struct WoopRay {
    o: Vec3,
    k: [usize; 3],
    s: [Real; 3],
}

impl WoopRay {
    /// Prepares `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if ray.d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = ray.d[kz];
        WoopRay {
            o: ray.o,
            k: [kx, ky, kz],
            s: [ray.d[kx] / dz, ray.d[ky] / dz, 1.0 / dz],
        }
    }

    /// Tests one triangle. Returns `t` and the barycentric weights of p0, p1, p2.
    #[inline]
    pub fn hit(
        &self,
        p0: Vec3,
        p1: Vec3,
        p2: Vec3,
        t_min: Real,
        t_max: Real,
    ) -> Option<(Real, [Real; 3])> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.s;
        let a = p0 - self.o;
        let b = p1 - self.o;
        let c = p2 - self.o;
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as Real;
            v = (ax * cy - ay * cx) as Real;
            w = (bx * ay - by * ax) as Real;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (sz * a[kz], sz * b[kz], sz * c[kz]);
        let t = (u * az + v * bz + w * cz) / det;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let inv = 1.0 / det;
        Some((t, [u * inv, v * inv, w * inv]))
    }
}

/// A single triangle with optional per-vertex normals and uvs.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3; 3],
    /// Per-vertex shading normals.
    pub n: Option<[Vec3; 3]>,
    /// Per-vertex uvs; the default is (0,0), (1,0), (0,1).
    pub uv: Option<[Vec2; 3]>,
}

impl Triangle {
    /// The geometric normal `(p1 − p0) × (p2 − p0)` (not normalized).
    pub fn normal(&self) -> Vec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in self.p {
            b.grow(p);
        }
        b
    }

    /// Closest hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: Real, t_max: Real) -> Option<Hit> {
        let (t, bary) = WoopRay::new(ray).hit(self.p[0], self.p[1], self.p[2], t_min, t_max)?;
        Some(surface(
            t,
            bary,
            self.p,
            self.normal(),
            self.n.as_ref(),
            self.uv.as_ref(),
        ))
    }
}

/// Builds the hit record from barycentrics: interpolated shading normal and uv.
#[inline]
pub(crate) fn surface(
    t: Real,
    b: [Real; 3],
    v: [Vec3; 3],
    n_geo: Vec3,
    n: Option<&[Vec3; 3]>,
    uv: Option<&[Vec2; 3]>,
) -> Hit {
    // The point from barycentrics, with pbrt's bound γ(7)·Σ|bᵢ·pᵢ|.
    let (q0, q1, q2) = (v[0] * b[0], v[1] * b[1], v[2] * b[2]);
    let p = q0 + q1 + q2;
    let err = (q0.abs() + q1.abs() + q2.abs()) * gamma(7);
    let n_shade = match n {
        Some(n) => {
            let s = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
            if s.length_squared() > 0.0 {
                s
            } else {
                n_geo
            }
        }
        None => n_geo,
    };
    let uv = match uv {
        Some(uv) => uv[0] * b[0] + uv[1] * b[1] + uv[2] * b[2],
        None => Vec2::new(b[1], b[2]),
    };
    Hit::new(t, p, err, n_geo, n_shade, uv)
}
