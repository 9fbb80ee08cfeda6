//! The BSDFs at a surface: Lambertian `diffuse`, smooth `conductor` (a mirror) and smooth
//! `dielectric` (Fresnel reflection and refraction), evaluated and sampled, and the
//! surface record oriented for shading.

use crate::light::frame;
use crate::real::Vec3;
use crate::sampler::{cos_sin_turn, PixelSampler};
use crate::scene::{Color, Material, MaterialModel};
use std::f64::consts::PI;

/// Unpolarized Fresnel reflectance of a smooth dielectric for `cos_i` (> 0 on the side the
/// light comes from) and relative ior `eta` = η_transmitted / η_incident. Returns
/// (F, cos_t); F = 1 on total internal reflection.
pub(super) fn fresnel(cos_i: f64, eta: f64) -> (f64, f64) {
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

pub(super) fn dv(v: Vec3) -> glam::DVec3 {
    crate::real::dvec3(v)
}

pub(super) fn rv(v: glam::DVec3) -> Vec3 {
    crate::real::vec3(v)
}

pub(super) fn rgb(c: Color) -> glam::DVec3 {
    glam::DVec3::new(c.x as f64, c.y as f64, c.z as f64)
}

/// A sampled BSDF direction.
pub(super) struct BsdfSample {
    pub(super) dir: glam::DVec3,
    /// f·|cos|/pdf (or the delta weight).
    pub(super) weight: glam::DVec3,
    /// Solid-angle density; 0 for delta lobes.
    pub(super) pdf: f64,
    /// Relative ior crossed (η_t/η_i) for refraction, else 1 (for Russian roulette).
    pub(super) eta: f64,
    /// A dielectric's reflection lobe (which `eta == 1` does not tell: an ior of 1, the
    /// default, refracts with η = 1 and a reflectance F that rounds to a tiny positive).
    pub(super) reflected: bool,
}

impl BsdfSample {
    /// A diffuse continuation in `dir`, whose lobe gives `f` (the BSDF times the cosine)
    /// and which was drawn with solid-angle density `pdf` (> 0): the cosine lobe's own
    /// ([`Surface::sample`]) or the specular guides' mixture
    /// (`PhysicalIntegrator::sample_guided`).
    #[inline(always)]
    pub(super) fn diffuse(dir: glam::DVec3, f: glam::DVec3, pdf: f64) -> BsdfSample {
        BsdfSample {
            dir,
            weight: f / pdf,
            pdf,
            eta: 1.0,
            reflected: false,
        }
    }
}

/// The mirror direction of `wo` about unit `n`, given `cos_i = n·wo`: the sampled
/// reflection of the conductor and the dielectric, and the ray `reflected_emission`
/// traces (the same bits, so it meets what the sampled reflection meets).
#[inline(always)]
pub(super) fn mirror(n: glam::DVec3, cos_i: f64, wo: glam::DVec3) -> glam::DVec3 {
    n * (2.0 * cos_i) - wo
}

/// A cosine-weighted direction about unit `n` from the 2D sample `u`.
#[inline(always)]
pub(super) fn cosine_dir(n: glam::DVec3, (u1, u2): (f64, f64)) -> glam::DVec3 {
    let r = u1.sqrt();
    let (cos_phi, sin_phi) = cos_sin_turn(u2);
    let (t, b) = frame(n);
    let local_z = (1.0 - u1).max(0.0).sqrt();
    t * (r * cos_phi) + b * (r * sin_phi) + n * local_z
}

/// The surface at a hit, oriented for shading.
pub(super) struct Surface<'a> {
    pub(super) p: Vec3,
    pub(super) err: Vec3,
    /// Unit geometric normal, outward.
    pub(super) ng: glam::DVec3,
    /// Unit shading normal, outward.
    pub(super) ns: glam::DVec3,
    pub(super) m: &'a Material,
    pub(super) object_id: u32,
    pub(super) n_world: Vec3,
}

impl Surface<'_> {
    /// The unit shading normal on the side of `wo` (the BSDFs are two-sided).
    #[inline(always)]
    pub(super) fn facing(&self, wo: glam::DVec3) -> glam::DVec3 {
        let side = if self.ns.dot(wo) >= 0.0 { 1.0 } else { -1.0 };
        self.ns * side
    }

    pub(super) fn is_delta(&self) -> bool {
        self.m.model != MaterialModel::Diffuse
    }

    /// Lambertian f·cos for incoming `wo` (towards the viewer) and `wi` (towards the
    /// light): zero unless both are on the same side of the surface (two-sided).
    pub(super) fn eval_diffuse(&self, wo: glam::DVec3, wi: glam::DVec3) -> (glam::DVec3, f64) {
        let (co, ci) = (self.ns.dot(wo), self.ns.dot(wi));
        if co * ci <= 0.0 || self.ng.dot(wo) * self.ng.dot(wi) <= 0.0 {
            return (glam::DVec3::ZERO, 0.0);
        }
        let cos = ci.abs();
        (rgb(self.m.color) * (cos / PI), cos / PI)
    }

    /// A dielectric's Fresnel split for the viewer at `wo`, `n` the shading normal on its
    /// side: cos θ_i, the relative ior crossed (η_t/η_i), the reflectance F and cos θ_t.
    #[inline(always)]
    pub(super) fn dielectric(&self, n: glam::DVec3, wo: glam::DVec3) -> (f64, f64, f64, f64) {
        let cos_i = n.dot(wo);
        // Outside when the viewer is on the outward side of the geometry.
        let outside = self.ng.dot(wo) > 0.0;
        let eta = if outside {
            self.m.ior as f64
        } else {
            1.0 / self.m.ior as f64
        };
        let (f, cos_t) = fresnel(cos_i, eta);
        (cos_i, eta, f, cos_t)
    }

    #[inline(always)]
    pub(super) fn sample(&self, wo: glam::DVec3, s: &mut PixelSampler) -> Option<BsdfSample> {
        let n = self.facing(wo);
        match self.m.model {
            MaterialModel::Diffuse => {
                let dir = cosine_dir(n, s.next_2d());
                let (f, pdf) = self.eval_diffuse(wo, dir);
                if pdf <= 0.0 {
                    return None;
                }
                Some(BsdfSample::diffuse(dir, f, pdf))
            }
            MaterialModel::Conductor => {
                s.next_1d();
                Some(BsdfSample {
                    dir: mirror(n, n.dot(wo), wo),
                    weight: rgb(self.m.color),
                    pdf: 0.0,
                    eta: 1.0,
                    reflected: false,
                })
            }
            MaterialModel::Dielectric => {
                let u = s.next_1d();
                let (cos_i, eta, f, cos_t) = self.dielectric(n, wo);
                if u < f {
                    Some(BsdfSample {
                        dir: mirror(n, cos_i, wo),
                        weight: glam::DVec3::ONE,
                        pdf: 0.0,
                        eta: 1.0,
                        reflected: true,
                    })
                } else {
                    let dir = -wo / eta + n * (cos_i / eta - cos_t);
                    // Radiance is compressed into a smaller solid angle when entering a
                    // denser medium: the transmitted weight is 1/η².
                    Some(BsdfSample {
                        dir,
                        weight: glam::DVec3::splat(1.0 / (eta * eta)),
                        pdf: 0.0,
                        eta,
                        reflected: false,
                    })
                }
            }
            MaterialModel::Classic => None,
        }
    }
}
