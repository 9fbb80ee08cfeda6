//! Light paths for the caustics seen directly.
//!
//! A camera path that meets a diffuse surface first and then one or more mirror or glass
//! surfaces before it hits an area light (camera → D → S⁺ → light) finds that light only
//! by its continuation's luck: next-event estimation cannot see a light through glass.
//! Such paths are the caustics seen directly (the bright patch a glass sphere focuses on
//! the floor), and their noise was most of the glass scene's error against Mitsuba.
//!
//! With `render.light_paths = r` (per camera sample), `r · width · height · spp` paths
//! start on the area lights instead, aimed at the spheres around the specular objects
//! (guide.rs's balls), follow the specular surfaces they meet, and at the first diffuse
//! surface are joined to the eye and added to the pixel they project to. The camera paths
//! leave exactly these paths out (their emission weighs 0 when the path so far is camera
//! → D → S⁺ and the light is an area light), so each path of the image is counted by one
//! of the two estimators: the expectation is unchanged. The partition is exact only when
//! every specular surface lies in a ball and reflects about its geometric normal (no
//! specular triangle or mesh, whose interpolated normals would need a correction at each
//! specular vertex), and no light lies in a ball; otherwise the light paths are off.
//! (Every camera here is a pinhole, which the connection to the eye assumes.)
//!
//! The estimate: a light path with throughput β (emitted radiance × cos / the densities of
//! its point and direction, × the specular weights) reaching the diffuse point x from the
//! direction ω_i, with the eye at distance d from x and the window at E in front of the
//! eye, adds to its pixel
//!
//!   β · f_r · |n_s·ω_i| · |n_g·ω_e| / |n_g·ω_i| · E² d / (a_p (n·(x − eye))³) / N,
//!
//! where a_p is a pixel's area on the window and N the number of light paths: a pixel's
//! value is the mean radiance over its window area, and a window area dA is E²/cos³θ dω at
//! the eye, while dω = |n_g·ω_e| dA_x / d² at x. A refraction leaves β as it was (weight
//! 1 for the lobe chosen with its probability): β carries power, which crossing an
//! interface keeps, while the camera path's 1/η² is radiance's change of units (η²·cos
//! dA dω is the same on both sides of the interface, so the two agree; pbrt's
//! "importance" transport mode). A closed object's two crossings would hide an error
//! here (η² and 1/η² cancel); a single interface does not (renderer/tests/physical.rs
//! test08).
//!
//! Output stays deterministic: the paths are traced in chunks in parallel, each chunk's
//! contributions kept in order in its own buffer, and the buffers added to the image in
//! chunk order.

use super::bsdf::{dv, rgb, rv};
use super::guide::{specular_balls, AtVertex, Ball, Pick, MAX_GUIDES, SHARE};
use super::vertex::Tracer;
use crate::image::{add_moment_products, MOMENT_PAIRS};
use crate::real::Real;
use crate::sampler::PixelSampler;
use crate::scene::{Integrator, MaterialModel, Scene};
use rayon::prelude::*;

/// Light paths a chunk traces (one rayon job).
const CHUNK: u64 = 1024;
/// Chunks traced between two merges into the image (their buffers are kept for reuse).
const GROUP: usize = 64;
/// Most light paths a render traces.
const MAX_PATHS: u64 = 1 << 31;
/// What keys the light paths' samples (a "pixel" no camera sample uses).
const LIGHT_KEY: u64 = u64::MAX - 0x11_9a7b;

/// What the light paths need, fixed for a render.
pub(super) struct LightPaths {
    balls: Vec<Ball>,
    eye: glam::DVec3,
    basis: [glam::DVec3; 3],
    e: f64,
    left: f64,
    top: f64,
    /// A pixel's width and height on the window.
    du: f64,
    dv: f64,
    cols: u32,
    rows: u32,
    /// Most specular vertices between the light and the diffuse one (`max_depth − 2`).
    max_specular: u32,
    ratio: f64,
}

/// The light paths' sums over a render: per pixel, the RGB sum of the contributions and,
/// when asked for, the sums of their products (RR, GG, BB, RG, RB, GB); the paths traced,
/// and the contributions left out for being non-finite.
pub(crate) struct LightImage {
    pub sum: Vec<f64>,
    pub sq: Option<Vec<f64>>,
    pub paths: u64,
    pub non_finite: usize,
}

impl LightPaths {
    /// The light paths of `scene`, when asked for and exact for it (module docs).
    pub(super) fn new(scene: &Scene) -> Option<LightPaths> {
        let s = &scene.settings;
        if s.integrator != Integrator::Path
            || !(s.light_paths > 0.0)
            || s.max_depth < 3
            || scene.area_lights.is_empty()
        {
            return None;
        }
        let (mut balls, complete) = specular_balls(scene);
        if !complete || balls.is_empty() || balls.len() > MAX_GUIDES {
            return None;
        }
        // A sphere is taken for one when its transform is a similarity to 1e-5
        // (light::sphere_ball): grown a little, its ball holds the slightly uneven one.
        for b in &mut balls {
            b.radius *= 1.0 + 1e-4;
        }
        // Every light outside every ball: the cones seen from a light point are then
        // every direction that can meet a specular surface first.
        for light in &scene.area_lights {
            let (lo, hi) = (dv(light.bounds.min), dv(light.bounds.max));
            for ball in &balls {
                let nearest = ball.centre.clamp(lo, hi);
                if !((nearest - ball.centre).length() > ball.radius) {
                    return None;
                }
            }
        }
        let cam = &scene.camera;
        let m = &cam.model;
        Some(LightPaths {
            balls,
            eye: cam.eye64 - cam.origin(),
            basis: cam.basis64,
            e: m.e,
            left: m.window.left,
            top: m.window.top,
            du: (m.window.right - m.window.left) / m.cols as f64,
            dv: (m.window.top - m.window.bottom) / m.rows as f64,
            cols: m.cols,
            rows: m.rows,
            max_specular: s.max_depth - 2,
            ratio: s.light_paths,
        })
    }

    /// The pixel `x` (render space) projects to, the factor E² d / (a_p (n·(x − eye))³)
    /// of the module docs, the unit direction from `x` to the eye and the distance.
    #[inline]
    fn project(&self, x: glam::DVec3) -> Option<(usize, f64, glam::DVec3, f64)> {
        let d = x - self.eye;
        let dn = d.dot(self.basis[2]);
        if !(dn > 0.0) {
            return None;
        }
        let scale = self.e / dn;
        let px = (d.dot(self.basis[0]) * scale - self.left) / self.du;
        let py = (self.top - d.dot(self.basis[1]) * scale) / self.dv;
        if !(px >= 0.0 && py >= 0.0 && px < self.cols as f64 && py < self.rows as f64) {
            return None;
        }
        let (i, j) = (px as usize, py as usize);
        let dist = d.length();
        let we = self.e * self.e * dist / (self.du * self.dv * dn * dn * dn);
        Some((j * self.cols as usize + i, we, -d / dist, dist))
    }
}

impl LightPaths {
    /// Traces the render's light paths with `t`: `spp` camera samples a pixel;
    /// `moments`: also the sums of the contributions' products.
    pub(super) fn image(&self, t: Tracer<'_>, spp: u32, moments: bool) -> LightImage {
        let px = self.cols as usize * self.rows as usize;
        // At most 2³¹ (a sample index and count of the samplers' u32, whose square root
        // the stratified sampler squares).
        let paths = (self.ratio * px as f64 * spp as f64)
            .round()
            .clamp(1.0, MAX_PATHS as f64) as u64;
        let mut sum = vec![0.0; px * 3];
        let mut sq = moments.then(|| vec![0.0; px * 6]);
        let mut non_finite = 0;
        let chunks = paths.div_ceil(CHUNK);
        let mut bufs: Vec<Vec<(usize, glam::DVec3)>> = vec![Vec::new(); GROUP];
        let mut first = 0u64;
        while first < chunks {
            let n = (chunks - first).min(GROUP as u64) as usize;
            bufs[..n]
                .par_iter_mut()
                .enumerate()
                .with_max_len(1)
                .for_each(|(c, buf)| {
                    buf.clear();
                    let start = (first + c as u64) * CHUNK;
                    for k in start..(start + CHUNK).min(paths) {
                        let mut smp = PixelSampler::new(
                            t.scene.settings.sampler,
                            LIGHT_KEY,
                            k as u32,
                            paths as u32,
                        );
                        if let Some(hit) = self.light_path(t, &mut smp) {
                            buf.push(hit);
                        }
                    }
                });
            for buf in &bufs[..n] {
                for &(i, c) in buf {
                    if !c.is_finite() {
                        non_finite += 1;
                        continue;
                    }
                    sum[3 * i] += c.x;
                    sum[3 * i + 1] += c.y;
                    sum[3 * i + 2] += c.z;
                    if let Some(sq) = sq.as_mut() {
                        add_moment_products(&mut sq[6 * i..6 * i + 6], c.to_array());
                    }
                }
            }
            first += n as u64;
        }
        LightImage {
            sum,
            sq,
            paths,
            non_finite,
        }
    }

    /// One light path: the pixel it adds to and what it adds (times the path count).
    fn light_path(&self, t: Tracer<'_>, smp: &mut PixelSampler) -> Option<(usize, glam::DVec3)> {
        let lights = &t.scene.area_lights;
        let light = if lights.len() == 1 {
            &lights[0]
        } else {
            let k = (smp.next_1d() * lights.len() as f64) as usize;
            &lights[k.min(lights.len() - 1)]
        };
        let (y, n_world, err) = light.sample_with_error(smp.next_2d());
        let ny = dv(n_world).normalize();
        let pdf_area = light.pdf_area(n_world) as f64;
        let y = dv(y);
        let cones = AtVertex::new(&self.balls, y, ny);
        let u = smp.next_2d();
        if !cones.active() {
            return None;
        }
        let Pick::Cone(k, dir) = cones.pick((u.0 * SHARE, u.1)) else {
            return None;
        };
        let cos_y = ny.dot(dir);
        // The cones alone: the mixture's density without the cosine lobe's share.
        let pdf_dir = cones.pdf(0.0, dir, Some(k)) / SHARE;
        if !(cos_y > 0.0 && pdf_dir > 0.0 && pdf_area > 0.0) {
            return None;
        }
        let mut beta = rgb(light.radiance) * (cos_y * lights.len() as f64 / (pdf_area * pdf_dir));
        let (mut ray, mut t_min) = t.spawn.ray(rv(y), err, rv(ny), rv(dir));
        let mut specular = 0;
        // The record written in place, as the camera paths' (integrator.rs).
        let mut hit = crate::hit::Hit::default();
        loop {
            if !t
                .scene
                .root
                .intersect_for_shading_into(&ray, t_min, Real::INFINITY, &mut hit)
            {
                return None;
            }
            let s = t.surface(&hit);
            let w_in = -dv(ray.d).normalize();
            if !s.is_delta() {
                // Straight from the light: next-event estimation's, not ours.
                if specular == 0 {
                    return None;
                }
                let (pixel, we, w_eye, dist) = self.project(dv(s.p))?;
                let (f, _) = s.eval_diffuse(w_eye, w_in);
                let cos_in = s.ng.dot(w_in).abs();
                if f == glam::DVec3::ZERO || !(cos_in > 0.0) || t.occluded(&s, w_eye, dist) {
                    return None;
                }
                // Non-finite contributions are counted where they are added.
                return Some((pixel, beta * f * (s.ng.dot(w_eye).abs() / cos_in * we)));
            }
            specular += 1;
            if specular > self.max_specular {
                return None;
            }
            let bs = s.sample(w_in, smp)?;
            // A light path carries power, which a refraction keeps (the lobe is chosen
            // with its probability): weight 1, not `sample`'s 1/η² for radiance (module
            // docs).
            if !(s.m.model == MaterialModel::Dielectric && !bs.reflected) {
                beta *= bs.weight;
            }
            if beta == glam::DVec3::ZERO {
                return None;
            }
            (ray, t_min) = t.spawn.ray(s.p, s.err, rv(s.ng), rv(bs.dir));
        }
    }
}

/// Folds the light paths' sums into an image of `n` camera samples a pixel: adds their
/// mean to `rgb`, and, when `moments` (E[RR] … E[GB] per pixel, as the camera samples left
/// them) are given, makes them such that (moments − mean·meanᵀ) / n is the variance of
/// the sum of the two estimates. Returns the channels that came out non-finite (written
/// as 0), with the light paths' contributions left out for being non-finite.
pub(crate) fn fold(
    img: &LightImage,
    rgb: &mut [f32],
    moments: Option<&mut [f32]>,
    n: u32,
) -> usize {
    let paths = img.paths as f64;
    let mut bad = img.non_finite;
    let mut moments = moments;
    for k in 0..rgb.len() / 3 {
        let cam = [
            rgb[3 * k] as f64,
            rgb[3 * k + 1] as f64,
            rgb[3 * k + 2] as f64,
        ];
        let y = [
            img.sum[3 * k] / paths,
            img.sum[3 * k + 1] / paths,
            img.sum[3 * k + 2] / paths,
        ];
        let z = [cam[0] + y[0], cam[1] + y[1], cam[2] + y[2]];
        if let (Some(m), Some(sq)) = (moments.as_deref_mut(), img.sq.as_ref()) {
            for (q, &(a, b)) in MOMENT_PAIRS.iter().enumerate() {
                // The light estimate's covariance: (E[CCᵀ] − YYᵀ) / N.
                let cov = (sq[6 * k + q] / paths - y[a] * y[b]) / paths;
                let v = m[6 * k + q] as f64 - cam[a] * cam[b] + z[a] * z[b] + n as f64 * cov;
                m[6 * k + q] = if v.is_finite() { v as f32 } else { 0.0 };
            }
        }
        for c in 0..3 {
            let v = z[c] as f32;
            rgb[3 * k + c] = if v.is_finite() {
                v
            } else {
                bad += 1;
                0.0
            };
        }
    }
    bad
}
