//! The render loop: rows in parallel through rayon, each pixel independent, so the
//! output is bit-identical for any thread count. Nothing here allocates per pixel.

use crate::adaptive;
use crate::hit::Hit;
use crate::image::add_moment_products;
pub use crate::image::{Aov, Image};
use crate::physical::PhysicalIntegrator;
pub use crate::progress::Progress;
use crate::progress::Reporter;
use crate::ray::Ray;
use crate::real::{dvec3, Real, Vec3};
use crate::sampler::{PixelSampler, SEQUENCE};
use crate::scene::Integrator;
use crate::scene::{Color, Scene};
use crate::shading::Shader;
use crate::spawn::Spawn;
use rayon::prelude::*;

/// Camera samples traced together (a multiple of [`crate::bvh::BATCH`]).
const CHUNK: usize = 64;
const _: () = assert!(CHUNK.is_multiple_of(crate::bvh::BATCH));

/// Render options that are not part of the scene.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    /// Compute the geometry channels.
    pub aov: bool,
    /// How to report progress on stderr (none by default).
    pub progress: Progress,
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
    let tracer = RowTracer {
        scene,
        shader: &shader,
        physical: &physical,
        classic,
        // The classic model samples the pixel centre at 1 spp, as POV-Ray does with
        // antialiasing off (and needs no sampler).
        centre: classic && spp == 1,
        kind: scene.settings.sampler,
        w,
    };
    let pilot = if scene.settings.adaptive {
        adaptive::pilot(spp)
    } else {
        None
    };
    let bar = Reporter::start(opts.progress, h as u64 * (1 + pilot.is_some() as u64));
    let mut rgb = vec![0f32; w * h * 3];
    let mut moments = opts.moments.then(|| vec![0f32; w * h * 6]);
    let mut aov = opts.aov.then(|| Aov {
        z: vec![0.0; w * h],
        n: vec![0.0; w * h * 3],
        p: vec![0.0; w * h * 3],
        object_id: vec![0.0; w * h],
    });
    // One moments row per image row; empty rows when moments are off.
    let moment_rows = rows_if(
        moments.is_some(),
        moments.as_deref_mut().unwrap_or_default(),
        w * 6,
        h,
    );
    let (mut non_finite, samples): (usize, u64) = match pilot {
        None => (
            rgb.par_chunks_mut(w * 3)
                .zip(moment_rows)
                .enumerate()
                // One row per job: rayon otherwise cuts the rows into a few runs (four
                // on two threads) and splits a run further only when another thread
                // steals it, so one run of costly rows (an adaptive render's
                // noisy rows, a glass object) kept one thread busy while the other
                // waited: an adaptive Cornell box's second pass ran 1.63x faster on two
                // threads than on one, and 2.0x with a job per row.
                .with_max_len(1)
                .map(|(j, (row, mrow))| {
                    let mut bad = 0;
                    let sq_wanted = !mrow.is_empty();
                    tracer.trace_row(
                        j,
                        Pass::ALONE,
                        Counts::Every(spp),
                        sq_wanted,
                        &mut |i, n, sum, sq, _| {
                            bad += write_pixel(row, mrow, i, n, sum, sq);
                        },
                    );
                    bar.row_done();
                    bad
                })
                .sum(),
            (w * h) as u64 * spp as u64,
        ),
        Some(pilot) => render_adaptive(&tracer, spp, pilot, &mut rgb, moment_rows, &bar),
    };
    // The caustics seen directly, from the light paths (light_paths.rs), when they are on.
    if let Some(light) = physical.light_image(spp, moments.is_some()) {
        non_finite +=
            crate::physical::fold_light_image(&light, &mut rgb, moments.as_deref_mut(), spp);
    }
    if let Some(a) = aov.as_mut() {
        fill_aov(scene, a, w);
    }
    bar.finish();
    Image {
        width: w as u32,
        height: h as u32,
        rgb,
        aov,
        non_finite,
        moments,
        samples,
    }
}

/// Writes pixel `i`'s mean of `n` samples (their `sum`, and their products' sums `sq` when
/// the moments row is not empty) into its row; returns how many channels came out
/// non-finite (written as 0).
fn write_pixel(
    row: &mut [f32],
    mrow: &mut [f32],
    i: usize,
    n: u32,
    sum: Color,
    sq: &[f64; 6],
) -> usize {
    let mut bad = 0;
    if !mrow.is_empty() {
        for m in 0..6 {
            let v = (sq[m] / n as f64) as f32;
            mrow[6 * i + m] = if v.is_finite() { v } else { 0.0 };
        }
    }
    let c = sum / n as f32;
    for m in 0..3 {
        let v = c[m];
        row[3 * i + m] = if v.is_finite() {
            v
        } else {
            bad += 1;
            0.0
        };
    }
    bad
}

/// Adaptive sampling (adaptive.rs): `pilot` samples in every pixel, then the rest of the
/// budget of `spp` a pixel where the neighbours' pilots were noisy. Each pixel's value is
/// the mean of all its samples. Returns the non-finite channels and the samples traced.
fn render_adaptive(
    t: &RowTracer,
    spp: u32,
    pilot: u32,
    rgb: &mut [f32],
    moment_rows: Vec<&mut [f32]>,
    bar: &Reporter,
) -> (usize, u64) {
    let w = t.w;
    let h = rgb.len() / (3 * w.max(1));
    let passes = Pass::adaptive(t.kind, pilot, (w * h) as u64);
    // The pilot: each pixel's sum and cost; its variance after a pilot of more than one
    // (one sample has none: its neighbours' samples score it); and its products' sums
    // when the moments are wanted. Each is kept only where it is used: at the pixel limit
    // every byte a pixel counts, and each page of a fresh buffer costs the kernel's time
    // to map it (renderer/docs/performance.md, "The step between the adaptive passes made
    // cheaper").
    let wants_sq = moment_rows.iter().any(|m| !m.is_empty());
    let wants_var = pilot > 1;
    let mut sums = vec![Color::ZERO; w * h];
    let mut variance = vec![0f64; if wants_var { w * h } else { 0 }];
    let mut cost = vec![0f64; w * h];
    let mut pilot_sq = vec![[0f64; 6]; if wants_sq { w * h } else { 0 }];
    let mut var_rows = rows_if(wants_var, &mut variance, w, h);
    let mut sq_rows = rows_if(wants_sq, &mut pilot_sq, w, h);
    sums.par_chunks_mut(w)
        .zip(var_rows.par_iter_mut())
        .zip(cost.par_chunks_mut(w))
        .zip(sq_rows.par_iter_mut())
        .enumerate()
        .with_max_len(1)
        .for_each(|(j, (((s, v), c), q))| {
            t.trace_row(
                j,
                passes[0],
                Counts::Every(pilot),
                wants_var || wants_sq,
                &mut |i, _, sum, sq, d| {
                    s[i] = sum;
                    if let Some(v) = v.get_mut(i) {
                        *v = adaptive::variance(sum, sq, pilot);
                    }
                    c[i] = adaptive::cost(d, pilot);
                    if let Some(q) = q.get_mut(i) {
                        *q = *sq;
                    }
                },
            );
            bar.row_done();
        });
    drop((var_rows, sq_rows));
    let extra =
        adaptive::extra_counts_after_pilot(w, h, pilot, &sums, &variance, &cost, spp - pilot);
    let samples = (w * h) as u64 * pilot as u64 + extra.iter().map(|&k| k as u64).sum::<u64>();
    let bad = rgb
        .par_chunks_mut(w * 3)
        .zip(moment_rows)
        .zip(sums.par_chunks(w))
        .enumerate()
        .with_max_len(1)
        .map(|(j, ((row, mrow), first))| {
            let counts = &extra[j * w..(j + 1) * w];
            let mut bad = 0;
            let mut i_next = 0;
            let sq_wanted = !mrow.is_empty();
            let finish =
                |row: &mut [f32], mrow: &mut [f32], i: usize, k: u32, sum: Color, sq: &[f64; 6]| {
                    let mut q = pilot_sq.get(j * w + i).copied().unwrap_or_default();
                    for m in 0..6 {
                        q[m] += sq[m];
                    }
                    write_pixel(row, mrow, i, pilot + k, first[i] + sum, &q)
                };
            t.trace_row(
                j,
                passes[1],
                Counts::Each(counts),
                sq_wanted,
                &mut |i, k, sum, sq, _| {
                    // Pixels with no extra samples keep their pilot's mean.
                    while i_next < i {
                        bad += finish(row, mrow, i_next, 0, Color::ZERO, &[0.0; 6]);
                        i_next += 1;
                    }
                    bad += finish(row, mrow, i, k, sum, sq);
                    i_next = i + 1;
                },
            );
            while i_next < w {
                bad += finish(row, mrow, i_next, 0, Color::ZERO, &[0.0; 6]);
                i_next += 1;
            }
            bar.row_done();
            bad
        })
        .sum();
    (bad, samples)
}

/// `buffer`'s `h` rows of `w` items when it is `wanted`, else `h` empty rows (`buffer` is
/// then empty: a row's writes go nowhere).
fn rows_if<T>(wanted: bool, buffer: &mut [T], w: usize, h: usize) -> Vec<&mut [T]> {
    if wanted {
        buffer.chunks_mut(w.max(1)).collect()
    } else {
        (0..h).map(|_| -> &mut [T] { &mut [] }).collect()
    }
}

/// Where a pass's samples come from: the samplers of pixel numbers `stream + j·w + i`,
/// sample numbers from `first`, in a set of `set` samples (else of the pixel's count).
#[derive(Clone, Copy)]
struct Pass {
    stream: u64,
    first: u32,
    set: Option<u32>,
}

impl Pass {
    /// A render of one pass: sample k of a pixel's count.
    const ALONE: Pass = Pass {
        stream: 0,
        first: 0,
        set: None,
    };

    /// The adaptive render's pilot and rest (adaptive.rs). For `independent` and
    /// `sobol`, one sequence: the pilot is its first `pilot` samples and the rest follow,
    /// so a pixel's samples are as well spread as a plain render's of the same count
    /// (`sobol` from a set of [`SEQUENCE`], whose prefixes of 2^m samples are
    /// (0, m, 2)-nets). Every sample is uniform whatever the count, and the count does not
    /// read the pixel's own samples, so the mean stays unbiased. `stratified` strata need
    /// the count in advance: the pilot is a set of `pilot`, and the rest a set of the
    /// pixel's extra count from a second stream (pixel numbers offset by `pixels`),
    /// independent of the pilot's.
    fn adaptive(kind: crate::sampler::SamplerKind, pilot: u32, pixels: u64) -> [Pass; 2] {
        if kind == crate::sampler::SamplerKind::Stratified {
            let rest = Pass {
                stream: pixels,
                ..Pass::ALONE
            };
            return [Pass::ALONE, rest];
        }
        let set = Some(SEQUENCE);
        [
            Pass { set, ..Pass::ALONE },
            Pass {
                first: pilot,
                set,
                ..Pass::ALONE
            },
        ]
    }
}

/// The samples of each pixel of a row: the same count in every pixel, or one each. (One
/// type, not a closure, so that the row loop is compiled once and the integrator inlined
/// into it, as when every render had one count.)
#[derive(Clone, Copy)]
enum Counts<'a> {
    Every(u32),
    Each(&'a [u32]),
}

/// What a row hands each finished pixel: (column, count, colour sum, products' sums,
/// sampler dimensions drawn).
type PixelDone<'a> = dyn FnMut(usize, u32, Color, &[f64; 6], u64) + 'a;

/// What tracing a row of pixels needs.
struct RowTracer<'a> {
    scene: &'a Scene,
    shader: &'a Shader<'a>,
    physical: &'a PhysicalIntegrator<'a>,
    classic: bool,
    /// One sample at the pixel centre (the classic model at 1 spp).
    centre: bool,
    kind: crate::sampler::SamplerKind,
    w: usize,
}

impl RowTracer<'_> {
    /// Traces `count(i)` samples in each pixel `i` of row `j` (pixel by pixel, sample by
    /// sample), with the samplers of `pass` (pixel numbers `stream + j·w + i`, sample
    /// numbers from `first`, of a set of `set` or else of the pixel's count), and hands each
    /// pixel that has samples to `done(i, count, sum, products, dimensions)`: the sum of
    /// its colours, when `sq_wanted` the sum of their products R², G², B², RG, RB, GB
    /// (else zeros), and the sampler dimensions its samples used (a measure of their
    /// paths' length, 0 for the classic model).
    fn trace_row(
        &self,
        j: usize,
        pass: Pass,
        count: Counts,
        sq_wanted: bool,
        done: &mut PixelDone,
    ) {
        let count = |i: usize| match count {
            Counts::Every(n) => n,
            Counts::Each(c) => c[i],
        };
        let (scene, w) = (self.scene, self.w);
        // The row's samples in order, in chunks: both models find a chunk's camera hits
        // together (Aggregate::intersect_many), then shade them one by one. Each
        // pixel's sum runs over its samples in the same order as one at a time.
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::ONE); CHUNK];
        let mut hits: [Option<Hit>; CHUNK] = [None; CHUNK];
        let mut samplers: [Option<PixelSampler>; CHUNK] = std::array::from_fn(|_| None);
        let mut ids = [(0u32, 0u32, 0u32); CHUNK];
        let mut sum = Color::ZERO;
        let mut sq = [0f64; 6];
        let mut dims = 0u64;
        // The next sample to place: (pixel column, sample index, the pixel's count).
        let (mut i, mut s) = (0usize, 0u32);
        let mut n_i = if w > 0 { count(0) } else { 0 };
        loop {
            // Fill a chunk.
            let mut n = 0;
            while n < CHUNK {
                while i < w && s >= n_i {
                    i += 1;
                    s = 0;
                    n_i = if i < w { count(i) } else { 0 };
                }
                if i >= w {
                    break;
                }
                ids[n] = (i as u32, s, n_i);
                let (dx, dy) = if self.centre {
                    (0.5, 0.5)
                } else {
                    let mut smp = PixelSampler::new(
                        self.kind,
                        pass.stream + (j * w + i) as u64,
                        pass.first + s,
                        pass.set.unwrap_or(n_i),
                    );
                    if self.classic {
                        smp.next_2d()
                    } else {
                        // The physical model draws the rest of the sample from it. (Made
                        // in its slot: a sampler advanced by the call and then copied
                        // into the slot was read back in pieces of other widths than
                        // the call wrote, which stalls store forwarding.)
                        samplers[n].insert(smp).next_2d()
                    }
                };
                rays[n] = scene.camera.ray_at(i as f64 + dx, j as f64 + dy);
                s += 1;
                n += 1;
            }
            if n == 0 {
                return;
            }
            scene
                .root
                .intersect_many_for_shading(&rays[..n], 0.0, Real::INFINITY, &mut hits[..n]);
            for k in 0..n {
                let (pi, ps, pn) = ids[k];
                let c = match (self.classic, &mut samplers[k]) {
                    (false, Some(smp)) => {
                        let c = self.physical.li(&rays[k], hits[k], smp);
                        dims += u64::from(smp.dimensions());
                        c
                    }
                    _ => self.shader.trace_primary_hit(&rays[k], hits[k]),
                };
                sum += c;
                if sq_wanted {
                    add_moment_products(&mut sq, [c.x as f64, c.y as f64, c.z as f64]);
                }
                if ps + 1 == pn {
                    // The pixel's last sample.
                    done(pi as usize, pn, sum, &sq, dims);
                    (sum, sq, dims) = (Color::ZERO, [0.0; 6], 0);
                }
            }
        }
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
