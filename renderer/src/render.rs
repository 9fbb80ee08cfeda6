//! The render loop: rows in parallel through rayon, each pixel independent, so the
//! output is bit-identical for any thread count. Nothing here allocates per pixel.

use crate::hit::Hit;
use crate::physical::PhysicalIntegrator;
use crate::ray::Ray;
use crate::real::{dvec3, Real, Vec3};
use crate::sampler::PixelSampler;
use crate::scene::Integrator;
use crate::scene::{Color, Scene};
use crate::shading::Shader;
use crate::spawn::Spawn;
use rayon::prelude::*;

/// Camera samples traced together (a multiple of [`crate::bvh::BATCH`]).
const CHUNK: usize = 64;
const _: () = assert!(CHUNK.is_multiple_of(crate::bvh::BATCH));

/// Geometry channels for every pixel, from the pixel-centre ray. Misses are 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aov {
    /// Euclidean distance from the eye to the hit.
    pub z: Vec<f32>,
    /// Unit, outward, world-space geometric normal (3 per pixel).
    pub n: Vec<f32>,
    /// World hit point (3 per pixel).
    pub p: Vec<f32>,
    /// 1-based object id, 0 for background.
    pub object_id: Vec<f32>,
}

/// A rendered image: linear RGB, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// RGB, 3 floats per pixel.
    pub rgb: Vec<f32>,
    /// Geometry channels, when requested.
    pub aov: Option<Aov>,
    /// Pixel channels that came out NaN or infinite and were written as 0.
    pub non_finite: usize,
    /// Per-pixel second moments of the samples, when requested: E[R²], E[G²], E[B²],
    /// E[RG], E[RB], E[GB] (6 per pixel). With the mean they give the variance of any linear
    /// function of RGB (for example XYZ), for statistical tests against references.
    pub moments: Option<Vec<f32>>,
}

/// Render options that are not part of the scene.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    /// Compute the geometry channels.
    pub aov: bool,
    /// Show a progress bar (only when stderr is a terminal).
    pub progress: bool,
    /// Self-intersection strategy.
    pub spawn: Spawn,
    /// Samples per pixel, overriding the scene's `render.samples`.
    pub samples: Option<u32>,
    /// Also record per-pixel second moments ([`Image::moments`]).
    pub moments: bool,
    /// A deliberate fault, for tests that show the conformance gate catches it.
    pub fault: Option<crate::physical::Fault>,
}

/// Stack size of the render threads: tracing recurses once per trace level (at most
/// `MAX_DEPTH` + `MAX_PASS_THROUGH`) and once per level of nested definitions (at most
/// `MAX_NESTING`), up to about 50 KB a level; 64 MiB holds the deepest scene the limits
/// allow with room to spare (address space only: untouched pages cost nothing).
pub const STACK_SIZE: usize = 64 << 20;

/// Renders `scene`. With `opts.threads` it renders in its own pool of render threads;
/// without, in the current rayon pool, whose threads must have [`STACK_SIZE`] of stack for
/// the deepest scenes the build accepts (the CLI sets up such a global pool).
///
/// # Panics
/// When `opts.threads` is given and the threads cannot be started; build the pool
/// yourself to handle that (the CLI does).
pub fn render(scene: &Scene, opts: &Options) -> Image {
    match opts.threads {
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n.max(1))
                .stack_size(STACK_SIZE)
                .build()
                .expect("a rayon thread pool with a fixed thread count");
            pool.install(|| render_in_pool(scene, opts))
        }
        None => render_in_pool(scene, opts),
    }
}

fn render_in_pool(scene: &Scene, opts: &Options) -> Image {
    let (w, h) = (
        scene.settings.width as usize,
        scene.settings.height as usize,
    );
    let spp = opts.samples.unwrap_or(scene.settings.samples).max(1);
    let shader = Shader::new(scene, opts.spawn);
    let mut physical = PhysicalIntegrator::new(scene, opts.spawn);
    physical.fault = opts.fault;
    let classic = scene.settings.integrator == Integrator::Classic;
    let kind = scene.settings.sampler;
    let bar = progress_bar(h as u64, opts.progress);
    let mut rgb = vec![0f32; w * h * 3];
    let mut moments = opts.moments.then(|| vec![0f32; w * h * 6]);
    let mut aov = opts.aov.then(|| Aov {
        z: vec![0.0; w * h],
        n: vec![0.0; w * h * 3],
        p: vec![0.0; w * h * 3],
        object_id: vec![0.0; w * h],
    });
    // One moments row per image row; empty rows when moments are off.
    let moment_rows: Vec<&mut [f32]> = match moments.as_mut() {
        Some(m) => m.chunks_mut(w * 6).collect(),
        None => (0..h).map(|_| -> &mut [f32] { &mut [] }).collect(),
    };
    let non_finite: usize = rgb
        .par_chunks_mut(w * 3)
        .zip(moment_rows)
        .enumerate()
        .map(|(j, (row, mrow))| {
            let mut bad = 0;
            // The row's samples in order (pixel by pixel, sample by sample), in chunks:
            // the classic model finds a chunk's camera hits together
            // (Aggregate::intersect_many), then shades them one by one. Each pixel's
            // sum runs over its samples in the same order as one at a time.
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::ONE); CHUNK];
            let mut hits: [Option<Hit>; CHUNK] = [None; CHUNK];
            let mut samplers: [Option<PixelSampler>; CHUNK] = std::array::from_fn(|_| None);
            let mut sum = Color::ZERO;
            let mut sq = [0f64; 6];
            let total = w * spp as usize;
            // Sample `q` of the row: (pixel column, sample index).
            let pixel_sample = |q: usize| (q / spp as usize, (q % spp as usize) as u32);
            for start in (0..total).step_by(CHUNK) {
                let n = CHUNK.min(total - start);
                for k in 0..n {
                    let (i, s) = pixel_sample(start + k);
                    // The classic model samples the pixel centre at 1 spp, as POV-Ray
                    // does with antialiasing off (and needs no sampler); otherwise
                    // positions are uniform in the pixel (a box filter, as Mitsuba's).
                    let (dx, dy) = if classic && spp == 1 {
                        (0.5, 0.5)
                    } else {
                        let mut smp = PixelSampler::new(kind, (j * w + i) as u64, s, spp);
                        if classic {
                            smp.next_2d()
                        } else {
                            // The physical model draws the rest of the sample from it. (Made
                            // in its slot: a sampler advanced by the call and then copied
                            // into the slot was read back in pieces of other widths than
                            // the call wrote, which stalls store forwarding.)
                            samplers[k].insert(smp).next_2d()
                        }
                    };
                    rays[k] = scene.camera.ray_at(i as f64 + dx, j as f64 + dy);
                }
                if classic {
                    scene.root.intersect_many_for_shading(
                        &rays[..n],
                        0.0,
                        Real::INFINITY,
                        &mut hits[..n],
                    );
                }
                for k in 0..n {
                    let (i, s) = pixel_sample(start + k);
                    let c = match (classic, &mut samplers[k]) {
                        (false, Some(smp)) => physical.li(&rays[k], smp),
                        _ => shader.trace_primary_hit(&rays[k], hits[k]),
                    };
                    sum += c;
                    if !mrow.is_empty() {
                        let (r, g, b) = (c.x as f64, c.y as f64, c.z as f64);
                        for (m, v) in [r * r, g * g, b * b, r * g, r * b, g * b]
                            .into_iter()
                            .enumerate()
                        {
                            sq[m] += v;
                        }
                    }
                    if s + 1 < spp {
                        continue;
                    }
                    // The pixel's last sample: write it out.
                    if !mrow.is_empty() {
                        for m in 0..6 {
                            let v = (sq[m] / spp as f64) as f32;
                            mrow[6 * i + m] = if v.is_finite() { v } else { 0.0 };
                        }
                    }
                    let c = sum / spp as f32;
                    for m in 0..3 {
                        let v = c[m];
                        row[3 * i + m] = if v.is_finite() {
                            v
                        } else {
                            bad += 1;
                            0.0
                        };
                    }
                    (sum, sq) = (Color::ZERO, [0.0; 6]);
                }
            }
            if let Some(b) = &bar {
                b.inc(1);
            }
            bad
        })
        .sum();
    if let Some(a) = aov.as_mut() {
        fill_aov(scene, a, w);
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Image {
        width: w as u32,
        height: h as u32,
        rgb,
        aov,
        non_finite,
        moments,
    }
}

fn fill_aov(scene: &Scene, a: &mut Aov, w: usize) {
    let eye = dvec3(scene.camera.eye());
    // P reports world coordinates: render space plus the origin it was moved to.
    let origin = scene.origin();
    a.z.par_chunks_mut(w)
        .zip(a.n.par_chunks_mut(w * 3))
        .zip(a.p.par_chunks_mut(w * 3))
        .zip(a.object_id.par_chunks_mut(w))
        .enumerate()
        .for_each(|(j, (((z, n), p), id))| {
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::ONE); CHUNK];
            let mut hits: [Option<Hit>; CHUNK] = [None; CHUNK];
            for i in 0..w {
                let k = i % CHUNK;
                if k == 0 {
                    let n = CHUNK.min(w - i);
                    for (m, ray) in rays[..n].iter_mut().enumerate() {
                        *ray = scene.camera.pixel_ray((i + m) as u32, j as u32);
                    }
                    scene.root.intersect_many_for_shading(
                        &rays[..n],
                        0.0,
                        Real::INFINITY,
                        &mut hits[..n],
                    );
                }
                let Some(hit) = hits[k] else {
                    continue;
                };
                let hp = dvec3(hit.p);
                let ng = dvec3(hit.n_geo).normalize_or_zero();
                if !(hp.is_finite() && ng.is_finite()) {
                    continue;
                }
                z[i] = (hp - eye).length() as f32;
                for k in 0..3 {
                    n[3 * i + k] = ng[k] as f32;
                    p[3 * i + k] = (hp[k] + origin[k]) as f32;
                }
                id[i] = hit.object_id as f32;
            }
        });
}

fn progress_bar(rows: u64, wanted: bool) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !wanted || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(rows);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {pos}/{len} rows, {elapsed} elapsed, ETA {eta}",
    ) {
        bar.set_style(style);
    }
    Some(bar)
}
