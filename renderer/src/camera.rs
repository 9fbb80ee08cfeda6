//! The viewing model of DEVELOPERS.md, and the friendlier forms that convert into it.
//!
//! The user gives the view reference point r (VRP), the view-plane normal n (VPN), an up
//! vector (VUP) from which v is made orthogonal to n, and u = v × n completing a
//! left-handed u, v, n basis. M has rows u, v, n. The eye is at (0, 0, −E) in view
//! coordinates and the window `W_l..W_r × W_b..W_t` lies on the plane n = 0. Pixel (i, j)
//! samples `u_i = W_l + (i + ½)Δu`, `v_j = W_t − (j + ½)Δv` and its ray is
//! `eye + t·dir` with `eye = (0, 0, −E)M + r` and `dir = (u_i, v_j, E)M`.
//!
//! Everything here is computed in `f64` and converted once to the renderer's precision.

use crate::ray::Ray;
use crate::real::{vec3, Real, Vec3};
use glam::DVec3;

/// Why a camera is degenerate.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A vector that must have a direction has length 0 (or is not finite).
    #[error("{0} is a zero-length or non-finite vector")]
    ZeroVector(&'static str),
    /// The up vector is parallel to the view direction.
    #[error("the up vector is parallel to the view-plane normal")]
    UpParallel,
    /// The eye distance is not positive.
    #[error("the eye distance E must be > 0 (got {0})")]
    EyeDistance(f64),
    /// The window has no area.
    #[error("the window is empty (W_l < W_r and W_b < W_t are required)")]
    EmptyWindow,
    /// The pixel array has no pixels.
    #[error("the pixel array must have at least one column and one row")]
    EmptyPixelArray,
    /// The field of view is outside (0°, 180°).
    #[error("the field of view must be in (0, 180) degrees (got {0})")]
    FieldOfView(f64),
    /// POV-Ray style vectors that the viewing model cannot represent.
    #[error("{0}")]
    NotOrthogonal(&'static str),
    /// A value is not finite.
    #[error("{0} is not finite")]
    NonFinite(&'static str),
}

/// The window on the view plane, in view units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// W_l.
    pub left: f64,
    /// W_r.
    pub right: f64,
    /// W_b.
    pub bottom: f64,
    /// W_t.
    pub top: f64,
}

/// The viewing model's inputs, in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewingModel {
    /// View reference point r.
    pub vrp: DVec3,
    /// View-plane normal.
    pub vpn: DVec3,
    /// Up vector.
    pub vup: DVec3,
    /// Eye distance E > 0.
    pub e: f64,
    /// Window on the plane n = 0.
    pub window: Window,
    /// Pixel columns.
    pub cols: u32,
    /// Pixel rows.
    pub rows: u32,
}

/// Which angle a field of view gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxis {
    /// The angle spans the window's width.
    Horizontal,
    /// The angle spans the window's height.
    Vertical,
}

/// The orthonormal view basis `u, v, n` in `f64`: the rows of M.
pub fn view_basis(vpn: DVec3, vup: DVec3) -> Result<[DVec3; 3], CameraError> {
    let nl = vpn.length();
    if !(nl > 0.0 && nl.is_finite()) {
        return Err(CameraError::ZeroVector("the view-plane normal (vpn)"));
    }
    let ul = vup.length();
    if !(ul > 0.0 && ul.is_finite()) {
        return Err(CameraError::ZeroVector("the up vector (vup)"));
    }
    let n = vpn / nl;
    let up = vup / ul;
    let v_raw = up - n * up.dot(n);
    // sin of the angle between up and n; below ~1e-9 v is all rounding noise.
    if v_raw.length() < 1e-9 {
        return Err(CameraError::UpParallel);
    }
    let v = v_raw.normalize();
    let u = v.cross(n);
    Ok([u, v, n])
}

impl ViewingModel {
    /// Converts a look-at camera with a field of view (square pixels) into the viewing
    /// model. The eye is `from`, E = 1 and the window is centred.
    pub fn look_at(
        from: DVec3,
        at: DVec3,
        up: DVec3,
        fov_degrees: f64,
        axis: FovAxis,
        cols: u32,
        rows: u32,
    ) -> Result<Self, CameraError> {
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            return Err(CameraError::FieldOfView(fov_degrees));
        }
        if cols == 0 || rows == 0 {
            return Err(CameraError::EmptyPixelArray);
        }
        if !from.is_finite() {
            return Err(CameraError::NonFinite("from"));
        }
        let dir = at - from;
        if !(dir.length() > 0.0) {
            return Err(CameraError::ZeroVector("the look-at direction (at − from)"));
        }
        let [_, _, n] = view_basis(dir, up)?;
        let half = (fov_degrees.to_radians() * 0.5).tan();
        let aspect = cols as f64 / rows as f64;
        let (hw, hh) = match axis {
            FovAxis::Horizontal => (half, half / aspect),
            FovAxis::Vertical => (half * aspect, half),
        };
        Ok(ViewingModel {
            vrp: from + n,
            vpn: dir,
            vup: up,
            e: 1.0,
            window: Window {
                left: -hw,
                right: hw,
                bottom: -hh,
                top: hh,
            },
            cols,
            rows,
        })
    }

    /// Converts a POV-Ray style camera (location, direction, right, up, all explicit) into
    /// the viewing model. POV-Ray traces pixel (i, j) along
    /// `direction + x·right + y·up` with `x = (i+½)/W − ½`, `y = ½ − (j+½)/H`, from
    /// `location` (source/backend/render/tracepixel.cpp). `right` and `up` must be
    /// perpendicular; `direction` may be oblique (an off-centre window).
    pub fn povray(
        location: DVec3,
        direction: DVec3,
        right: DVec3,
        up: DVec3,
        cols: u32,
        rows: u32,
    ) -> Result<Self, CameraError> {
        if cols == 0 || rows == 0 {
            return Err(CameraError::EmptyPixelArray);
        }
        if !location.is_finite() {
            return Err(CameraError::NonFinite("location"));
        }
        let (rl, ul) = (right.length(), up.length());
        if !(rl > 0.0 && rl.is_finite()) {
            return Err(CameraError::ZeroVector("right"));
        }
        if !(ul > 0.0 && ul.is_finite()) {
            return Err(CameraError::ZeroVector("up"));
        }
        if !(direction.length() > 0.0 && direction.is_finite()) {
            return Err(CameraError::ZeroVector("direction"));
        }
        let u = right / rl;
        let v = up / ul;
        if u.dot(v).abs() > 1e-9 {
            return Err(CameraError::NotOrthogonal(
                "right and up must be perpendicular for the viewing model",
            ));
        }
        let n = u.cross(v);
        let e = direction.dot(n);
        if !(e > 0.0) {
            return Err(CameraError::EyeDistance(e));
        }
        let (uc, vc) = (direction.dot(u), direction.dot(v));
        Ok(ViewingModel {
            vrp: location + n * e,
            vpn: n,
            vup: v,
            e,
            window: Window {
                left: uc - 0.5 * rl,
                right: uc + 0.5 * rl,
                bottom: vc - 0.5 * ul,
                top: vc + 0.5 * ul,
            },
            cols,
            rows,
        })
    }

    /// The inverse conversion: POV-Ray `location, direction, right, up` for this camera.
    /// Exact for asymmetric windows and non-square pixels.
    pub fn to_povray(&self) -> Result<[DVec3; 4], CameraError> {
        let [u, v, n] = view_basis(self.vpn, self.vup)?;
        let w = self.window;
        let uc = 0.5 * (w.left + w.right);
        let vc = 0.5 * (w.bottom + w.top);
        let eye = self.vrp - n * self.e;
        Ok([
            eye,
            u * uc + v * vc + n * self.e,
            u * (w.right - w.left),
            v * (w.top - w.bottom),
        ])
    }
}

/// A validated camera in renderer precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Basis vectors (rows of M), in `f64` for exact conversions and checks.
    pub basis64: [DVec3; 3],
    /// The eye in world coordinates, `f64`.
    pub eye64: DVec3,
    /// The model this camera was built from.
    pub model: ViewingModel,
    /// Where render space's origin lies in world coordinates (see [`Camera::rebased`]).
    origin: DVec3,
    u: Vec3,
    v: Vec3,
    n: Vec3,
    eye: Vec3,
}

impl Camera {
    /// Validates a viewing model.
    pub fn new(model: ViewingModel) -> Result<Self, CameraError> {
        let w = model.window;
        for (name, x) in [
            ("vrp", model.vrp.x),
            ("vrp", model.vrp.y),
            ("vrp", model.vrp.z),
            ("window", w.left),
            ("window", w.right),
            ("window", w.bottom),
            ("window", w.top),
        ] {
            if !x.is_finite() {
                return Err(CameraError::NonFinite(name));
            }
        }
        if !(model.e > 0.0 && model.e.is_finite()) {
            return Err(CameraError::EyeDistance(model.e));
        }
        if !(w.left < w.right && w.bottom < w.top) {
            return Err(CameraError::EmptyWindow);
        }
        if model.cols == 0 || model.rows == 0 {
            return Err(CameraError::EmptyPixelArray);
        }
        let basis64 = view_basis(model.vpn, model.vup)?;
        let [u, v, n] = basis64;
        let eye64 = model.vrp - n * model.e;
        Ok(Camera {
            basis64,
            eye64,
            model,
            origin: DVec3::ZERO,
            u: vec3(u),
            v: vec3(v),
            n: vec3(n),
            eye: vec3(eye64),
        })
    }

    /// The same camera in a render space whose origin is the world point `origin`
    /// (computed in `f64`, then converted): rays start at `eye64 − origin`, which is
    /// exactly 0 when the origin is the eye. The model stays in world coordinates.
    pub fn rebased(&self, origin: DVec3) -> Camera {
        Camera {
            origin,
            eye: vec3(self.eye64 - origin),
            ..*self
        }
    }

    /// Where render space's origin lies in world coordinates (0 unless rebased).
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Pixel columns.
    pub fn cols(&self) -> u32 {
        self.model.cols
    }

    /// Pixel rows.
    pub fn rows(&self) -> u32 {
        self.model.rows
    }

    /// The angle one pixel subtends at the eye at the window's centre (radians): the
    /// finer of its width and its height over E.
    pub fn pixel_angle(&self) -> f64 {
        let (m, w) = (&self.model, &self.model.window);
        let px = ((w.right - w.left) / m.cols.max(1) as f64)
            .abs()
            .min(((w.top - w.bottom) / m.rows.max(1) as f64).abs());
        px / m.e
    }

    /// The eye, in render space (world coordinates minus [`Camera::origin`]).
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The basis u, v, n (rows of M) in renderer precision.
    pub fn basis(&self) -> [Vec3; 3] {
        [self.u, self.v, self.n]
    }

    /// The window point (u, v) of the continuous pixel position (x, y): x runs over
    /// `0..cols` left to right, y over `0..rows` top to bottom. Pixel (i, j)'s centre is
    /// `(i + ½, j + ½)`.
    pub fn window_point(&self, x: f64, y: f64) -> (f64, f64) {
        let w = self.model.window;
        let du = (w.right - w.left) / self.model.cols as f64;
        let dv = (w.top - w.bottom) / self.model.rows as f64;
        (w.left + x * du, w.top - y * dv)
    }

    /// The ray through the continuous pixel position (x, y).
    #[inline]
    pub fn ray_at(&self, x: f64, y: f64) -> Ray {
        let (ui, vj) = self.window_point(x, y);
        let (ui, vj) = (ui as Real, vj as Real);
        Ray::new(
            self.eye,
            self.u * ui + self.v * vj + self.n * self.model.e as Real,
        )
    }

    /// The ray through the centre of pixel (i, j).
    #[inline]
    pub fn pixel_ray(&self, i: u32, j: u32) -> Ray {
        self.ray_at(i as f64 + 0.5, j as f64 + 0.5)
    }
}
