//! Whether the build's precision resolves an instance whose own size is huge next to the
//! distances the camera sees, and what the builder does about it (renderer/docs/
//! precision.md, "Scale against view").
//!
//! An instance's intersection works in its object space, where the numbers it handles
//! near the surface the camera sees have the size R (in render-space units: the scale
//! times the object-space distance of the eye from the origin, at least 1) and must
//! resolve a fraction τ of the distance D from the eye to that surface. Rounding
//! moves the surface by about 4·u·R (u = 2⁻ᵖ, p bits of significand: the ray's
//! object-space origin and the quadratic's or the slab's cancelling term), so the
//! intersection needs `bits = log2(4·R / (τ·D))` bits. τ is the finer of 2⁻¹⁷ (the
//! relative depth the comparisons check, 1e-5, with margin) and 1/64 of the camera's
//! pixel angle (the smallest feature it resolves at D, with margin).

use crate::aggregate::Shape;
use crate::real::Real;
use crate::shapes::anchored::{Anchored, Kind};
use crate::shapes::Mesh;
use crate::transform::Affine64;
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// Bits of significand of the build's precision: 24 in f32, 53 in f64.
pub const BUILD_BITS: f64 = Real::MANTISSA_DIGITS as f64;

/// Bits of significand of f64, which the mixed-precision terms have.
pub const MIXED_BITS: f64 = f64::MANTISSA_DIGITS as f64;

/// The relative depth an intersection must resolve, given the camera's pixel angle
/// (radians): the finer of 2⁻¹⁷ and 1/64 of a pixel.
pub fn tolerance(pixel_angle: f64) -> f64 {
    (pixel_angle / 64.0).min(2f64.powi(-17))
}

/// An instance the build's precision cannot resolve, where the scene file places it.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleNote {
    /// The scene file.
    pub file: String,
    /// Line and column of the object (1-based).
    pub line: usize,
    /// Column.
    pub column: usize,
    /// The object's field path, such as `objects[0]`.
    pub field: String,
    /// Bits of significand its intersection needs.
    pub bits: f64,
    /// Its object space's size against its distance from the eye (R/D).
    pub ratio: f64,
    /// Whether it is intersected in mixed precision (else the build cannot resolve it).
    pub mixed: bool,
    /// Whether mixed precision was turned off (`render.mixed_precision = false`).
    pub mixed_off: bool,
}

impl std::fmt::Display for ScaleNote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = crate::real::PRECISION;
        write!(
            f,
            "{}:{}:{}: {}: ",
            self.file, self.line, self.column, self.field
        )?;
        let why = format!(
            "its size is {:.1e} times its distance from the eye, so its intersection needs {:.0} \
bits of precision, more than the {BUILD_BITS} of the {p} build",
            self.ratio, self.bits
        );
        if self.mixed {
            write!(
                f,
                "note: {why}; it is intersected in mixed precision (the terms that cancel in f64), \
which resolves it (renderer/docs/precision.md, \"Scale against view\")"
            )
        } else {
            let fix = if self.bits <= MIXED_BITS && self.mixed_off {
                "render.mixed_precision = true (the default) or the f64 build (--features f64) would resolve it"
            } else if self.bits <= MIXED_BITS {
                "the f64 build (--features f64) would resolve it"
            } else {
                "not even the f64 build would: bring the camera farther from it, or model the part \
the camera sees at a smaller scale"
            };
            let not_mixed = if self.mixed_off {
                "render.mixed_precision is off"
            } else {
                "mixed precision cannot take it (a cone, a definition or an emitter, or more than \
53 bits)"
            };
            write!(
                f,
                "warning: {why}, and {not_mixed}; depths on it may be off by about {:.0e} of their \
distance; {fix} (renderer/docs/precision.md, \"Scale against view\")",
                self.ratio * 2f64.powi(-(BUILD_BITS as i32))
            )
        }
    }
}

/// What the estimate found for one instance.
#[derive(Clone, Debug)]
pub struct Need {
    /// Bits of significand its intersection needs.
    pub bits: f64,
    /// R/D: the size its object space handles against the distance to its surface.
    pub ratio: f64,
    /// The surface point nearest the eye, in object space (the anchor of mixed precision).
    pub anchor: DVec3,
}

/// The estimate for `shape` placed by `xf` (render space), seen from `eye` (render space)
/// with a relative depth tolerance `tau`. `inv` is the linear part of `xf`'s inverse, as
/// the instance stores it (in the build's precision, which is enough for an estimate and
/// costs the build no second inversion).
pub fn need(shape: &Shape, xf: &Affine64, inv: &DMat3, eye: DVec3, tau: f64) -> Need {
    let o = *inv * (eye - xf.d);
    let s = [
        xf.m.x_axis.length(),
        xf.m.y_axis.length(),
        xf.m.z_axis.length(),
    ];
    let smax = s[0].max(s[1]).max(s[2]);
    // The distance from the eye to an object point, in render space.
    let dist = |p: DVec3| (xf.point(p) - eye).length();
    // Per-term ratio: the size of a term against the larger of the distance to the
    // surface and the term's own distance to where it cancels.
    let term = |size: f64, gap: f64, d: f64| size / d.max(gap).max(size * 2f64.powi(-60));
    let (ratio, anchor) = match shape {
        Shape::Sphere => {
            let r = o.length();
            let a = if r > 0.0 { o / r } else { DVec3::Y };
            let d = dist(a);
            (term(smax * r.max(1.0), s_min(&s) * (r - 1.0).abs(), d), a)
        }
        Shape::Cube => {
            let a = box_point(o, DVec3::splat(-1.0), DVec3::splat(1.0));
            let d = dist(a);
            let mut ratio: f64 = 1.0;
            for k in 0..3 {
                ratio = ratio.max(term(
                    s[k] * o[k].abs().max(1.0),
                    s[k] * (o[k].abs() - 1.0).abs(),
                    d,
                ));
            }
            (ratio, a)
        }
        Shape::Cylinder { .. } | Shape::Cone { .. } => {
            let r = o.x.hypot(o.z);
            let (ax, az) = if r > 0.0 {
                (o.x / r, o.z / r)
            } else {
                (1.0, 0.0)
            };
            let a = DVec3::new(ax, o.y.clamp(-1.0, 1.0), az);
            let d = dist(a);
            let sr = s[0].max(s[2]);
            let radial = term(sr * r.max(1.0), s[0].min(s[2]) * (r - 1.0).abs(), d);
            let axial = term(s[1] * o.y.abs().max(1.0), s[1] * (o.y.abs() - 1.0).abs(), d);
            (radial.max(axial), a)
        }
        // The surface passes through the object-space origin: the term that decides t
        // (the eye's height over the plane) is itself the distance; in-plane terms only
        // move the rim by ε of the size.
        Shape::Plane | Shape::Disk | Shape::Rectangle => (1.0, DVec3::new(o.x, 0.0, o.z)),
        Shape::Triangle(_) | Shape::Mesh(_) | Shape::Group(_) | Shape::Anchored(_) => {
            let b = shape.bounds();
            let (lo, hi) = (crate::real::dvec3(b.min), crate::real::dvec3(b.max));
            let a = box_point(o, lo, hi);
            let reach = lo.abs().max(hi.abs()).length().max(o.length());
            (term(smax * reach.max(1e-300), 0.0, dist(a)), a)
        }
    };
    let ratio = ratio.max(1.0);
    Need {
        bits: (4.0 * ratio / tau).log2(),
        ratio,
        anchor,
    }
}

fn s_min(s: &[f64; 3]) -> f64 {
    s[0].min(s[1]).min(s[2])
}

/// The point of the box [lo, hi] nearest `o`; from inside, the nearest point of its
/// surface.
fn box_point(o: DVec3, lo: DVec3, hi: DVec3) -> DVec3 {
    let mut p = o.clamp(lo, hi);
    if p == o {
        // Inside: move along the axis whose face is nearest.
        let mut best = (f64::INFINITY, 0, 0.0);
        for k in 0..3 {
            for f in [lo[k], hi[k]] {
                if (o[k] - f).abs() < best.0 {
                    best = ((o[k] - f).abs(), k, f);
                }
            }
        }
        p[best.1] = best.2;
    }
    p
}

/// The shape and transform that intersect `shape` (placed by `xf`) about `anchor` in
/// mixed precision, or `None` when the shape has no such form (a cone, a definition).
/// A sphere, cube or cylinder becomes [`Shape::Anchored`]; a triangle or a mesh gets its
/// vertices moved by −anchor in f64 and rounded once (a mesh is then its own copy).
/// The transform takes the shift: `xf ∘ translate(anchor)`, composed in f64.
pub fn anchored(shape: &Shape, xf: &Affine64, anchor: DVec3) -> Option<(Shape, Affine64)> {
    let shifted = xf.compose(&Affine64::translate(anchor));
    let kind = |kind| Shape::Anchored(Box::new(Anchored { kind, a: anchor }));
    let shape = match shape {
        Shape::Sphere => kind(Kind::Sphere),
        Shape::Cube => kind(Kind::Cube),
        Shape::Cylinder { capped } => kind(Kind::Cylinder { capped: *capped }),
        Shape::Triangle(t) => {
            let mut t = t.as_ref().clone();
            t.p = t.p.map(|p| move_by(p, anchor));
            Shape::Triangle(Box::new(t))
        }
        Shape::Mesh(m) => {
            let positions = m.positions.iter().map(|&p| move_by(p, anchor)).collect();
            let mesh = Mesh::new(
                positions,
                m.normals.clone(),
                m.uvs.clone(),
                m.triangles_as_given(),
            )
            .ok()?;
            Shape::Mesh(Arc::new(mesh))
        }
        _ => return None,
    };
    Some((shape, shifted))
}

/// `p − anchor` in f64, rounded once.
fn move_by(p: crate::real::Vec3, anchor: DVec3) -> crate::real::Vec3 {
    crate::real::vec3(crate::real::dvec3(p) - anchor)
}
