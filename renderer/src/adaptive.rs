//! Adaptive sampling: where a pixel's samples go when `render.adaptive` is on.
//!
//! A budget of `spp` samples a pixel is spent in two passes. The pilot traces
//! [`pilot`]`(spp)` samples in every pixel; the rest of the budget is then shared out
//! among the pixels in proportion to the noise their neighbours' pilots showed (a pixel's
//! standard deviation, estimated from the pixels around it: [`radius`]), with a part
//! shared evenly. Up to [`SPREAD_UP_TO`] spp the pilot is one sample a pixel, and the
//! estimate is the spread of the neighbours' samples ([`spread_scores`]); above, each
//! neighbour's pilot gives its own variance, and the estimate is the mean of their
//! standard deviations ([`scores`]).
//! The rest continues each pixel's sequence of samples (`independent`, `sobol`) or is a
//! second set from an independent stream (`stratified`, whose strata need the count in
//! advance; render.rs's `Pass::adaptive`). A pixel's value is the mean of all its
//! samples.
//!
//! **Why the neighbours, and not the pixel itself.** A pixel's count must not depend on
//! its own pilot samples: if it did, the mean would be biased. A pixel at the edge of a
//! light whose pilot samples all fell on the light would show no variance, get no more
//! samples, and keep a value that is too bright, while its neighbours whose pilots were
//! mixed would be pulled to the truth: over many renders such pixels come out too bright
//! on average (at 4 pilot samples and 90 % coverage, by 6 % of the light's radiance).
//! Here a pixel's count is a function of other pixels' pilots only, which are
//! independent of its own (every pixel's sampler is seeded by its own index), so its
//! mean is unbiased for any count: E[mean | count] is the pixel's value. The share of
//! the budget is normalized by the pixels that do not touch it either (the mean of the
//! estimates outside its block of neighbours), so nothing in a pixel's count reads its own
//! samples, not even through the rounding of that sum (it is added up from prefix and
//! suffix sums that leave the block out). The total then matches the budget only
//! approximately: a few per cent over where the noise is clustered in patches (their
//! pixels are measured against a mean that leaves their own patch out), under where
//! the cap binds; the renderer reports the samples it took.
//!
//! Allocation proportional to the standard deviation is the one that minimizes the
//! summed variance of the pixel means for a fixed total, when each pixel's variance
//! falls as 1/n (Neyman allocation). Noise is spatially coherent (the edge of a light, a
//! caustic, a soft shadow's penumbra), which is what makes the neighbours a good guess.

use crate::material::Color;
use glam::DVec2;
use rayon::prelude::*;
use std::ops::Range;

/// The share of the extra samples spread evenly over all pixels, so a pixel whose
/// neighbours' pilots happened to show no noise (a caustic that no pilot path found)
/// still gets some.
pub const EVEN_SHARE: f64 = 0.25;

/// The fewest pilot samples a pixel's neighbourhood holds after a pilot of more than one
/// ([`radius`]; after a pilot of one, the 24 of [`SPREAD_RADIUS`]).
pub const NEIGHBOURHOOD_SAMPLES: u32 = 64;

/// How far a pixel's neighbourhood reaches for a pilot of `pilot` samples a pixel. For a
/// pilot of one, [`SPREAD_RADIUS`]. Otherwise the smallest radius (1 is the 8 pixels
/// around it, 2 the 24 of its 5 × 5 block) whose neighbours hold at least
/// [`NEIGHBOURHOOD_SAMPLES`] pilot samples. A variance from fewer misses noisy pixels (a
/// light's edge whose neighbours' pilots happened to be quiet); one from farther than it
/// needs blurs the noise's picture. Measured with `sobol`, five or six seeds each, at 16
/// spp with a pilot of 4 (the rule before the pilot of one): the 5 × 5 block cut the
/// squared error of the glass and mirror scenes by 11–12 % at 256² (7 % at 128²) and the
/// Cornell box's by 5 % at 256², and on the area-light scene it took away the seeds whose
/// error was 4–36 times the others' (a light's edge left with the even share); with a
/// pilot of 8 or 16 it was 2–4 % worse than the 8 neighbours
/// (renderer/docs/performance.md).
pub fn radius(pilot: u32) -> usize {
    if pilot == 1 {
        return SPREAD_RADIUS;
    }
    let mut r = 1;
    while (((2 * r + 1) * (2 * r + 1) - 1) as u32).saturating_mul(pilot) < NEIGHBOURHOOD_SAMPLES {
        r += 1;
    }
    r
}

/// The radius of the block whose samples' spread scores a pixel after a pilot of one
/// ([`spread_scores`]): its 5 × 5 block, 24 samples. Four seeds at 3 spp on eight Mitsuba
/// scenes no bench times: the 3 × 3 block had 0.72–0.96 of its RMSE on six, 1.03 and
/// 1.05 on the two whose noise covers the image (mi_path_rr, mi_env_diffuse); the 7 × 7
/// and 9 × 9 blocks were worse at 2–4 spp on six, within 1 % on mi_sphere_light and 1–2 %
/// better on mi_path_rr (renderer/docs/performance.md).
pub const SPREAD_RADIUS: usize = 2;

/// No pixel takes more than this many times the average extra samples.
pub const MAX_FACTOR: f64 = 64.0;

/// Nor more extra samples than this (with the pilot, under 2³¹: sampler.rs's `SEQUENCE`).
pub const MAX_EXTRA: f64 = (1u32 << 30) as f64 - 1.0;

/// The fewest pilot samples whose own variances score the neighbours: with fewer, they miss
/// noisy pixels that a small bright light lights (mi_sphere_light at 6 and 7 spp: a pilot
/// of 3 had 1.29 and 1.45 times the RMSE of a pilot of 4; renderer/docs/performance.md).
/// Every budget above [`SPREAD_UP_TO`] has a quarter at least this large (checked when
/// built).
pub const MIN_PILOT: u32 = 4;
const _: () = assert!((SPREAD_UP_TO + 1) / 4 >= MIN_PILOT);

/// The largest budget whose pilot is one sample a pixel ([`pilot`]).
pub const SPREAD_UP_TO: u32 = 16;

/// The pilot's samples a pixel for a budget of `spp`: one from 2 to [`SPREAD_UP_TO`] spp
/// (its neighbours' samples' spread scores a pixel: [`spread_scores`]); above, a quarter
/// (at least [`MIN_PILOT`]). `None` (no adapting) at 1 spp. Chosen on eight Mitsuba scenes
/// that no bench times, four seeds, RMSE against a 1,024-spp render
/// (renderer/docs/performance.md, "A pilot of one sample"): at 2 spp 0.09–0.94 of the
/// plain render's; at 3 to 16 spp 0.38–1.02 of the previous pilots' (2 at 3 and 4 spp, 3
/// at 5, then a quarter, at least 4), at most 1.016 on any scene; at 32 and 64 spp better
/// on six scenes (0.65–0.98) but 1.01–1.03 on the two whose noise covers the image, and
/// at 128 and 256 spp up to 10 % slower on seven.
pub fn pilot(spp: u32) -> Option<u32> {
    match spp {
        0..=1 => None,
        2..=SPREAD_UP_TO => Some(1),
        _ => Some(spp / 4),
    }
}

/// The extra samples of each pixel after a pilot of `pilot` samples a pixel, from the
/// pilot's `sums` (each pixel's sample, after a pilot of one: [`extra_counts_from_samples`])
/// or its `variance`s ([`extra_counts`]; not read after a pilot of one, and may then be
/// empty), and its `cost`s, for `extra` more samples a pixel on average, in neighbourhoods
/// of [`radius`]`(pilot)`.
pub fn extra_counts_after_pilot(
    w: usize,
    h: usize,
    pilot: u32,
    sums: &[Color],
    variance: &[f64],
    cost: &[f64],
    extra: u32,
) -> Vec<u32> {
    let r = radius(pilot);
    if pilot == 1 {
        extra_counts_from_samples(w, h, r, sums, cost, extra)
    } else {
        extra_counts(w, h, r, variance, cost, extra)
    }
}

/// The variance of one sample, summed over R, G and B, from `n` samples' `sum` and their
/// products' sums `sq` (R², G², B² first), as [`crate::render`]'s rows gather them: the
/// unbiased sample variance, 0 when it is not finite (a non-finite sample is reported by
/// the render itself).
pub fn variance(sum: Color, sq: &[f64; 6], n: u32) -> f64 {
    if n < 2 {
        return 0.0;
    }
    let n = n as f64;
    let mut v = 0.0;
    for c in 0..3 {
        let m = sum[c] as f64 / n;
        let d = (sq[c] - n * m * m) / (n - 1.0);
        if !d.is_finite() {
            return 0.0;
        }
        // Rounding can take a tiny variance below 0.
        v += d.max(0.0);
    }
    v
}

/// The cost of one sample, in units of a ray, from `n` samples that drew `dimensions`
/// sampler dimensions in all: one for the camera ray and one for every few dimensions a
/// path vertex draws (its light sample, its direction, its roulette). A proxy that is the
/// same on every run, where a clock would not be.
pub fn cost(dimensions: u64, n: u32) -> f64 {
    1.0 + dimensions as f64 / (4.0 * n.max(1) as f64)
}

/// The extra samples of each pixel of a `w` × `h` image (row-major) for `extra` more
/// samples a pixel on average, from each pixel's pilot `variance` and `cost` a sample,
/// with neighbourhoods of radius `r` ([`radius`]).
///
/// Pixel p gets `extra · (EVEN_SHARE + (1 − EVEN_SHARE) · a_p / ā_p)`, at most
/// `MAX_FACTOR · extra`, rounded up or down at random by a hash of its index (so the
/// expected count is that number). Its score `a_p = σ_p / √c_p` is the count that minimizes the
/// summed variance of the means at a fixed total time (Neyman's allocation with costs),
/// where σ_p and c_p are estimated from the pixels around p (within `r` in both
/// directions), not from p ([`scores`]); ā_p is the mean score of
/// the pixels outside p's block of radius `r` (whose scores do not read p's pilot
/// either). When ā_p is 0 (no noise anywhere
/// else) the share is even.
pub fn extra_counts(
    w: usize,
    h: usize,
    r: usize,
    variance: &[f64],
    cost: &[f64],
    extra: u32,
) -> Vec<u32> {
    share_out(w, h, r, &scores(w, h, r, variance, cost), extra)
}

/// [`extra_counts`] after a pilot of one sample a pixel, whose variance no pixel's own
/// sample gives: each pixel's score is the spread of its neighbours' `samples` about their
/// mean ([`spread_scores`]), over the root of their mean cost.
pub fn extra_counts_from_samples(
    w: usize,
    h: usize,
    r: usize,
    samples: &[Color],
    cost: &[f64],
    extra: u32,
) -> Vec<u32> {
    share_out(w, h, r, &spread_scores(w, h, r, samples, cost), extra)
}

/// Each pixel's extra count from the pixels' scores, as [`extra_counts`] says.
fn share_out(w: usize, h: usize, r: usize, score: &[f64], extra: u32) -> Vec<u32> {
    let outside = Outside::new(w, h, r, score);
    let extra = extra as f64;
    let mut counts = vec![0; w * h];
    counts.par_chunks_mut(w.max(1)).enumerate().for_each_init(
        || BlockRows::new(&outside),
        |rows, (j, row)| {
            let sums = rows.row(j);
            for (i, (count, sum)) in row.iter_mut().zip(sums).enumerate() {
                let p = j * w + i;
                let rest = w * h - Block::new(i, j, w, h, r).len();
                let mean = if rest > 0 { sum / rest as f64 } else { 0.0 };
                let share = if mean > 0.0 {
                    EVEN_SHARE + (1.0 - EVEN_SHARE) * score[p] / mean
                } else {
                    1.0
                };
                let x = (extra * share).min(MAX_FACTOR * extra).min(MAX_EXTRA);
                *count = (x + round_up_chance(p)).floor() as u32;
            }
        },
    );
    counts
}

/// Each pixel's score σ/√c for [`extra_counts`], from its neighbours within `r` (not
/// itself): σ the mean of their standard deviations, c the mean of their costs.
///
/// The mean of the standard deviations, not the root of the mean variance: each
/// neighbour's variance comes from a few pilot samples (4 at 17 to 19 spp), and one bright
/// sample makes it large, which the root of the mean passes on to the whole block. Five
/// or six seeds at 256², 16 spp (64 for the second figure): squared error 0.94 (0.95) of
/// the root of the mean's on the Cornell box, 0.96 (0.93) on the area light, 0.95 on the
/// mirror, 1.06 (1.02) on the glass scene, whose caustic's rare bright paths are the
/// outliers the root of the mean follows (renderer/docs/performance.md).
pub(crate) fn scores(w: usize, h: usize, r: usize, variance: &[f64], cost: &[f64]) -> Vec<f64> {
    assert_eq!(variance.len(), w * h, "one variance a pixel");
    assert_eq!(cost.len(), w * h, "one cost a pixel");
    // Each pixel's standard deviation, taken once, beside its cost: a block reads the
    // pair for each of its 8 or 24 neighbours and adds it up as one pair, each lane its own
    // sum in the same order (the same bits as two sums; 8 bytes a pixel more than the
    // deviations alone, for the step between the passes).
    let pairs: Vec<DVec2> = variance
        .par_iter()
        .zip(cost)
        .map(|(v, c)| DVec2::new(v.sqrt(), *c))
        .collect();
    neighbour_sums(
        w,
        h,
        r,
        |p| pairs[p],
        |sum, n| {
            let (sd, c) = (sum.x, sum.y);
            let n = n as f64;
            if n > 0.0 && c > 0.0 {
                (sd / n) / (c / n).sqrt()
            } else {
                0.0
            }
        },
    )
}

/// Each pixel's score σ/√c after a pilot of one sample a pixel: σ the standard deviation of
/// its neighbours' samples about their mean (the unbiased sample variance, summed over R, G
/// and B), c the mean of their costs. The samples' spread holds the image's own changes
/// across the block as well as its noise: an edge draws samples as noise does, which it
/// also needs at one sample a pixel.
pub(crate) fn spread_scores(
    w: usize,
    h: usize,
    r: usize,
    samples: &[Color],
    cost: &[f64],
) -> Vec<f64> {
    assert_eq!(samples.len(), w * h, "one sample a pixel");
    assert_eq!(cost.len(), w * h, "one cost a pixel");
    let item = |p: usize| {
        let x = samples[p].as_dvec3();
        Spread {
            x,
            xx: x * x,
            cost: cost[p],
        }
    };
    block_sums(w, h, r, item, |sum, n| {
        if n < 2 || !(sum.cost > 0.0) {
            return 0.0;
        }
        // A non-finite sample gives the block no spread, as `variance` gives its pixel
        // none (the render itself reports it).
        if !(sum.x.is_finite() && sum.xx.is_finite()) {
            return 0.0;
        }
        let n = n as f64;
        let var = (sum.xx - sum.x * sum.x / n) / (n - 1.0);
        // Rounding leaves equal samples a spread of a few ulps of their mean square (or
        // takes it below 0): none, so that a flat block scores 0 as a flat pilot does.
        let floor = sum.xx / n * FLAT;
        let var = glam::DVec3::select(var.cmpgt(floor), var, glam::DVec3::ZERO);
        var.element_sum().sqrt() / (sum.cost / n).sqrt()
    })
}

/// A block's spread in a channel at most this part of its samples' mean square is taken
/// for rounding ([`spread_scores`]): far above the few ulps that 24 sums leave, far below
/// any noise a render shows.
const FLAT: f64 = 1e-12;

/// The sums of a block's samples, their squares and their costs ([`spread_scores`]).
#[derive(Clone, Copy, Default)]
struct Spread {
    x: glam::DVec3,
    xx: glam::DVec3,
    cost: f64,
}

impl std::ops::AddAssign for Spread {
    fn add_assign(&mut self, o: Spread) {
        self.x += o.x;
        self.xx += o.xx;
        self.cost += o.cost;
    }
}

/// For each pixel p, `score(sum, n)` of the sum of `item(q)` over the `n` pixels q of p's
/// block of radius `r` other than p: row by row, left to right, p's own row in two runs
/// (the order of the sums the counts were measured with, so the same bits;
/// renderer/docs/performance.md, 2026-11-29).
fn neighbour_sums<T: Copy + Default + std::ops::AddAssign>(
    w: usize,
    h: usize,
    r: usize,
    item: impl Fn(usize) -> T + Sync,
    score: impl Fn(T, usize) -> f64 + Sync,
) -> Vec<f64> {
    (0..w * h)
        .into_par_iter()
        .map(|p| {
            let (i, j) = (p % w, p / w);
            let block = Block::new(i, j, w, h, r);
            let mut sum = T::default();
            let mut add = |run: Range<usize>| {
                for q in run {
                    sum += item(q);
                }
            };
            for b in block.rows.clone() {
                let run = b * w + block.cols.start..b * w + block.cols.end;
                if b == j {
                    add(run.start..p);
                    add(p + 1..run.end);
                } else {
                    add(run);
                }
            }
            score(sum, block.len() - 1)
        })
        .collect()
}

/// For each pixel p, `score(sum, n)` of the sum of `item(q)` over the `n` pixels q of p's
/// block of radius `r` other than p, as [`neighbour_sums`] gives it but added up in an
/// order that neighbouring pixels share, so that a pixel costs a few additions, not one
/// for each of its neighbours (a 5 × 5 block: 24). For p's row, each column's sum over the
/// block's rows other than p's, top to bottom (`rows_by`), and that plus p's row
/// (`column`); p's sum is `column`'s sum over the columns left of p, left to right, plus
/// the same right of p, plus its own column's `rows_by`. A column outside the image adds
/// a zero, which changes no sum, so every pixel's sum is one fixed sum of its neighbours:
/// the same bits whatever the threads, and never p's own item, not even through rounding
/// (nothing is taken away). Its bits differ from [`neighbour_sums`]' in the last places at
/// most, which changes a count only where its share rounds across a whole number; none
/// changed in 33 adaptive renders of five bench scenes at 2 to 16 spp, three samplers
/// (renderer/docs/performance.md, "The step between the adaptive passes made cheaper").
fn block_sums<T: Copy + Default + Send + std::ops::AddAssign>(
    w: usize,
    h: usize,
    r: usize,
    item: impl Fn(usize) -> T + Sync,
    score: impl Fn(T, usize) -> f64 + Sync,
) -> Vec<f64> {
    let mut out = vec![0.0; w * h];
    // Each row's columns, with `r` zeros at either end.
    let scratch = || (vec![T::default(); w + 2 * r], vec![T::default(); w + 2 * r]);
    out.par_chunks_mut(w.max(1)).enumerate().for_each_init(
        scratch,
        |(rows_by, column), (j, out)| {
            let others = j.saturating_sub(r)..j;
            let below = j + 1..(j + r + 1).min(h);
            for i in 0..w {
                let mut sum = T::default();
                for b in others.clone().chain(below.clone()) {
                    sum += item(b * w + i);
                }
                rows_by[r + i] = sum;
                sum += item(j * w + i);
                column[r + i] = sum;
            }
            for (i, out) in out.iter_mut().enumerate() {
                let mut left = T::default();
                for x in &column[i..r + i] {
                    left += *x;
                }
                let mut right = T::default();
                for x in &column[r + i + 1..2 * r + i + 1] {
                    right += *x;
                }
                left += right;
                left += rows_by[r + i];
                *out = score(left, Block::new(i, j, w, h, r).len() - 1);
            }
        },
    );
    out
}

/// A number in [0, 1) from the pixel's index alone, for rounding its count: a hash of its
/// own (not any sampler's numbers, which would be the pixel's own samples).
fn round_up_chance(p: usize) -> f64 {
    crate::sampler::to_unit(crate::sampler::mix64(p as u64 ^ 0xada7_c0de_5eed_0001))
}

/// Sums of the scores outside each pixel's block ([`Block`]), each added up from the scores
/// outside the block alone: the rows above and below it (prefix and suffix sums over
/// whole rows), and in each of its rows the columns left and right of it (prefix and
/// suffix sums within the row). A total less the block's sum would read the block's
/// scores through its rounding.
struct Outside<'a> {
    w: usize,
    h: usize,
    r: usize,
    score: &'a [f64],
    /// Sum of the rows before row b, for b in 0..=h.
    rows_before: Vec<f64>,
    /// Sum of the rows from row b on, for b in 0..=h.
    rows_from: Vec<f64>,
}

impl<'a> Outside<'a> {
    /// For the blocks of radius `r` in the `w` × `h` image of scores `score`.
    fn new(w: usize, h: usize, r: usize, score: &'a [f64]) -> Self {
        // Each row's sum, left to right.
        let row_sum: Vec<f64> = (0..h)
            .into_par_iter()
            .map(|b| score[b * w..(b + 1) * w].iter().fold(0.0, |s, x| s + x))
            .collect();
        let mut rows_before = vec![0.0; h + 1];
        let mut rows_from = vec![0.0; h + 1];
        for b in 0..h {
            rows_before[b + 1] = rows_before[b] + row_sum[b];
            rows_from[h - b - 1] = rows_from[h - b] + row_sum[h - b - 1];
        }
        Outside {
            w,
            h,
            r,
            score,
            rows_before,
            rows_from,
        }
    }
}

/// The sums outside the blocks of one image row's pixels ([`BlockRows::row`]), from the
/// prefix and suffix sums of the rows those blocks cover, held in 2r + 1 slots (row b in
/// slot b mod (2r + 1)) while the next image rows need them: the next row's blocks share
/// all but one. Not kept for the whole image: the same sums, in less fresh memory (a page
/// the kernel maps the first time it is written costs more than adding a row up again).
/// It belongs to one [`Outside`], whose scores it reads.
struct BlockRows<'o, 'a> {
    of: &'o Outside<'a>,
    /// The image row each slot holds.
    held: Vec<Option<usize>>,
    /// Each slot's sums of the columns before column a (at a, for a in 0..=w), then of the
    /// columns from column a on (at w + 1 + a).
    sums: Vec<f64>,
    /// Where the current image row's block rows start in `sums`, top to bottom.
    at: Vec<usize>,
    /// The current image row's sums outside each pixel's block.
    outside: Vec<f64>,
}

impl<'o, 'a> BlockRows<'o, 'a> {
    fn new(of: &'o Outside<'a>) -> Self {
        let slots = 2 * of.r + 1;
        BlockRows {
            of,
            held: vec![None; slots],
            sums: vec![0.0; slots * 2 * (of.w + 1)],
            at: Vec::with_capacity(slots),
            outside: Vec::with_capacity(of.w),
        }
    }

    /// Makes the slots hold the rows of the blocks of row `j`'s pixels, and `at` point
    /// at them.
    fn rows_of(&mut self, j: usize) {
        let Outside { w, h, r, score, .. } = *self.of;
        let (slots, stride) = (2 * r + 1, 2 * (w + 1));
        self.at.clear();
        for b in Block::new(0, j, w, h, r).rows {
            let slot = b % slots;
            if self.held[slot] != Some(b) {
                let row = &score[b * w..(b + 1) * w];
                let out = &mut self.sums[slot * stride..(slot + 1) * stride];
                let (before, from) = out.split_at_mut(w + 1);
                for a in 0..w {
                    before[a + 1] = before[a] + row[a];
                    from[w - a - 1] = from[w - a] + row[w - a - 1];
                }
                self.held[slot] = Some(b);
            }
            self.at.push(slot * stride);
        }
    }

    /// The sums of the scores outside the blocks of row `j`'s pixels, left to right. Each
    /// is the rows above and below the block, then for each of the block's rows, top to
    /// bottom, its columns left of the block plus those right of it. Added up for the
    /// whole row one block row at a time, so that the pixels whose blocks the image's
    /// edges do not cut run in lanes; each pixel's sum is added in the same order as
    /// alone.
    fn row(&mut self, j: usize) -> &[f64] {
        self.rows_of(j);
        let Outside { w, h, r, .. } = *self.of;
        let ends = Block::new(0, j, w, h, r).rows;
        let out = &mut self.outside;
        out.clear();
        out.resize(
            w,
            self.of.rows_before[ends.start] + self.of.rows_from[ends.end],
        );
        // The pixels whose blocks reach neither side: columns i − r to i + r, for i from
        // r on (their left sides start at column 0).
        let inner = r.min(w)..w.saturating_sub(r).max(r.min(w));
        for &at in &self.at {
            let (before, from) = self.sums[at..at + 2 * (w + 1)].split_at(w + 1);
            for i in (0..inner.start).chain(inner.end..w) {
                out[i] += before[i.saturating_sub(r)] + from[(i + r + 1).min(w)];
            }
            let lanes = out[inner.clone()].iter_mut();
            let right = &from[(inner.start + r + 1).min(w)..];
            for ((o, b), f) in lanes.zip(before).zip(right) {
                *o += *b + *f;
            }
        }
        &self.outside
    }
}

/// The block of radius `r` around (i, j) (3 × 3 for 1), cut at the image's edges: its
/// columns and rows.
struct Block {
    cols: Range<usize>,
    rows: Range<usize>,
}

impl Block {
    fn new(i: usize, j: usize, w: usize, h: usize, r: usize) -> Self {
        Block {
            cols: i.saturating_sub(r)..(i + r + 1).min(w),
            rows: j.saturating_sub(r)..(j + r + 1).min(h),
        }
    }

    /// How many pixels it holds.
    fn len(&self) -> usize {
        self.cols.len() * self.rows.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pixels of the block of radius `r` around (i, j) that lie in the image, row by
    /// row.
    fn block(
        i: usize,
        j: usize,
        w: usize,
        h: usize,
        r: usize,
    ) -> impl Iterator<Item = (usize, usize)> {
        let Block { cols, rows } = Block::new(i, j, w, h, r);
        rows.flat_map(move |b| cols.clone().map(move |a| (a, b)))
    }

    /// A `w` × `h` image of variances with one noisy pixel at (`x`, `y`).
    fn spike(w: usize, h: usize, x: usize, y: usize, v: f64) -> Vec<f64> {
        let mut var = vec![0.01; w * h];
        var[y * w + x] = v;
        var
    }

    #[test]
    fn the_pilot_is_one_sample_to_sixteen_then_a_quarter_and_at_least_four() {
        assert_eq!(pilot(0), None);
        assert_eq!(pilot(1), None);
        for spp in 2..=16 {
            assert_eq!(pilot(spp), Some(1), "{spp} spp");
        }
        assert_eq!(pilot(17), Some(4));
        assert_eq!(pilot(19), Some(4));
        assert_eq!(pilot(20), Some(5));
        assert_eq!(pilot(258), Some(64));
        assert_eq!(pilot(u32::MAX), Some(u32::MAX / 4));
    }

    #[test]
    fn variance_is_the_unbiased_sample_variance_over_rgb() {
        // Samples (1, 0, 2), (3, 0, 2): variance 2 in R, 0 in G and B.
        let sum = Color::new(4.0, 0.0, 4.0);
        let sq = [10.0, 0.0, 8.0, 0.0, 0.0, 0.0];
        assert!((variance(sum, &sq, 2) - 2.0).abs() < 1e-12);
        assert_eq!(variance(sum, &sq, 1), 0.0);
        assert_eq!(variance(Color::new(f32::NAN, 0.0, 0.0), &sq, 2), 0.0);
    }

    /// Checks, for radii 1 to 3, that the count of the pixel (`x`, `y`) of a `w` × `h` image
    /// is the same whether its pilot is loud (noisy), quiet or dear (costly); that its
    /// neighbours' counts rise more than `rise` times when it is loud and fall when it is
    /// dear; and that a pixel outside its block does not rise. `counts(loud, cost, r)`
    /// gives the counts from its loud or quiet pilot and the costs `cost`.
    fn check_own_pilot_unread(
        (w, h, x, y): (usize, usize, usize, usize),
        rise: u32,
        counts: impl Fn(bool, &[f64], usize) -> Vec<u32>,
    ) {
        let cost = vec![1.0; w * h];
        let mut costly = cost.clone();
        costly[y * w + x] = 50.0;
        for r in 1..=3 {
            let quiet = counts(false, &cost, r);
            let loud = counts(true, &cost, r);
            let dear = counts(false, &costly, r);
            assert_eq!(quiet[y * w + x], loud[y * w + x], "radius {r}");
            assert_eq!(quiet[y * w + x], dear[y * w + x], "radius {r}");
            for (a, b) in block(x, y, w, h, r).filter(|&q| q != (x, y)) {
                let p = b * w + a;
                assert!(
                    loud[p] > rise * quiet[p],
                    "radius {r}, neighbour ({a}, {b}): {} vs {}",
                    loud[p],
                    quiet[p]
                );
                assert!(
                    dear[p] < quiet[p],
                    "radius {r}, neighbour ({a}, {b}): {} vs {}",
                    dear[p],
                    quiet[p]
                );
            }
            // A pixel outside the block is not the pixel's neighbour: its count does not
            // rise.
            let outside = (y * w + x) - r - 1;
            assert!(loud[outside] <= quiet[outside], "radius {r}");
        }
    }

    #[test]
    fn a_pixels_count_does_not_read_its_own_pilot() {
        // Large enough that the spike's neighbourhood is a small part of the image.
        let (w, h, x, y) = (31, 27, 15, 13);
        check_own_pilot_unread((w, h, x, y), 4, |loud, cost, r| {
            let v = if loud { 1e4 } else { 0.01 };
            extra_counts(w, h, r, &spike(w, h, x, y, v), cost, 12)
        });
    }

    #[test]
    fn scores_are_the_neighbours_mean_deviation_over_their_root_mean_cost() {
        // 3 x 1: the middle pixel's neighbours have variances 16 and 0 and costs 1 and 3.
        let s = scores(3, 1, 1, &[16.0, 1e6, 0.0], &[1.0, 1e6, 3.0]);
        assert!((s[1] - 2.0 / 2f64.sqrt()).abs() < 1e-12, "{}", s[1]);
        // The ends' one neighbour each: the middle pixel.
        assert!((s[0] - 1e3 / 1e3).abs() < 1e-12 && s[0] == s[2], "{s:?}");
        // No neighbours, or none with a cost: 0.
        assert_eq!(scores(1, 1, 1, &[4.0], &[1.0]), vec![0.0]);
        assert_eq!(scores(2, 1, 1, &[4.0, 4.0], &[0.0, 0.0]), vec![0.0, 0.0]);
    }

    #[test]
    fn the_neighbourhood_holds_enough_pilot_samples() {
        // 8 neighbours from a pilot of 8, the 24 of the 5 x 5 block below.
        assert_eq!(radius(4), 2);
        assert_eq!(radius(7), 2);
        assert_eq!(radius(8), 1);
        assert_eq!(radius(64), 1);
        // A pilot of one: the spread of the 24 samples of its 5 x 5 block.
        assert_eq!(radius(1), 2);
        // Small pilots (which no budget takes now): 2 reads the 48 of its 7 x 7 block, 3
        // the 24 of its 5 x 5.
        assert_eq!(radius(2), 3);
        assert_eq!(radius(3), 2);
        for pilot in 2..100 {
            let r = radius(pilot) as u32;
            assert!(((2 * r + 1).pow(2) - 1) * pilot >= NEIGHBOURHOOD_SAMPLES);
            assert!(r == 1 || ((2 * r - 1).pow(2) - 1) * pilot < NEIGHBOURHOOD_SAMPLES);
        }
    }

    #[test]
    fn counts_share_out_the_budget() {
        let (w, h) = (64, 48);
        let var: Vec<f64> = (0..w * h)
            .map(|p| ((p * 7919) % 101) as f64 / 10.0)
            .collect();
        let cost: Vec<f64> = (0..w * h).map(|p| 1.0 + ((p * 31) % 7) as f64).collect();
        let extra = extra_counts(w, h, 1, &var, &cost, 24);
        let mean = extra.iter().map(|&k| k as f64).sum::<f64>() / (w * h) as f64;
        assert!((mean - 24.0).abs() < 0.5, "mean extra {mean}");
        // Every pixel keeps at least the even share.
        let least = *extra.iter().min().unwrap();
        assert!(least as f64 >= (EVEN_SHARE * 24.0).floor(), "least {least}");
    }

    #[test]
    fn no_noise_shares_evenly_and_one_pixel_takes_at_most_its_cap() {
        let (w, h) = (40, 40);
        let cost = vec![1.0; w * h];
        assert!(extra_counts(w, h, 1, &vec![0.0; w * h], &cost, 10)
            .iter()
            .all(|&k| k == 10));
        // All the noise around one pixel: it is capped.
        let mut var = vec![0.0; w * h];
        for (a, b) in block(20, 20, w, h, 1) {
            var[b * w + a] = 1e9;
        }
        var[20 * w + 20] = 0.0;
        let extra = extra_counts(w, h, 1, &var, &cost, 10);
        assert_eq!(extra[20 * w + 20], (MAX_FACTOR * 10.0) as u32);
        // A 1 × 1 image has no neighbours.
        assert_eq!(extra_counts(1, 1, 2, &[5.0], &[1.0], 6), vec![6]);
    }

    #[test]
    fn outside_sums_leave_the_block_out() {
        // Wide enough for pixels in lanes between the edges' at every radius.
        // Taller than the 2r + 1 rows `BlockRows` holds, so that it replaces rows.
        let (w, h) = (13, 9);
        let score: Vec<f64> = (0..w * h).map(|p| (p * p % 13) as f64 + 0.5).collect();
        for r in 1..=3 {
            let outside = Outside::new(w, h, r, &score);
            // Rows down, up and out of order: `BlockRows` keeps rows from one to the next.
            let mut sums = BlockRows::new(&outside);
            for j in (0..h).chain((0..h).rev()).chain([1, 8, 0, 4, 3]) {
                let got = sums.row(j).to_vec();
                for i in 0..w {
                    let inside: Vec<_> = block(i, j, w, h, r).collect();
                    let want: f64 = (0..w * h)
                        .filter(|p| !inside.contains(&(p % w, p / w)))
                        .map(|p| score[p])
                        .sum();
                    assert_eq!(got[i], want, "radius {r}, pixel ({i}, {j})");
                }
            }
            // Changing a score inside the block leaves the sum's bits as they were; one
            // outside it changes them.
            let sum = |score: &[f64]| {
                let outside = Outside::new(w, h, r, score);
                BlockRows::new(&outside).row(2)[3].to_bits()
            };
            let mut other = score.clone();
            other[(2 + r).min(h - 1) * w + (3 + r).min(w - 1)] = 1e17;
            assert_eq!(sum(&other), sum(&score), "radius {r}");
            let mut other = score.clone();
            other[2 * w] = 1e17;
            if r < 3 {
                assert_ne!(sum(&other), sum(&score), "radius {r}");
            }
        }
    }

    #[test]
    fn outside_sums_add_rows_then_each_block_rows_sides() {
        // Each sum's bits are those of the order the counts were measured with: the rows
        // above the block plus those below it (each row left to right, the rows top to
        // bottom, and those below from the bottom up), then for each block row, top to
        // bottom, its columns left of the block (left to right) plus those right of it
        // (right to left).
        for (w, h) in SIZES.into_iter().chain([(13, 6)]) {
            let score = values(w * h);
            let row = |b: usize| &score[b * w..(b + 1) * w];
            let before = |b: usize, a: usize| row(b)[..a].iter().fold(0.0, |s, x| s + x);
            let from = |b: usize, a: usize| row(b)[a..].iter().rev().fold(0.0, |s, x| s + x);
            let rows_before = |e: usize| (0..e).fold(0.0, |s, b| s + before(b, w));
            let rows_from = |e: usize| (e..h).rev().fold(0.0, |s, b| s + before(b, w));
            for r in 1..=4 {
                let outside = Outside::new(w, h, r, &score);
                let mut rows = BlockRows::new(&outside);
                for j in 0..h {
                    let got = rows.row(j);
                    for (i, got) in got.iter().enumerate() {
                        let Block { cols, rows: ends } = Block::new(i, j, w, h, r);
                        let mut want = rows_before(ends.start) + rows_from(ends.end);
                        for b in ends {
                            want += before(b, cols.start) + from(b, cols.end);
                        }
                        assert_eq!(
                            got.to_bits(),
                            want.to_bits(),
                            "{w} x {h}, radius {r}, pixel ({i}, {j})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn blocks_stop_at_the_image_edges() {
        assert_eq!(block(0, 0, 3, 2, 1).count(), 4);
        assert_eq!(block(1, 1, 3, 3, 1).count(), 9);
        assert_eq!(block(1, 1, 9, 9, 2).count(), 16);
        assert_eq!(block(4, 4, 9, 9, 2).count(), 25);
        assert_eq!(
            block(2, 1, 3, 2, 1).collect::<Vec<_>>(),
            vec![(1, 0), (2, 0), (1, 1), (2, 1)]
        );
        for (i, j, w, h, r) in [
            (0, 0, 3, 2, 1),
            (1, 1, 9, 9, 2),
            (4, 4, 9, 9, 2),
            (5, 0, 6, 1, 3),
        ] {
            assert_eq!(
                Block::new(i, j, w, h, r).len(),
                block(i, j, w, h, r).count()
            );
        }
    }

    /// Images whose blocks are cut by every edge, and smaller than the blocks.
    const SIZES: [(usize, usize); 5] = [(11, 9), (1, 7), (7, 1), (3, 2), (1, 1)];

    /// `n` positive values of many sizes, so that a sum's order shows in its bits.
    fn values(n: usize) -> Vec<f64> {
        (0..n)
            .map(|p| ((p * 7919) % 101) as f64 / 7.0 + 1e-3)
            .collect()
    }

    #[test]
    fn scores_add_the_neighbours_up_row_by_row() {
        // Each score's bits are those of the neighbours' sums taken row by row, left to
        // right, the pixel itself left out: the order the adaptive counts were measured
        // with (a change of order changes some counts, and so the image). Blocks cut by
        // every edge, and blocks larger than the image.
        for (w, h) in SIZES {
            let var = values(w * h);
            let cost: Vec<f64> = (0..w * h)
                .map(|p| 1.0 + ((p * 31) % 13) as f64 / 3.0)
                .collect();
            for r in 1..=5 {
                let got = scores(w, h, r, &var, &cost);
                for p in 0..w * h {
                    let (i, j) = (p % w, p / w);
                    let (mut sd, mut c, mut n) = (0.0, 0.0, 0.0);
                    for (a, b) in block(i, j, w, h, r).filter(|&q| q != (i, j)) {
                        sd += var[b * w + a].sqrt();
                        c += cost[b * w + a];
                        n += 1.0;
                    }
                    let want = if n > 0.0 && c > 0.0 {
                        (sd / n) / (c / n).sqrt()
                    } else {
                        0.0
                    };
                    assert_eq!(
                        got[p].to_bits(),
                        want.to_bits(),
                        "{w} x {h}, radius {r}, pixel ({i}, {j})"
                    );
                }
            }
        }
    }

    #[test]
    fn block_sums_add_columns_then_the_columns_left_and_right() {
        // Each sum's bits are those of the order `block_sums` documents: each column's
        // rows other than the pixel's, top to bottom (`by`); the columns left of the pixel
        // and right of it, each with the pixel's row added last; then its own column's
        // `by`. The pixel itself is never added. Blocks cut by every edge, and blocks
        // larger than the image.
        for (w, h) in SIZES {
            let v = values(w * h);
            for r in 1..=4 {
                let got = block_sums(w, h, r, |p| v[p], |s, _| s);
                let counts = block_sums(w, h, r, |p| v[p], |_, n| n as f64);
                for p in 0..w * h {
                    let (i, j) = (p % w, p / w);
                    let Block { cols, rows } = Block::new(i, j, w, h, r);
                    let by = |a: usize| {
                        let others = rows.clone().filter(|&b| b != j);
                        others.fold(0.0, |s, b| s + v[b * w + a])
                    };
                    let column = |a: usize| by(a) + v[j * w + a];
                    let left = (cols.start..i).fold(0.0, |s, a| s + column(a));
                    let right = (i + 1..cols.end).fold(0.0, |s, a| s + column(a));
                    let want = (left + right) + by(i);
                    assert_eq!(
                        got[p].to_bits(),
                        want.to_bits(),
                        "{w} x {h}, radius {r}, pixel ({i}, {j})"
                    );
                    assert_eq!(counts[p], (cols.len() * rows.len() - 1) as f64);
                }
            }
        }
    }

    #[test]
    fn spread_scores_are_the_neighbours_spread_over_their_root_mean_cost() {
        // 3 x 1: the middle pixel's neighbours are (1, 0, 2) and (3, 2, 2), with costs 1
        // and 3: variance 2 in R and G, 0 in B, 4 in all (so σ 2, not the sum of the
        // channels' deviations, 2√2); mean cost 2; its own sample is not read.
        let samples = [
            Color::new(1.0, 0.0, 2.0),
            Color::new(1e6, -1e6, 1e6),
            Color::new(3.0, 2.0, 2.0),
        ];
        let s = spread_scores(3, 1, 1, &samples, &[1.0, 1e6, 3.0]);
        assert!((s[1] - 2.0 / 2f64.sqrt()).abs() < 1e-12, "{}", s[1]);
        // The ends have one neighbour each, which gives no spread.
        assert_eq!((s[0], s[2]), (0.0, 0.0));
        // Equal samples (whose squares' sums round: 0.1 is not a binary fraction), no
        // cost, or a non-finite sample: 0.
        for v in [1.0, 0.1, 0.7, 3.3e-5] {
            let flat = vec![Color::splat(v); 7 * 5];
            assert_eq!(
                spread_scores(7, 5, 2, &flat, &[1.0; 7 * 5]),
                vec![0.0; 7 * 5],
                "samples {v}"
            );
        }
        assert_eq!(spread_scores(3, 1, 1, &samples, &[0.0; 3])[1], 0.0);
        let inf = [Color::ONE, Color::ONE, Color::INFINITY];
        assert_eq!(spread_scores(3, 1, 1, &inf, &[1.0; 3])[1], 0.0);
        // Not even the other channels' spread, as `variance` gives its pixel none.
        for bad in [f32::INFINITY, f32::NAN] {
            let one = [
                Color::new(bad, 0.0, 0.0),
                Color::ONE,
                Color::new(0.0, 5.0, 0.0),
            ];
            assert_eq!(spread_scores(3, 1, 1, &one, &[1.0; 3])[1], 0.0, "{bad}");
        }
    }

    #[test]
    fn a_pixels_count_does_not_read_its_own_sample_after_a_pilot_of_one() {
        let (w, h, x, y) = (31, 27, 15, 13);
        // Samples that vary a little everywhere, and one that stands out.
        let samples = |v: f32| -> Vec<Color> {
            (0..w * h)
                .map(|p| match p == y * w + x {
                    true => Color::splat(v),
                    false => Color::splat(((p * 7919) % 13) as f32 / 100.0),
                })
                .collect()
        };
        check_own_pilot_unread((w, h, x, y), 2, |loud, cost, r| {
            let v = if loud { 1e3 } else { 0.06 };
            extra_counts_from_samples(w, h, r, &samples(v), cost, 12)
        });
    }

    #[test]
    fn a_pilot_of_one_is_scored_by_the_samples_and_a_larger_one_by_the_variances() {
        let (w, h) = (23, 19);
        let sums: Vec<Color> = (0..w * h)
            .map(|p| Color::new(((p * 7919) % 17) as f32, (p % 5) as f32, 1.0))
            .collect();
        let var: Vec<f64> = (0..w * h).map(|p| ((p * 31) % 11) as f64).collect();
        let cost: Vec<f64> = (0..w * h).map(|p| 1.0 + (p % 3) as f64).collect();
        let after = |pilot| extra_counts_after_pilot(w, h, pilot, &sums, &var, &cost, 9);
        assert_eq!(
            after(1),
            extra_counts_from_samples(w, h, SPREAD_RADIUS, &sums, &cost, 9)
        );
        for pilot in [4, 5, 8, 64] {
            assert_eq!(
                after(pilot),
                extra_counts(w, h, radius(pilot), &var, &cost, 9),
                "pilot {pilot}"
            );
        }
        // The two scores differ here, so the routing shows.
        assert_ne!(after(1), extra_counts(w, h, SPREAD_RADIUS, &var, &cost, 9));
    }
}
