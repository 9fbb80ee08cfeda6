//! The render loop against its definition. render.rs traces a row's samples in chunks (the
//! camera hits found together by `Aggregate::intersect_many`) and
//! carries each pixel's sums across chunk boundaries. Here every pixel is recomputed the
//! plain way, one sample at a time, and the image and its second moments must match bit
//! for bit, with sample counts that split pixels across chunks.

use renderer::adaptive;
use renderer::physical::PhysicalIntegrator;
use renderer::render::{render, Image, Options};
use renderer::sampler::{PixelSampler, SamplerKind};
use renderer::scene::Integrator;
use renderer::scene::{Color, Scene};
use renderer::shading::Shader;
use renderer::Real;
use std::path::Path;

/// One pixel's samples `0..count` from sampler stream `stream`, traced the plain way: the
/// sum of their colours, of their products (R², G², B², RG, RB, GB), and the sampler
/// dimensions they drew.
struct Plain<'a> {
    scene: &'a Scene,
    shader: Shader<'a>,
    physical: PhysicalIntegrator<'a>,
    classic: bool,
    centre: bool,
}

impl<'a> Plain<'a> {
    fn new(scene: &'a Scene, opts: &Options, spp: u32) -> Self {
        let classic = scene.settings.integrator == Integrator::Classic;
        Plain {
            scene,
            shader: Shader::new(scene, opts.spawn),
            physical: PhysicalIntegrator::new(scene, opts.spawn),
            classic,
            centre: classic && spp == 1,
        }
    }

    /// Samples `first..first + count` of a set of `set` (else of `count`) from the pixel
    /// numbers offset by `stream`.
    fn pixel(
        &self,
        i: usize,
        j: usize,
        (stream, first, set): (u64, u32, Option<u32>),
        count: u32,
    ) -> (Color, [f64; 6], u64) {
        let scene = self.scene;
        let pixel = stream + (j * scene.settings.width as usize + i) as u64;
        let mut sum = Color::ZERO;
        let mut sq = [0f64; 6];
        let mut dims = 0u64;
        for s in 0..count {
            let mut smp = PixelSampler::new(
                scene.settings.sampler,
                pixel,
                first + s,
                set.unwrap_or(count),
            );
            let (dx, dy) = if self.centre {
                (0.5, 0.5)
            } else {
                smp.next_2d()
            };
            let ray = scene.camera.ray_at(i as f64 + dx, j as f64 + dy);
            let c = if self.classic {
                self.shader.trace_primary(&ray)
            } else {
                let first = scene.root.intersect_for_shading(&ray, 0.0, Real::INFINITY);
                let c = self.physical.li(&ray, first, &mut smp);
                dims += u64::from(smp.dimensions());
                c
            };
            sum += c;
            let (r, g, b) = (c.x as f64, c.y as f64, c.z as f64);
            for (k, v) in [r * r, g * g, b * b, r * g, r * b, g * b]
                .into_iter()
                .enumerate()
            {
                sq[k] += v;
            }
        }
        (sum, sq, dims)
    }
}

/// Compares pixel `pixel`'s colour and moments with the mean of `n` samples.
fn compare(img: &Image, what: &str, pixel: usize, n: u32, sum: Color, sq: &[f64; 6]) {
    let moments = img.moments.as_ref().unwrap();
    let (i, j) = (pixel % img.width as usize, pixel / img.width as usize);
    let c = sum / n as f32;
    for k in 0..3 {
        assert_eq!(
            img.rgb[3 * pixel + k].to_bits(),
            c[k].to_bits(),
            "{what}: pixel ({i}, {j}) channel {k}"
        );
    }
    for k in 0..6 {
        assert_eq!(
            moments[6 * pixel + k].to_bits(),
            ((sq[k] / n as f64) as f32).to_bits(),
            "{what}: pixel ({i}, {j}) moment {k}"
        );
    }
}

fn options(spp: u32) -> Options {
    Options {
        samples: Some(spp),
        moments: true,
        threads: Some(2),
        ..Default::default()
    }
}

fn check(file: &str, spp: u32) {
    let scene = Scene::load(Path::new(file)).unwrap();
    let opts = options(spp);
    let img = render(&scene, &opts);
    let plain = Plain::new(&scene, &opts, spp);
    let (w, h) = (img.width as usize, img.height as usize);
    assert_eq!(img.samples, (w * h) as u64 * spp as u64);
    for j in 0..h {
        for i in 0..w {
            let (sum, sq, _) = plain.pixel(i, j, (0, 0, None), spp);
            compare(
                &img,
                &format!("{file}, {spp} spp"),
                j * w + i,
                spp,
                sum,
                &sq,
            );
        }
    }
}

/// Adaptive sampling (renderer/src/adaptive.rs) against its definition: the pilot's
/// samples in every pixel, the extra counts from the pilots' variances (after a pilot of
/// one, their samples) and costs, the
/// extra samples from the second stream (pixel numbers offset by w·h), and each pixel the
/// mean of all its samples.
fn check_adaptive(file: &str, spp: u32, sampler: SamplerKind) {
    let mut scene = Scene::load(Path::new(file)).unwrap();
    scene.settings.adaptive = true;
    scene.settings.sampler = sampler;
    let opts = options(spp);
    let img = render(&scene, &opts);
    let plain = Plain::new(&scene, &opts, spp);
    let (w, h) = (img.width as usize, img.height as usize);
    let pilot = adaptive::pilot(spp).expect("a budget that adapts");
    // Stratified: two sets, the rest's from pixel numbers offset by w·h; the others: one
    // sequence of SEQUENCE samples, the rest after the pilot.
    let (pass0, pass1) = if scene.settings.sampler == SamplerKind::Stratified {
        ((0, 0, None), ((w * h) as u64, 0, None))
    } else {
        let set = Some(renderer::sampler::SEQUENCE);
        ((0, 0, set), (0, pilot, set))
    };
    let first: Vec<_> = (0..w * h)
        .map(|p| plain.pixel(p % w, p / w, pass0, pilot))
        .collect();
    let variance: Vec<f64> = first
        .iter()
        .map(|(sum, sq, _)| adaptive::variance(*sum, sq, pilot))
        .collect();
    let cost: Vec<f64> = first
        .iter()
        .map(|(.., d)| adaptive::cost(*d, pilot))
        .collect();
    let sums: Vec<_> = first.iter().map(|(sum, ..)| *sum).collect();
    let extra =
        adaptive::extra_counts_after_pilot(w, h, pilot, &sums, &variance, &cost, spp - pilot);
    assert!(
        extra.iter().any(|&k| k != extra[0]),
        "{file}: every pixel got the same extra count, so this test shows nothing about uneven counts"
    );
    let total: u64 = extra.iter().map(|&k| u64::from(k)).sum();
    assert_eq!(img.samples, (w * h) as u64 * u64::from(pilot) + total);
    for (p, (s1, q1, _)) in first.iter().enumerate() {
        let (s2, q2, _) = plain.pixel(p % w, p / w, pass1, extra[p]);
        let q: [f64; 6] = std::array::from_fn(|k| q1[k] + q2[k]);
        compare(
            &img,
            &format!("{file}, adaptive at {spp} spp"),
            p,
            pilot + extra[p],
            *s1 + s2,
            &q,
        );
    }
}

#[test]
fn classic_render_matches_one_sample_at_a_time() {
    for spp in [1, 3, 7] {
        check("scenes/hierarchy.toml", spp);
    }
}

#[test]
fn physical_render_matches_one_sample_at_a_time() {
    check("../conformance/scenes/mitsuba/mi_diffuse_point.toml", 5);
}

#[test]
fn adaptive_render_matches_its_definition() {
    let area = "../conformance/scenes/mitsuba/mi_area_soft_shadow.toml";
    // A pilot of one sample a pixel (`adaptive::pilot`), scored by its neighbours'
    // samples' spread: the smallest budget that adapts, 2 spp, and others up to 16, the
    // rest from stratified's second set at 4 and 12;
    check_adaptive(area, 2, SamplerKind::Sobol);
    check_adaptive(area, 4, SamplerKind::Stratified);
    check_adaptive(area, 9, SamplerKind::Sobol);
    check_adaptive(area, 12, SamplerKind::Stratified);
    check_adaptive(area, 8, SamplerKind::Independent);
    check_adaptive("scenes/hierarchy.toml", 8, SamplerKind::Sobol);
    check_adaptive(area, 16, SamplerKind::Sobol);
    // a pilot of 4 (a quarter) scored by its neighbours' own variances, from 17 spp.
    check_adaptive(area, 17, SamplerKind::Sobol);
    check_adaptive(area, 24, SamplerKind::Stratified);
}
