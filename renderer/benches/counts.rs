//! Instruction counts of the paths users pay for, under Callgrind (gungraun): BVH build
//! (N = 100 and 10⁵ spheres; 10⁶ takes almost three minutes under Callgrind) and primary
//! rays on spheres (N = 100 and 10⁶), build and primary rays on a 100,000-triangle mesh, a classic
//! Whitted frame (shadows, reflection, refraction), a `direct` and a `path` frame of the
//! physical model, and scene parsing. Counts do not move with the machine's load, so
//! `scripts/bench-counts.sh` compares them with `renderer/benches/baseline.json` and fails
//! on growth beyond the stated limit. Setup (scene construction for the trace benchmarks)
//! is not counted, and neither is freeing what a benchmark built or was given: each
//! returns it to `drop` as its `teardown`, outside the count (a million-instance
//! aggregate's drop had been a fifth of `primary_spheres.spheres_1e6`'s count, and
//! moved it by +23 % when the drop glue of `Shape` stopped being inlined: see
//! renderer/docs/performance.md). Everything runs on one thread, so the counts are
//! deterministic.

use gungraun::prelude::*;
use renderer::aggregate::Aggregate;
use renderer::render::{render, Options};
use renderer::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

mod common;

const CATALOG: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../conformance/scenes");

/// The 100,000-triangle mesh as the only instance of an aggregate.
fn mesh_scene() -> Aggregate {
    common::one_mesh(Arc::new(common::mesh(250, 200)))
}

fn catalog_scene(rel: &str) -> Scene {
    Scene::load(&Path::new(CATALOG).join(rel)).expect("a catalog scene")
}

fn one_thread(samples: Option<u32>) -> Options {
    // No `threads`: the render runs in the pool `frame` installs.
    Options {
        samples,
        ..Options::default()
    }
}

#[library_benchmark(teardown = drop)]
#[bench::spheres_100(100)]
#[bench::spheres_1e5(100_000)]
fn build_spheres(n: usize) -> Aggregate {
    black_box(common::cloud(black_box(n)))
}

#[library_benchmark(teardown = drop)]
fn build_mesh() -> Aggregate {
    black_box(mesh_scene())
}

#[library_benchmark(teardown = drop)]
#[bench::spheres_100(args = (100,), setup = common::cloud)]
#[bench::spheres_1e6(args = (1_000_000,), setup = common::cloud)]
fn primary_spheres(agg: Aggregate) -> (u32, Aggregate) {
    let hits = black_box(common::trace_all(&common::camera(), black_box(&agg)));
    (hits, agg)
}

#[library_benchmark(teardown = drop)]
#[bench::mesh_1e5(setup = mesh_scene)]
fn primary_mesh(agg: Aggregate) -> (u32, Aggregate) {
    let hits = black_box(common::trace_all(&common::camera(), black_box(&agg)));
    (hits, agg)
}

#[library_benchmark(teardown = drop)]
#[bench::whitted(args = ("povray/shade_refract_sphere.toml", None), setup = frame_setup)]
#[bench::direct(args = ("mitsuba/mi_area_soft_shadow.toml", Some(4)), setup = frame_setup)]
#[bench::path_cornell(args = ("mitsuba/mi_cornell.toml", Some(4)), setup = frame_setup)]
fn frame(input: (Scene, Options)) -> (usize, (Scene, Options)) {
    // A one-thread pool that runs on this thread, so Callgrind counts the whole frame.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .expect("a one-thread pool");
    let img = pool.install(|| render(black_box(&input.0), &input.1));
    (black_box(img.rgb.len()), input)
}

fn frame_setup(rel: &str, samples: Option<u32>) -> (Scene, Options) {
    (catalog_scene(rel), one_thread(samples))
}

#[library_benchmark(teardown = drop)]
#[bench::hier_three_levels("povray/hier_three_levels.toml")]
#[bench::cornell("mitsuba/mi_cornell.toml")]
fn parse(rel: &str) -> Scene {
    let path = Path::new(CATALOG).join(rel);
    let text = std::fs::read_to_string(&path).unwrap();
    black_box(Scene::from_str(black_box(&text), &path, path.parent().unwrap()).unwrap())
}

library_benchmark_group!(name = build, benchmarks = [build_spheres, build_mesh]);
library_benchmark_group!(name = trace, benchmarks = [primary_spheres, primary_mesh]);
library_benchmark_group!(name = frames, benchmarks = [frame, parse]);

main!(library_benchmark_groups = build, trace, frames);
