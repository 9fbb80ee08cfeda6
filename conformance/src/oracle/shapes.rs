//! Closed-form ray intersections of the canonical primitives, in `f64`, in object space.
//!
//! Each function takes the ray `o + t·d` in the primitive's own space (`d` as the instance
//! mapped it, not renormalised, so `t` is the world distance) and the open interval
//! `(t_min, t_max)`, and returns the nearest root inside it with the object-space normal
//! (any orientation: the shading flips it to face the ray, as POV-Ray does).
//!
//! | primitive | surface | POV-Ray (as the exporter writes it) |
//! |---|---|---|
//! | sphere | x² + y² + z² = 1 | `sphere { 0, 1 }` |
//! | plane | y = 0 | `plane { y, 0 }` |
//! | cube | the faces of [−1, 1]³ | `box { -1, 1 }` |
//! | cylinder | x² + z² = 1, \|y\| ≤ 1, caps y = ±1 | `cylinder { -y, y, 1 [open] }` |
//! | cone | x² + z² = ((1 − y)/2)², \|y\| ≤ 1, base y = −1 | `cone { -y, 1, y, 0 [open] }` |
//! | disk | y = 0, x² + z² ≤ 1 | `disc { 0, y, 1 }` |
//! | rectangle | y = 0, \|x\| ≤ 1, \|z\| ≤ 1 | `polygon` of its 4 corners |
//! | triangle | the plane of its vertices, inside its edges | `triangle`, `smooth_triangle` |

use glam::DVec3;

/// A root and its object-space normal (not unit).
pub type Root = (f64, DVec3);

/// What the oracle intersects in object space.
#[derive(Clone, Debug)]
pub enum Primitive {
    /// Unit sphere.
    Sphere,
    /// The plane y = 0.
    Plane,
    /// [−1, 1]³.
    Cube,
    /// Radius-1 cylinder, y ∈ [−1, 1].
    Cylinder {
        /// Whether the end disks are part of the surface.
        capped: bool,
    },
    /// Apex (0, 1, 0), base radius 1 at y = −1.
    Cone {
        /// Whether the base disk is part of the surface.
        capped: bool,
    },
    /// Unit disk in y = 0.
    Disk,
    /// [−1, 1]² in y = 0.
    Rectangle,
    /// A triangle (object-space vertices), with per-vertex normals when smooth.
    Triangle([DVec3; 3], Option<[DVec3; 3]>),
}

/// POV-Ray ignores a plane's hits beyond `MAX_DISTANCE` (1e7; source/backend/frame.h in 3.7,
/// used by source/backend/shape/planes.cpp, `Plane::Intersect`).
pub const MAX_DISTANCE: f64 = 1e7;

/// Keeps the nearer of two candidates.
fn nearer(best: Option<Root>, t: f64, n: DVec3, lo: f64, hi: f64) -> Option<Root> {
    if t > lo && t < hi && best.is_none_or(|b| t < b.0) {
        Some((t, n))
    } else {
        best
    }
}

/// The two roots of a·t² + 2b·t + c = 0 (a ≠ 0), smaller first, computed without
/// cancellation; `None` when there is no real root.
fn quadratic(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let q = -(b + b.signum() * disc.sqrt());
    if q == 0.0 {
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (q / a, c / q);
    Some((t0.min(t1), t0.max(t1)))
}

impl Primitive {
    /// The nearest intersection with t in (lo, hi), refined ([`Primitive::refine`]): its
    /// distance, normal and object-space point.
    pub fn intersect(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<(f64, DVec3, DVec3)> {
        self.root(o, d, lo, hi)
            .map(|(t, n)| self.refine(o, d, t, n))
    }

    /// One Newton step of the root onto the surface: from the point `o + t·d`, the root
    /// of the same surface nearest to it is added to t, and the normal recomputed there.
    ///
    /// A root found from far away carries the cancellation of its equation's constant
    /// term (for a sphere seen from distance D, |o|² − 1 loses about D² ulps), so the point
    /// may lie ~1e-11 off the surface at D = 300; a shadow ray leaving such a point at a
    /// grazing angle would find its own surface again beyond [`super::shade::SELF`]. From
    /// the point itself the constant term is tiny and exact to an ulp of 1, and so is
    /// the step.
    fn refine(&self, o: DVec3, d: DVec3, t: f64, n: DVec3) -> (f64, DVec3, DVec3) {
        let p = o + t * d;
        // The root of a·s² + 2b·s + c = 0 nearest to 0 (0 if there is none).
        let small = |a: f64, b: f64, c: f64| {
            quadratic(a, b, c).map_or(0.0, |(s0, s1)| if s0.abs() < s1.abs() { s0 } else { s1 })
        };
        // The plane through the face with unit normal `axis` at signed offset `at`.
        let plane = |axis: usize, at: f64| {
            if d[axis] == 0.0 {
                0.0
            } else {
                (at - p[axis]) / d[axis]
            }
        };
        let s = match self {
            Primitive::Sphere => small(d.dot(d), p.dot(d), p.dot(p) - 1.0),
            Primitive::Plane | Primitive::Disk | Primitive::Rectangle => plane(1, 0.0),
            Primitive::Cube => {
                let a = (0..3).find(|&a| n[a] != 0.0).unwrap_or(0);
                plane(a, p[a].signum())
            }
            Primitive::Cylinder { .. } if n.y != 0.0 => plane(1, n.y.signum()),
            Primitive::Cylinder { .. } => small(
                d.x * d.x + d.z * d.z,
                p.x * d.x + p.z * d.z,
                p.x * p.x + p.z * p.z - 1.0,
            ),
            Primitive::Cone { .. } if n == -DVec3::Y => plane(1, -1.0),
            Primitive::Cone { .. } => {
                let (h, k) = (1.0 - p.y, -d.y);
                small(
                    d.x * d.x + d.z * d.z - 0.25 * k * k,
                    p.x * d.x + p.z * d.z - 0.25 * h * k,
                    p.x * p.x + p.z * p.z - 0.25 * h * h,
                )
            }
            Primitive::Triangle(v, _) => {
                let dn = d.dot(n);
                if dn == 0.0 {
                    0.0
                } else {
                    (v[0] - p).dot(n) / dn
                }
            }
        };
        let q = p + s * d;
        let n = match self {
            Primitive::Sphere => q,
            Primitive::Cylinder { .. } if n.y == 0.0 => DVec3::new(q.x, 0.0, q.z),
            Primitive::Cone { .. } if n != -DVec3::Y => {
                DVec3::new(2.0 * q.x, 0.5 * (1.0 - q.y), 2.0 * q.z)
            }
            Primitive::Triangle(v, Some(vn)) => smooth_normal(v, vn, q, n),
            _ => n,
        };
        (t + s, n, q)
    }

    /// The nearest root with t in (lo, hi), as the closed form gives it.
    fn root(&self, o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Root> {
        match self {
            Primitive::Sphere => sphere(o, d, lo, hi),
            Primitive::Plane => flat(o, d, lo, hi.min(MAX_DISTANCE), |_| true),
            Primitive::Cube => cube(o, d, lo, hi),
            Primitive::Cylinder { capped } => cylinder(o, d, lo, hi, *capped),
            Primitive::Cone { capped } => cone(o, d, lo, hi, *capped),
            Primitive::Disk => flat(o, d, lo, hi, |p| p.x * p.x + p.z * p.z <= 1.0),
            Primitive::Rectangle => flat(o, d, lo, hi, |p| p.x.abs() <= 1.0 && p.z.abs() <= 1.0),
            Primitive::Triangle(v, _) => triangle(v, o, d, lo, hi),
        }
    }
}

fn sphere(o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Root> {
    let (t0, t1) = quadratic(d.dot(d), o.dot(d), o.dot(o) - 1.0)?;
    let mut best = None;
    for t in [t0, t1] {
        best = nearer(best, t, o + t * d, lo, hi);
    }
    best
}

/// The plane y = 0, restricted to the points `inside` accepts.
fn flat(o: DVec3, d: DVec3, lo: f64, hi: f64, inside: impl Fn(DVec3) -> bool) -> Option<Root> {
    if d.y == 0.0 {
        return None;
    }
    let t = -o.y / d.y;
    let p = o + t * d;
    (t > lo && t < hi && inside(p)).then_some((t, DVec3::Y))
}

fn cube(o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Root> {
    // Slabs: the entering and leaving distance along each axis.
    let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut near_axis, mut far_axis) = (0, 0);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a].abs() > 1.0 {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((-1.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
        let (ta, tb) = (t0.min(t1), t0.max(t1));
        if ta > near {
            near = ta;
            near_axis = a;
        }
        if tb < far {
            far = tb;
            far_axis = a;
        }
    }
    if near > far {
        return None;
    }
    let axis = |a: usize| DVec3::AXES[a];
    nearer(
        nearer(None, far, axis(far_axis), lo, hi),
        near,
        axis(near_axis),
        lo,
        hi,
    )
}

fn cylinder(o: DVec3, d: DVec3, lo: f64, hi: f64, capped: bool) -> Option<Root> {
    let mut best = None;
    let a = d.x * d.x + d.z * d.z;
    if let Some((t0, t1)) = quadratic(a, o.x * d.x + o.z * d.z, o.x * o.x + o.z * o.z - 1.0) {
        for t in [t0, t1] {
            let p = o + t * d;
            if p.y.abs() <= 1.0 {
                best = nearer(best, t, DVec3::new(p.x, 0.0, p.z), lo, hi);
            }
        }
    }
    if capped && d.y != 0.0 {
        for y in [-1.0, 1.0] {
            let t = (y - o.y) / d.y;
            let p = o + t * d;
            if p.x * p.x + p.z * p.z <= 1.0 {
                best = nearer(best, t, DVec3::new(0.0, y, 0.0), lo, hi);
            }
        }
    }
    best
}

fn cone(o: DVec3, d: DVec3, lo: f64, hi: f64, capped: bool) -> Option<Root> {
    // x² + z² − (1 − y)²/4 = 0; its gradient is (2x, (1 − y)/2, 2z).
    let mut best = None;
    let (h, k) = (1.0 - o.y, -d.y);
    let a = d.x * d.x + d.z * d.z - 0.25 * k * k;
    let b = o.x * d.x + o.z * d.z - 0.25 * h * k;
    let c = o.x * o.x + o.z * o.z - 0.25 * h * h;
    let roots = if a == 0.0 {
        (b != 0.0).then(|| {
            let t = -c / (2.0 * b);
            (t, t)
        })
    } else {
        quadratic(a, b, c)
    };
    if let Some((t0, t1)) = roots {
        for t in [t0, t1] {
            let p = o + t * d;
            if p.y.abs() <= 1.0 {
                let n = DVec3::new(2.0 * p.x, 0.5 * (1.0 - p.y), 2.0 * p.z);
                best = nearer(best, t, n, lo, hi);
            }
        }
    }
    if capped && d.y != 0.0 {
        let t = (-1.0 - o.y) / d.y;
        let p = o + t * d;
        if p.x * p.x + p.z * p.z <= 1.0 {
            best = nearer(best, t, -DVec3::Y, lo, hi);
        }
    }
    best
}

/// A smooth triangle's normal at its point `q`: the vertex normals interpolated by `q`'s
/// barycentric weights. POV-Ray (`Mesh::Smooth_Mesh_Normal`, `SmoothTriangle::Normal`)
/// interpolates in two steps, from N1 by u (the fraction of the way from P1 to the edge
/// P2–P3) and along that edge by v: `N1 + u·(N2 − N1 + v·(N3 − N2))`, which is
/// `(1 − u)·N1 + u(1 − v)·N2 + uv·N3`, the barycentric interpolation itself. Where the
/// interpolated normal vanishes, the geometric one `n` is kept.
fn smooth_normal(v: &[DVec3; 3], vn: &[DVec3; 3], q: DVec3, n: DVec3) -> DVec3 {
    // q − v0 = b1·e1 + b2·e2, solved through the Gram matrix.
    let (e1, e2, w) = (v[1] - v[0], v[2] - v[0], q - v[0]);
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = a * c - b * b;
    if det == 0.0 {
        return n;
    }
    let (p, r) = (w.dot(e1), w.dot(e2));
    let b1 = (c * p - b * r) / det;
    let b2 = (a * r - b * p) / det;
    let s = (1.0 - b1 - b2) * vn[0] + b1 * vn[1] + b2 * vn[2];
    if s.length_squared() > 0.0 {
        s
    } else {
        n
    }
}

/// Möller and Trumbore's barycentric solve (1997), in `f64`.
fn triangle(v: &[DVec3; 3], o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Root> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - v[0];
    let b1 = s.dot(p) / det;
    let q = s.cross(e1);
    let b2 = d.dot(q) / det;
    if b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(q) / det;
    nearer(None, t, e1.cross(e2), lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One ray against one primitive: the expected distance and unit normal (up to sign).
    fn check(p: Primitive, o: [f64; 3], d: [f64; 3], want: Option<(f64, [f64; 3])>) {
        let got = p.intersect(DVec3::from(o), DVec3::from(d), 1e-9, f64::INFINITY);
        match (got, want) {
            (None, None) => {}
            (Some((t, n, _)), Some((wt, wn))) => {
                assert!((t - wt).abs() < 1e-12, "{p:?}: t {t}, want {wt}");
                let (n, wn) = (n.normalize(), DVec3::from(wn));
                assert!(
                    n.dot(wn).abs() > 1.0 - 1e-12,
                    "{p:?}: normal {n:?}, want {wn:?}"
                );
            }
            _ => panic!("{p:?} from {o:?} along {d:?}: got {got:?}, want {want:?}"),
        }
    }

    #[test]
    fn test01_each_primitive_against_its_closed_form() {
        let s = 0.5f64.sqrt();
        check(
            Primitive::Sphere,
            [0.0, 0.0, -5.0],
            [0.0, 0.0, 1.0],
            Some((4.0, [0.0, 0.0, -1.0])),
        );
        check(
            Primitive::Sphere,
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 2.0],
            Some((0.5, [0.0, 0.0, 1.0])),
        );
        check(Primitive::Sphere, [0.0, 1.5, -5.0], [0.0, 0.0, 1.0], None);
        check(
            Primitive::Plane,
            [0.0, 2.0, 0.0],
            [0.0, -1.0, 0.0],
            Some((2.0, [0.0, 1.0, 0.0])),
        );
        check(Primitive::Plane, [0.0, 1.0, 0.0], [1.0, -1e-8, 0.0], None);
        check(
            Primitive::Cube,
            [0.5, 0.5, -3.0],
            [0.0, 0.0, 1.0],
            Some((2.0, [0.0, 0.0, 1.0])),
        );
        check(
            Primitive::Cube,
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            Some((1.0, [1.0, 0.0, 0.0])),
        );
        check(Primitive::Cube, [1.5, 0.0, -3.0], [0.0, 0.0, 1.0], None);
        let cyl = Primitive::Cylinder { capped: true };
        check(
            cyl.clone(),
            [-3.0, 0.5, 0.0],
            [1.0, 0.0, 0.0],
            Some((2.0, [1.0, 0.0, 0.0])),
        );
        check(
            cyl.clone(),
            [0.5, 3.0, 0.0],
            [0.0, -1.0, 0.0],
            Some((2.0, [0.0, 1.0, 0.0])),
        );
        check(
            Primitive::Cylinder { capped: false },
            [0.5, 3.0, 0.0],
            [0.0, -1.0, 0.0],
            None,
        );
        // The cone's side at y = 0 has radius ½ and normal (1, ¼, 0)·k.
        let cone = Primitive::Cone { capped: true };
        let n = DVec3::new(2.0, 1.0, 0.0).normalize();
        check(
            cone.clone(),
            [-3.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            Some((2.5, [-n.x, n.y, 0.0])),
        );
        check(
            cone.clone(),
            [0.5, -3.0, 0.0],
            [0.0, 1.0, 0.0],
            Some((2.0, [0.0, 1.0, 0.0])),
        );
        check(
            Primitive::Cone { capped: false },
            [0.2, -3.0, 0.0],
            [0.0, 1.0, 0.0],
            Some((3.6, [n.x, n.y, 0.0])),
        );
        check(
            cone,
            [0.2, 3.0, 0.0],
            [0.0, -1.0, 0.0],
            Some((2.4, [n.x, n.y, 0.0])),
        );
        check(
            Primitive::Disk,
            [s, 1.0, s * 0.99],
            [0.0, -1.0, 0.0],
            Some((1.0, [0.0, 1.0, 0.0])),
        );
        check(Primitive::Disk, [0.8, 1.0, 0.8], [0.0, -1.0, 0.0], None);
        check(
            Primitive::Rectangle,
            [0.8, 1.0, 0.8],
            [0.0, -1.0, 0.0],
            Some((1.0, [0.0, 1.0, 0.0])),
        );
        let tri = Primitive::Triangle([DVec3::ZERO, DVec3::X, DVec3::Y], None);
        check(
            tri.clone(),
            [0.2, 0.2, -1.0],
            [0.0, 0.0, 1.0],
            Some((1.0, [0.0, 0.0, 1.0])),
        );
        check(tri, [0.6, 0.6, -1.0], [0.0, 0.0, 1.0], None);
    }

    #[test]
    fn test02_a_root_behind_t_min_gives_the_far_one() {
        // From the sphere's surface inwards: the near root (0) is excluded.
        check(
            Primitive::Sphere,
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 1.0],
            Some((2.0, [0.0, 0.0, 1.0])),
        );
    }
}
