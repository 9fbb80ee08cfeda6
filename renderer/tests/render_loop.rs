//! The render loop against its definition. render.rs traces a row's samples in chunks (the
//! classic integrator's camera hits found together by `Aggregate::intersect_many`) and
//! carries each pixel's sums across chunk boundaries. Here every pixel is recomputed the
//! plain way, one sample at a time, and the image and its second moments must match bit
//! for bit, with sample counts that split pixels across chunks.

use renderer::physical::PhysicalIntegrator;
use renderer::render::{render, Options};
use renderer::sampler::PixelSampler;
use renderer::scene::Integrator;
use renderer::scene::{Color, Scene};
use renderer::shading::Shader;
use std::path::Path;

fn check(file: &str, spp: u32) {
    let scene = Scene::load(Path::new(file)).unwrap();
    let opts = Options {
        samples: Some(spp),
        moments: true,
        threads: Some(2),
        ..Default::default()
    };
    let img = render(&scene, &opts);
    let moments = img.moments.as_ref().unwrap();
    let shader = Shader::new(&scene, opts.spawn);
    let physical = PhysicalIntegrator::new(&scene, opts.spawn);
    let classic = scene.settings.integrator == Integrator::Classic;
    let (w, h) = (img.width as usize, img.height as usize);
    for j in 0..h {
        for i in 0..w {
            let pixel = j * w + i;
            let mut sum = Color::ZERO;
            let mut sq = [0f64; 6];
            for s in 0..spp {
                let mut smp = PixelSampler::new(scene.settings.sampler, pixel as u64, s, spp);
                let (dx, dy) = if classic && spp == 1 {
                    (0.5, 0.5)
                } else {
                    smp.next_2d()
                };
                let ray = scene.camera.ray_at(i as f64 + dx, j as f64 + dy);
                let c = if classic {
                    shader.trace_primary(&ray)
                } else {
                    physical.li(&ray, &mut smp)
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
            let c = sum / spp as f32;
            for k in 0..3 {
                assert_eq!(
                    img.rgb[3 * pixel + k].to_bits(),
                    c[k].to_bits(),
                    "{file}, {spp} spp: pixel ({i}, {j}) channel {k}"
                );
            }
            for k in 0..6 {
                assert_eq!(
                    moments[6 * pixel + k].to_bits(),
                    ((sq[k] / spp as f64) as f32).to_bits(),
                    "{file}, {spp} spp: pixel ({i}, {j}) moment {k}"
                );
            }
        }
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
