//! The scaling target as a paired measurement: primary-ray cost at N = 10⁶ spheres over
//! N = 100, for the `front` and `cloud` families of primary_rays.rs (same scenes, same
//! 128×128 camera, one thread).
//!
//! Run with `cargo bench -p renderer --bench scaling`. Both scenes are built once; the
//! two are then timed alternately, one pass each, 31 times. Each pair is taken within a
//! few milliseconds, so a slow phase of the shared machine (other tenants on the shared
//! L3 cache and memory) hits both halves of a pair; the median of the 31 per-pair ratios
//! is the figure reported in renderer/docs/performance.md, beside the spread.

use std::time::Instant;

mod common;
use common::{camera, cloud, front, trace_all};

const PAIRS: usize = 31;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn main() {
    let cam = camera();
    println!("family   median ms (N = 100)   median ms (N = 10^6)   ratio: median [min, max] of {PAIRS} pairs");
    for (name, family) in [
        ("front", front as fn(usize) -> renderer::Aggregate),
        ("cloud", cloud),
    ] {
        let (small, big) = (family(100), family(1_000_000));
        let time = |agg: &renderer::Aggregate| {
            let t = Instant::now();
            std::hint::black_box(trace_all(&cam, agg));
            t.elapsed().as_secs_f64() * 1e3
        };
        for _ in 0..3 {
            time(&small);
            time(&big);
        }
        let (mut ts, mut tb, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..PAIRS {
            let (s, b) = (time(&small), time(&big));
            ts.push(s);
            tb.push(b);
            ratios.push(b / s);
        }
        let (lo, hi) = (
            ratios.iter().copied().fold(f64::INFINITY, f64::min),
            ratios.iter().copied().fold(0.0, f64::max),
        );
        println!(
            "{name:<8} {:>19.2} {:>22.2}   {:.2} [{lo:.2}, {hi:.2}]",
            median(&mut ts),
            median(&mut tb),
            median(&mut ratios)
        );
    }
}
