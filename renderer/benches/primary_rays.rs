//! Primary-ray throughput (closest hit, no shading) on N = 1, 100, 10 000 and 1 000 000
//! spheres and on a mesh of about one million triangles. Run with
//! `cargo bench -p renderer --bench primary_rays`; results go to renderer/docs/performance.md.
//!
//! Two sphere families, both filling the same part of the image for every N:
//!
//! - `spheres_front`: N spheres of radius 1/√N on a jittered √N×√N grid in a layer of the
//!   cube [−1, 1]³ facing the camera, so every ray meets the same depth of spheres. This is
//!   the pure O(log N) traversal cost, and the family the ≤ 3× target is stated for
//!   (renderer/docs/performance.md).
//! - `spheres_cloud`: N spheres scattered uniformly in the cube with radius `0.35·N^(−1/3)`
//!   (a constant volume fraction, about 1 %). The cloud's optical depth grows as N^(1/3),
//!   so rays meet more spheres as N grows and the cost grows faster than log N.
//!
//! Each iteration traces the pixel-centre rays of a 128×128 camera on one thread.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use renderer::aggregate::Aggregate;
use std::sync::Arc;

mod common;
use common::{camera, cloud, front, mesh, trace_all, RES};

fn bench(c: &mut Criterion) {
    let cam = camera();
    let mut g = c.benchmark_group("primary_rays");
    g.throughput(Throughput::Elements((RES * RES) as u64));
    g.sample_size(20);
    for (name, family) in [
        ("spheres_front", front as fn(usize) -> Aggregate),
        ("spheres_cloud", cloud),
    ] {
        for n in [1usize, 100, 10_000, 1_000_000] {
            let agg = family(n);
            g.bench_with_input(BenchmarkId::new(name, n), &agg, |b, agg| {
                b.iter(|| trace_all(&cam, agg))
            });
        }
    }
    let m = Arc::new(mesh(1000, 500));
    let agg = common::one_mesh(m.clone());
    g.bench_with_input(
        BenchmarkId::new("mesh_triangles", m.triangles.len()),
        &agg,
        |b, agg| b.iter(|| trace_all(&cam, agg)),
    );
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
