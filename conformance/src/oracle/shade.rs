//! POV-Ray 3.7's classic illumination, re-derived in `f64` from its source (tag
//! `v3.7.0.10`, `source/backend/render/trace.cpp`; conformance/docs/oracle.md gives every
//! term with its location). One texture layer, no normal perturbation, no radiosity,
//! photons, media, iridescence, metallic or conserve_energy: the subset the catalog's
//! materials use (the scene format has no other finish terms).
//!
//! Where POV-Ray keeps a numerical tolerance for its own robustness, the oracle does
//! the exact thing instead (the point of a third opinion):
//!
//! - a secondary or shadow ray ignores only the surface it starts on: hits closer than
//!   [`SELF`] (1e-9, far above the f64 rounding of a hit point in a scene of size ~10 and
//!   far below any gap between surfaces in the catalog), where POV-Ray ignores every hit
//!   within `MIN_ISECT_DEPTH` (1e-4) and, on shadow rays, within `SMALL_TOLERANCE` and
//!   `SHADOW_TOLERANCE` (1e-3) of either end;
//! - colours are `f64` (POV-Ray's `COLC` is `float`).

use super::camera::Ray;
use super::intersect::Hit;
use super::world::{Finish, World};
use glam::DVec3;

/// Distance within which a ray's own starting surface is ignored.
pub const SELF: f64 = 1e-9;

/// POV-Ray's `EPSILON` (1e-10): the light-facing test and the ior-ratio test.
const EPSILON: f64 = 1e-10;

/// What one traced ray carries: its trace level, its weight (for `adc_bailout`) and the
/// interiors it is inside, innermost last (POV-Ray's `Ray::interiors`).
#[derive(Clone, Debug)]
pub struct Ticket {
    /// Surfaces hit so far (`TraceTicket::traceLevel`).
    pub level: u32,
    /// The ray's weight.
    pub weight: f64,
    /// Interiors the ray is inside, innermost last.
    pub interiors: Vec<usize>,
}

/// POV-Ray's greyscale (`GREY_SCALE`, source/backend/colour/colour.h).
fn greyscale(c: DVec3) -> f64 {
    0.297 * c.x + 0.589 * c.y + 0.114 * c.z
}

impl World {
    /// `Trace::TraceRay`: the colour a ray brings back, and its first hit.
    /// `continued` is a ray passed straight through a surface of unchanged ior, which does
    /// not use up a trace level.
    pub fn trace(&self, ray: &Ray, t: &Ticket, continued: bool, lo: f64) -> (DVec3, Option<Hit>) {
        if t.level >= self.max_trace_level || t.weight < self.adc_bailout {
            return (DVec3::ZERO, None);
        }
        let Some(hit) = self.closest(ray, lo, f64::INFINITY) else {
            return (self.background, None);
        };
        let level = if continued { t.level } else { t.level + 1 };
        let t = Ticket { level, ..t.clone() };
        (self.shade(ray, &hit, &t), Some(hit))
    }

    /// `Trace::ComputeLightedTexture` for one layer.
    fn shade(&self, ray: &Ray, hit: &Hit, t: &Ticket) -> DVec3 {
        let obj = &self.objects[hit.object];
        let m = &self.materials[obj.material];
        let d = ray.d;
        // ComputeTextureColour: the normal is flipped to face the ray.
        let n = if hit.n.dot(d) > 0.0 { -hit.n } else { hit.n };
        let p = m.color;
        // Pigment filter colour (`rgbTransm`) and opacity (`att = layCol.opacity()`).
        let fil = p * m.filter + DVec3::splat(m.transmit);
        let att = 1.0 - m.filter - m.transmit;
        let mut c = p * m.ambient * self.ambient_light * att + p * m.emission * att;
        if m.diffuse != 0.0 || m.specular != 0.0 || m.phong != 0.0 {
            for l in &self.lights {
                c += self.one_light(l, m, hit.p, d, n, att);
            }
        }
        // Transmission (`trans` gates it; w1 weights it).
        let trans = greyscale(fil).abs().min(1.0);
        let mut tir = false;
        if trans > self.adc_bailout {
            let w1 = fil.x.abs().max(fil.y.abs()).max(fil.z.abs());
            let weight = t.weight * w1;
            let (ior, inside) = self.ior_ratio(&t.interiors, obj.interior);
            let next = Ticket {
                level: t.level,
                weight,
                interiors: inside,
            };
            if (ior - 1.0).abs() < EPSILON {
                let r = Ray { o: hit.p, d };
                c += fil * self.trace(&r, &next, true, SELF).0;
            } else {
                // Heckbert's refraction (TraceRefractionRay), n = −D·N ≥ 0.
                let cos = -d.dot(n);
                let k = 1.0 + ior * ior * (cos * cos - 1.0);
                if k < 0.0 {
                    // Total internal reflection: the mirrored ray, with the incoming
                    // ray's interiors, added unfiltered; the finish's own reflection is
                    // then skipped.
                    tir = true;
                    let back = Ticket {
                        weight,
                        ..t.clone()
                    };
                    c += self.reflect(hit.p, d, n, &back);
                } else {
                    let dir = ior * d + (ior * cos - k.sqrt()) * n;
                    let r = Ray { o: hit.p, d: dir };
                    c += fil * self.trace(&r, &next, false, SELF).0;
                }
            }
        }
        // Reflection (ComputeReflectivity, type 0, min = max = `reflection`).
        if !tir && m.reflection != 0.0 {
            let back = Ticket {
                weight: t.weight * m.reflection,
                ..t.clone()
            };
            c += m.reflection * self.reflect(hit.p, d, n, &back);
        }
        c
    }

    /// `ComputeReflection`: the mirrored ray R = D − 2(D·N)N, normalised.
    fn reflect(&self, o: DVec3, d: DVec3, n: DVec3, t: &Ticket) -> DVec3 {
        let r = (d - 2.0 * d.dot(n) * n).normalize();
        self.trace(&Ray { o, d: r }, t, false, SELF).0
    }

    /// `ComputeRefraction`'s ratio of iors from the ray's interiors, and the interiors of
    /// the refracted ray.
    fn ior_ratio(&self, interiors: &[usize], this: usize) -> (f64, Vec<usize>) {
        let ior = |k: usize| self.ior_of(k);
        let mut inside = interiors.to_vec();
        let ratio = match interiors.last() {
            // Entering from the atmosphere (ior 1).
            None => {
                inside.push(this);
                1.0 / ior(this)
            }
            // Leaving the innermost object: into the next one out, or the atmosphere.
            Some(&last) if last == this => {
                inside.pop();
                ior(this) / inside.last().map_or(1.0, |&k| ior(k))
            }
            Some(&last) => {
                if let Some(at) = inside.iter().position(|&k| k == this) {
                    // Leaving an overlap: treated as no interface.
                    inside.remove(at);
                    1.0
                } else {
                    // Entering a new object from inside another.
                    inside.push(this);
                    ior(last) / ior(this)
                }
            }
        };
        (ratio, inside)
    }

    /// The ior of an interior (every object of an interior shares its material).
    fn ior_of(&self, interior: usize) -> f64 {
        let o = self.objects.iter().find(|o| o.interior == interior);
        o.map_or(1.0, |o| self.materials[o.material].ior)
    }

    /// `ComputeOneDiffuseLight` for a point light: diffuse, phong and specular.
    fn one_light(
        &self,
        l: &super::world::PointLight,
        m: &Finish,
        p: DVec3,
        d: DVec3,
        n: DVec3,
        att: f64,
    ) -> DVec3 {
        let to = l.position - p;
        let dist = to.length();
        let dir = to / dist;
        // Attenuate_Light (source/backend/lighting/point.cpp).
        let fade = match l.fade {
            Some((fd, fp)) if fp > 0.0 && fd.abs() >= EPSILON => 2.0 / (1.0 + (dist / fd).powf(fp)),
            Some((_, fp)) if fp > 0.0 => dist.powf(-fp),
            _ => 1.0,
        };
        let mut lc = l.color * fade;
        if n.dot(dir) < EPSILON {
            return DVec3::ZERO;
        }
        lc *= self.shadow(p, dir, dist);
        if lc.abs().max_element() <= EPSILON {
            return DVec3::ZERO;
        }
        let mut c = DVec3::ZERO;
        // ComputeDiffuseColour.
        if m.diffuse > 0.0 {
            let cos = n.dot(dir).abs();
            let i = if m.brilliance != 1.0 {
                cos.powf(m.brilliance)
            } else {
                cos
            };
            c += i * m.diffuse * att * m.color * lc;
        }
        // ComputePhongColour: the mirrored view ray against the light.
        if m.phong > 0.0 {
            let r = d - 2.0 * d.dot(n) * n;
            let cos = r.dot(dir);
            if cos > 0.0 && (m.phong_size < 60.0 || cos > 0.0008) {
                c += m.phong * cos.powf(m.phong_size) * lc;
            }
        }
        // ComputeSpecularColour: the half vector of −D and L; POV-Ray stores 1/roughness.
        if m.specular > 0.0 {
            let h = 0.5 * (-d + dir);
            let hl = h.length();
            if hl > 0.0 {
                let cos = h.dot(n) / hl;
                if cos > 0.0 {
                    c += m.specular * cos.powf(1.0 / m.roughness) * lc;
                }
            }
        }
        c
    }

    /// `TracePointLightShadowRay` and `ComputeShadowColour`: the light's filter between `p`
    /// and the light. An opaque blocker stops it; each surface of a transparent one
    /// multiplies it by `colour·filter + transmit`, and the ray goes on unrefracted.
    fn shadow(&self, p: DVec3, dir: DVec3, dist: f64) -> DVec3 {
        let ray = Ray { o: p, d: dir };
        let mut s = DVec3::ONE;
        let mut lo = SELF;
        while let Some(h) = self.closest(&ray, lo, dist) {
            let m = &self.materials[self.objects[h.object].material];
            if m.filter == 0.0 && m.transmit == 0.0 {
                return DVec3::ZERO;
            }
            s *= m.color * m.filter + DVec3::splat(m.transmit);
            lo = h.t + SELF;
        }
        s
    }
}
