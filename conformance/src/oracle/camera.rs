//! The oracle's camera rays, derived from the viewing model as the scene format documents it
//! (renderer/docs/scene-format.md, `[camera.view]`), in `f64`, without the renderer's camera
//! code.
//!
//! With n the unit view-plane normal, v the unit part of the up vector orthogonal to n and
//! u = v × n, pixel position (x, y) (x to the right, y down, pixel (i, j)'s centre at
//! (i + ½, j + ½)) traces from the eye `r − E·n` along
//!
//! ```text
//! dir = (W_l + x·(W_r − W_l)/cols)·u + (W_t − y·(W_t − W_b)/rows)·v + E·n
//! ```
//!
//! normalised, as POV-Ray normalises its camera rays (so t is a distance everywhere).

use glam::DVec3;
use renderer::camera::ViewingModel;

/// A camera ray: origin and unit direction.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub o: DVec3,
    /// Unit direction.
    pub d: DVec3,
}

/// The viewing model's eye, basis and window.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    eye: DVec3,
    u: DVec3,
    v: DVec3,
    n: DVec3,
    model: ViewingModel,
}

impl Camera {
    /// The camera of a viewing model (already validated by the scene parser).
    pub fn new(model: &ViewingModel) -> Camera {
        let n = model.vpn.normalize();
        let up = model.vup.normalize();
        let v = (up - n * up.dot(n)).normalize();
        let u = v.cross(n);
        Camera {
            eye: model.vrp - model.e * n,
            u,
            v,
            n,
            model: *model,
        }
    }

    /// The ray through the continuous pixel position (x, y).
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let w = &self.model.window;
        let ui = w.left + x * (w.right - w.left) / self.model.cols as f64;
        let vj = w.top - y * (w.top - w.bottom) / self.model.rows as f64;
        let d = ui * self.u + vj * self.v + self.model.e * self.n;
        Ray {
            o: self.eye,
            d: d.normalize(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use renderer::camera::Window;

    #[test]
    fn test01_the_centre_ray_runs_along_the_view_plane_normal() {
        let model = ViewingModel {
            vrp: DVec3::new(1.0, 2.0, 3.0),
            vpn: DVec3::new(0.0, 0.0, 2.0),
            vup: DVec3::new(0.0, 5.0, 1.0),
            e: 2.0,
            window: Window {
                left: -1.0,
                right: 1.0,
                bottom: -0.75,
                top: 0.75,
            },
            cols: 4,
            rows: 3,
        };
        let c = Camera::new(&model);
        let r = c.ray(2.0, 1.5);
        assert!((r.o - DVec3::new(1.0, 2.0, 1.0)).length() < 1e-15);
        assert!((r.d - DVec3::Z).length() < 1e-15);
        // The top-left corner: u = v × n = y × z = x, so left is −x, top is +y.
        let r = c.ray(0.0, 0.0);
        let want = DVec3::new(-1.0, 0.75, 2.0).normalize();
        assert!((r.d - want).length() < 1e-15, "{:?}", r.d);
    }
}
