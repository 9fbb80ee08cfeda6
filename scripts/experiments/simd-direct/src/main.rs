//! What eight samples a vector would buy (renderer/docs/performance.md): the `direct`
//! integrator of `mi_area_soft_shadow` (conformance/scenes/mitsuba/) at 256 x 256, eight
//! samples of a pixel in the lanes of f32x8 (AVX2), against our scalar path and Mitsuba's
//! llvm variant on the same scene. Prints the time, the rate and the image's mean (ours at
//! 64 spp: 0.06175), for a check that it computes the same thing.
//!
//!   simd-direct [THREADS] [SPP]     (defaults 1 and 64; SPP a multiple of 8)
mod direct;
mod lanes;
mod scene;

use direct::{Camera, Light};
use lanes::V;
use rayon::prelude::*;
use scene::{Affine, Object, Scene, Shape};
use std::time::Instant;
use wide::u32x8;

fn main() {
    let arg = |k: usize, default: usize| std::env::args().nth(k).map_or(default, |s| s.parse().expect("a number"));
    let (threads, spp) = (arg(1, 1), arg(2, 64) as u32);
    assert!(spp % 8 == 0 && spp > 0, "SPP must be a positive multiple of 8");
    let (w, h) = (256usize, 256usize);
    // The scene of conformance/scenes/mitsuba/mi_area_soft_shadow.toml.
    let scene = Scene {
        objects: vec![
            Object { shape: Shape::Rectangle, xf: Affine::diagonal([6.0; 3], [0., -1., 0.]), albedo: [0.7; 3], radiance: 0.0 },
            // Scaled by 0.6, turned over about x (y and z negated), moved up.
            Object { shape: Shape::Rectangle, xf: Affine::diagonal([0.6, -0.6, -0.6], [-0.5, 2.2, -0.3]), albedo: [0.0; 3], radiance: 6.0 },
            Object { shape: Shape::Sphere, xf: Affine::diagonal([0.7; 3], [0., -0.3, 0.]), albedo: [0.8, 0.25, 0.2], radiance: 0.0 },
        ],
    };
    let light = Light { y: 2.2, x0: -1.1, z0: -0.9, size: 1.2, radiance: 6.0, object: 1 };
    // from (0, 1.6, -5) at (0, 0.2, 0), fov 45: forward (0, -1.4, 5) normalised.
    let len = (1.4f32 * 1.4 + 25.0).sqrt();
    let cam = Camera { eye: V::splat(0., 1.6, -5.), tan_half_fov: 22.5f32.to_radians().tan(), cos: 5.0 / len, sin: 1.4 / len };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
    let mut img = vec![0f32; w * h * 3];
    let start = Instant::now();
    pool.install(|| {
        img.par_chunks_mut(w * 3).enumerate().for_each(|(j, row)| {
            let lane = u32x8::from([0, 1, 2, 3, 4, 5, 6, 7]);
            for i in 0..w {
                let mut sum = [wide::f32x8::ZERO; 3];
                for first in (0..spp).step_by(8) {
                    let pixel = ((j * w + i) as u32).wrapping_mul(0x9e37_79b9);
                    let key = u32x8::splat(pixel ^ first.wrapping_mul(0x85eb_ca6b)) + lane * u32x8::splat(0x632b_e5ab);
                    let c = direct::eight(&scene, &light, &cam, (w, h), (i, j), key);
                    for k in 0..3 {
                        sum[k] += c[k];
                    }
                }
                for k in 0..3 {
                    row[3 * i + k] = sum[k].reduce_add() / spp as f32;
                }
            }
        })
    });
    let secs = start.elapsed().as_secs_f64();
    let mean = img.iter().map(|&v| v as f64).sum::<f64>() / img.len() as f64;
    let rate = (w * h) as f64 * spp as f64 / secs / 1e6;
    println!("{threads} thread(s), {spp} spp: {secs:.3} s, {rate:.2} Msamples/s, image mean {mean:.5}");
}
