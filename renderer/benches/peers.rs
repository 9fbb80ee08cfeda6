//! Our side of `scripts/bench-peers.sh` (wall clock, side by side with the peers).
//!
//! - `peers mesh DIR [--quick]`: builds the ~1M-triangle mesh (784 icospheres of 1,280
//!   triangles over a ground quad), writes it and four ray sets (coherent primary, shuffled
//!   primary, occlusion toward a light, diffuse bounce) to DIR as raw little-endian arrays
//!   for Embree (embreex) to read, then times our single-ray closest hit (and any hit for
//!   the occlusion rays) on 1 and 2 threads, and the BVH build. Prints JSON.
//! - `peers growth [--quick]`: time per primary ray from 100 to 10⁶ primitives, for
//!   spheres and for triangles. Prints JSON.
//!
//! Run it through the script: `cargo bench -p renderer --bench peers -- mesh DIR`.

use glam::DVec3;
use renderer::aggregate::Aggregate;
use renderer::ray::Ray;
use renderer::real::{Real, Vec3};
use renderer::shapes::Mesh;
use std::fmt::Write;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

mod common;

/// A deterministic uniform number in [0, 1).
fn rnd(state: &mut u64) -> f64 {
    *state = renderer::sampler::mix64(state.wrapping_add(0x9e37_79b9_7f4a_7c15));
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// An icosphere: the icosahedron subdivided `levels` times (20·4^levels triangles).
fn icosphere(levels: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::BTreeMap::new();
        let mut split = |a: u32, b: u32, v: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (
                split(a, b, &mut v),
                split(b, c, &mut v),
                split(c, a, &mut v),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// 784 icospheres (28 × 28, 1,280 triangles each) over a ground quad: 1,003,522 triangles.
fn big_mesh() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (sv, sf) = icosphere(3);
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    let mut s = 11u64;
    for gz in 0..28 {
        for gx in 0..28 {
            let r = 0.25 + 0.15 * rnd(&mut s);
            let c = DVec3::new(gx as f64 - 13.5, r, gz as f64 - 13.5);
            let base = pos.len() as u32;
            pos.extend(sv.iter().map(|p| {
                let q = c + *p * r;
                Vec3::new(q.x as Real, q.y as Real, q.z as Real)
            }));
            tris.extend(sf.iter().map(|t| t.map(|k| k + base)));
        }
    }
    let base = pos.len() as u32;
    for (x, z) in [(-20.0, -20.0), (20.0, -20.0), (20.0, 20.0), (-20.0, 20.0)] {
        pos.push(Vec3::new(x, 0.0, z));
    }
    tris.push([base, base + 2, base + 1]);
    tris.push([base, base + 3, base + 2]);
    (pos, tris)
}

struct RaySet {
    name: &'static str,
    rays: Vec<(Ray, Real)>,
}

fn camera(w: u32, h: u32) -> renderer::camera::Camera {
    let m = renderer::camera::ViewingModel::look_at(
        DVec3::new(0.0, 9.0, -22.0),
        DVec3::new(0.0, 0.0, -2.0),
        DVec3::Y,
        55.0,
        renderer::camera::FovAxis::Horizontal,
        w,
        h,
    )
    .unwrap();
    renderer::camera::Camera::new(m).unwrap()
}

/// The four ray sets, all from the same camera: primary rays in pixel order and shuffled,
/// shadow rays from each primary hit to a light (t < 1), and cosine-distributed bounce
/// rays from each primary hit.
fn ray_sets(agg: &Aggregate, w: u32, h: u32) -> Vec<RaySet> {
    let cam = camera(w, h);
    let inf = Real::INFINITY;
    let primary: Vec<(Ray, Real)> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| (cam.pixel_ray(i, j), inf))
        .collect();
    let mut shuffled = primary.clone();
    let mut s = 5u64;
    for k in (1..shuffled.len()).rev() {
        let j = (rnd(&mut s) * (k + 1) as f64) as usize;
        shuffled.swap(k, j.min(k));
    }
    let light = Vec3::new(-30.0, 40.0, -25.0);
    let (mut shadow, mut bounce) = (Vec::new(), Vec::new());
    for (r, _) in &primary {
        if let Some(hit) = agg.intersect(r, 0.0, inf) {
            let n = hit.n_geo.normalize();
            let n = if n.dot(r.d) > 0.0 { -n } else { n };
            let o = hit.p + n * 1e-3;
            shadow.push((Ray::new(o, light - o), 1.0));
            // Cosine-weighted about n.
            let (u1, u2) = (rnd(&mut s), rnd(&mut s));
            let (rr, ph) = (u1.sqrt(), 2.0 * std::f64::consts::PI * u2);
            let nd = DVec3::new(n.x as f64, n.y as f64, n.z as f64);
            let a = if nd.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
            let t = nd.cross(a).normalize();
            let b = nd.cross(t);
            let d = t * (rr * ph.cos()) + b * (rr * ph.sin()) + nd * (1.0 - u1).sqrt();
            bounce.push((
                Ray::new(o, Vec3::new(d.x as Real, d.y as Real, d.z as Real)),
                inf,
            ));
        }
    }
    vec![
        RaySet {
            name: "coherent",
            rays: primary,
        },
        RaySet {
            name: "shuffled",
            rays: shuffled,
        },
        RaySet {
            name: "occlusion",
            rays: shadow,
        },
        RaySet {
            name: "bounce",
            rays: bounce,
        },
    ]
}

/// Writes numbers as little-endian f32 (what embreex reads; the f64 build rounds).
fn write_f32(path: &Path, data: impl Iterator<Item = Real>) {
    let bytes: Vec<u8> = data.flat_map(|x| (x as f32).to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// Writes little-endian u32.
fn write_u32(path: &Path, data: impl Iterator<Item = u32>) {
    let bytes: Vec<u8> = data.flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// What one ray's search stores, as Embree's `rtcIntersect1` and `rtcOccluded1` do: for a
/// closest hit the distance and the primitive (`f32::INFINITY` and `u32::MAX` on a miss),
/// for any hit whether there is one. Every ray's result is written to memory, so no part
/// of a search can be optimised away, on our side or on Embree's.
type Store<'a> = dyn Fn(&[(Ray, Real)], &mut [(f32, u32)]) + Sync + 'a;

/// A [`Store`] that takes the rays one at a time.
fn each_ray(
    f: impl Fn(&Ray, Real, &mut (f32, u32)) + Sync,
) -> impl Fn(&[(Ray, Real)], &mut [(f32, u32)]) + Sync {
    move |rays, out| {
        for ((r, t), o) in rays.iter().zip(out) {
            f(r, *t, o);
        }
    }
}

/// What a [`Store`] keeps of a closest hit, its distance and primitive: `f32::INFINITY`
/// and `u32::MAX` on a miss.
fn as_stored(hit: Option<(Real, u32)>) -> (f32, u32) {
    match hit {
        Some((t, prim)) => (t as f32, prim),
        None => (f32::INFINITY, u32::MAX),
    }
}

/// The rays of a chunk and their common `t_max`, for the calls that take many rays at
/// once (every ray set has one `t_max` for all its rays).
fn as_stream(rays: &[(Ray, Real)]) -> (Vec<Ray>, Real) {
    let t = rays[0].1;
    assert!(rays.iter().all(|r| r.1 == t), "one t_max for the chunk");
    (rays.iter().map(|r| r.0).collect(), t)
}

/// Rays per second (millions) of `f` over `rays` on `threads` threads, repeated for at
/// least `secs` seconds, each ray's result stored in `out`; returns (Mrays/s, the number
/// of rays whose stored primitive is not `u32::MAX`).
fn time_rays(
    rays: &[(Ray, Real)],
    threads: usize,
    secs: f64,
    out: &mut [(f32, u32)],
    f: &Store<'_>,
) -> (f64, usize) {
    use rayon::prelude::*;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut run = || {
            rays.par_chunks(4096)
                .zip(out.par_chunks_mut(4096))
                .for_each(|(c, o)| f(c, o))
        };
        run();
        let t0 = Instant::now();
        let mut n = 0usize;
        while t0.elapsed().as_secs_f64() < secs {
            run();
            n += rays.len();
        }
        let rate = n as f64 / t0.elapsed().as_secs_f64() / 1e6;
        (rate, out.iter().filter(|o| o.1 != u32::MAX).count())
    })
}

fn mesh(dir: &Path, quick: bool) {
    std::fs::create_dir_all(dir).unwrap();
    let (pos, tris) = big_mesh();
    let t0 = Instant::now();
    let m = Mesh::new(pos.clone(), None, None, tris.clone()).unwrap();
    let agg = common::one_mesh(Arc::new(m));
    let build = t0.elapsed().as_secs_f64();
    let (w, h) = (640, 480);
    let sets = ray_sets(&agg, w, h);
    write_f32(
        &dir.join("vertices.f32"),
        pos.iter().flat_map(|p| [p.x, p.y, p.z]),
    );
    write_u32(&dir.join("indices.u32"), tris.iter().flatten().copied());
    let secs = if quick { 0.3 } else { 2.0 };
    let mut json = format!(
        "{{\"triangles\": {}, \"build_seconds\": {build:.4}, \"sets\": [",
        tris.len()
    );
    for (k, set) in sets.iter().enumerate() {
        write_f32(
            &dir.join(format!("rays_{}.f32", set.name)),
            set.rays
                .iter()
                .flat_map(|(r, t)| [r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, *t]),
        );
        // The closest hit as Embree reports one (`Aggregate::nearest`: distance,
        // geometric normal, barycentrics, surface and primitive; the whole record goes
        // through `black_box`, so none of it is left uncomputed), and with our full
        // shading record (`Aggregate::intersect`: also the point and its error bound, the
        // shading normal, the uv and the material), which the renderer's integrators use.
        // Also, as streams: our calls that take many rays at once and walk them 16 at a
        // time interleaved (`Aggregate::intersect_many`, what the renderer's camera rays
        // use, with the full record; `Aggregate::occluded_many`), against the same
        // single-ray Embree figures (Embree 4 has no stream call; its packets are not in
        // embreex).
        let closest = each_ray(|r: &Ray, t: Real, o: &mut (f32, u32)| {
            *o = as_stored(std::hint::black_box(agg.nearest(r, 0.0, t)).map(|h| (h.t, h.prim)))
        });
        let record = each_ray(|r: &Ray, t: Real, o: &mut (f32, u32)| {
            *o = as_stored(agg.intersect(r, 0.0, t).map(|h| (h.t, h.prim)))
        });
        let any = each_ray(|r: &Ray, t: Real, o: &mut (f32, u32)| {
            o.1 = if agg.occluded(r, 0.0, t) { 0 } else { u32::MAX }
        });
        let record_stream = |rays: &[(Ray, Real)], out: &mut [(f32, u32)]| {
            let (rays, t) = as_stream(rays);
            let mut hits = vec![None; rays.len()];
            agg.intersect_many(&rays, 0.0, t, &mut hits);
            for (o, h) in out.iter_mut().zip(hits) {
                *o = as_stored(h.map(|h| (h.t, h.prim)))
            }
        };
        let any_stream = |rays: &[(Ray, Real)], out: &mut [(f32, u32)]| {
            let (rays, t) = as_stream(rays);
            let mut hits = vec![false; rays.len()];
            agg.occluded_many(&rays, 0.0, t, &mut hits);
            for (o, h) in out.iter_mut().zip(hits) {
                o.1 = if h { 0 } else { u32::MAX }
            }
        };
        let mut stored = vec![(0f32, 0u32); set.rays.len()];
        let mut parts = Vec::new();
        for threads in [1, 2] {
            let (c, hc) = time_rays(&set.rays, threads, secs, &mut stored, &closest);
            if threads == 1 {
                // Our closest hits, for the script to compare with Embree's ray by ray.
                write_f32(
                    &dir.join(format!("ours_t_{}.f32", set.name)),
                    stored.iter().map(|o| o.0 as Real),
                );
                write_u32(
                    &dir.join(format!("ours_prim_{}.u32", set.name)),
                    stored.iter().map(|o| o.1),
                );
            }
            let (f, hf) = time_rays(&set.rays, threads, secs, &mut stored, &record);
            let (a, ha) = time_rays(&set.rays, threads, secs, &mut stored, &any);
            let (fs, hfs) = time_rays(&set.rays, threads, secs, &mut stored, &record_stream);
            let (s, hs) = time_rays(&set.rays, threads, secs, &mut stored, &any_stream);
            for (what, h) in [
                ("intersect", hf),
                ("occluded", ha),
                ("intersect_many", hfs),
                ("occluded_many", hs),
            ] {
                assert_eq!(hc, h, "nearest and {what} disagree on {}", set.name);
            }
            parts.push(format!(
                "{{\"threads\": {threads}, \"closest_mrays\": {c:.4}, \"record_mrays\": {f:.4}, \"any_mrays\": {a:.4}, \"record_stream_mrays\": {fs:.4}, \"any_stream_mrays\": {s:.4}, \"hits\": {hc}}}"
            ));
        }
        write!(
            json,
            "{}{{\"name\": \"{}\", \"rays\": {}, \"runs\": [{}]}}",
            if k > 0 { ", " } else { "" },
            set.name,
            set.rays.len(),
            parts.join(", ")
        )
        .unwrap();
    }
    json.push_str("]}");
    println!("{json}");
}

/// One pass of closest hit (any hit for `SET-any`) over one ray set of the mesh
/// benchmark, on one thread, with no timing loop: for Callgrind (`valgrind
/// --tool=callgrind --toggle-collect='peers::trace_set*' BENCH profile shuffled`, BENCH
/// being target/release/deps/peers-HASH, not its `.d` file), which then counts the
/// traversal alone. `passes` > 1 repeats it, for a sampling profiler
/// (`perf record -e cpu-clock`), whose samples would otherwise fall mostly in the build.
fn profile(set: &str, passes: usize) {
    if let Some(n) = set.strip_prefix("growth-") {
        return profile_growth(n, passes);
    }
    // `SET-any` profiles the search for any hit (`Aggregate::occluded`) instead, and
    // `SET-nearest` the closest hit as Embree reports one (`Aggregate::nearest`).
    let (name, any, nearest) = match (set.strip_suffix("-any"), set.strip_suffix("-nearest")) {
        (Some(name), _) => (name, true, false),
        (_, Some(name)) => (name, false, true),
        _ => (set, false, false),
    };
    let (pos, tris) = big_mesh();
    let agg = common::one_mesh(Arc::new(Mesh::new(pos, None, None, tris).unwrap()));
    let sets = ray_sets(&agg, 640, 480);
    let Some(s) = sets.iter().find(|s| s.name == name) else {
        eprintln!(
            "no ray set {name} (coherent, shuffled, occlusion, bounce; each also as NAME-any or NAME-nearest)"
        );
        std::process::exit(2);
    };
    let mut hits = 0;
    let t0 = Instant::now();
    for _ in 0..passes.max(1) {
        hits = if any {
            trace_set_any(&agg, &s.rays)
        } else if nearest {
            trace_set_nearest(&agg, &s.rays)
        } else {
            trace_set(&agg, &s.rays)
        };
    }
    let rate = (passes.max(1) * s.rays.len()) as f64 / t0.elapsed().as_secs_f64() / 1e6;
    println!(
        "{set}: {} rays, {hits} hits, {rate:.3} Mrays/s over {} pass(es)",
        s.rays.len(),
        passes.max(1)
    );
}

/// `peers profile growth-N PASSES`: passes of the cost-growth scene of N triangles (100,
/// 10000 or 1000000: the UV spheres `growth` times), 128² primary rays through
/// `intersect_many` as there. Under Callgrind, count the passes alone with
/// `--toggle-collect='peers::common::trace_all'` (a function of its own in this binary).
fn profile_growth(n: &str, passes: usize) {
    let Some(&(nu, nv)) = GROWTH_MESHES
        .iter()
        .find(|&&(nu, nv)| n.parse() == Ok(2 * nu * nv))
    else {
        eprintln!("no growth scene of {n} triangles (100, 10000, 1000000)");
        std::process::exit(2);
    };
    let agg = common::one_mesh(Arc::new(common::mesh(nu, nv)));
    let cam = common::camera();
    let mut hits = 0;
    let t0 = Instant::now();
    for _ in 0..passes.max(1) {
        hits = common::trace_all(&cam, &agg);
    }
    let rays = common::RES * common::RES;
    let ns = t0.elapsed().as_secs_f64() * 1e9 / (passes.max(1) * rays as usize) as f64;
    println!(
        "growth-{n}: {rays} rays, {hits} hits, {ns:.2} ns/ray over {} pass(es)",
        passes.max(1)
    );
}

#[inline(never)]
fn trace_set(agg: &Aggregate, rays: &[(Ray, Real)]) -> usize {
    rays.iter()
        .filter(|(r, t)| agg.intersect(r, 0.0, *t).is_some())
        .count()
}

/// [`trace_set`] for the closest hit as Embree reports one (under Callgrind:
/// `--toggle-collect='peers::trace_set_nearest'`).
#[inline(never)]
fn trace_set_nearest(agg: &Aggregate, rays: &[(Ray, Real)]) -> usize {
    rays.iter()
        .filter(|(r, t)| std::hint::black_box(agg.nearest(r, 0.0, *t)).is_some())
        .count()
}

/// [`trace_set`] for any hit (under Callgrind: `--toggle-collect='peers::trace_set_any'`).
#[inline(never)]
fn trace_set_any(agg: &Aggregate, rays: &[(Ray, Real)]) -> usize {
    rays.iter()
        .filter(|(r, t)| agg.occluded(r, 0.0, *t))
        .count()
}

/// Seconds per primary ray of one pass of the 128² pixel centres (one thread) on `agg`.
fn per_ray(agg: &Aggregate) -> f64 {
    let cam = common::camera();
    let t0 = Instant::now();
    std::hint::black_box(common::trace_all(&cam, agg));
    t0.elapsed().as_secs_f64() / (common::RES * common::RES) as f64
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// Times the scenes of one family (N = 100, 10⁴, 10⁶) alternately, one pass each per
/// round, so a slow phase of the machine falls on all of them; returns the JSON rows:
/// median ns/ray per N, and for the largest N the median and range of the per-round
/// ratios to N = 100.
fn growth_family(kind: &str, scenes: &[(usize, Aggregate)], rounds: usize) -> Vec<String> {
    let mut times = vec![Vec::new(); scenes.len()];
    for (_, agg) in scenes {
        per_ray(agg); // warm-up
    }
    for _ in 0..rounds {
        for (k, (_, agg)) in scenes.iter().enumerate() {
            times[k].push(per_ray(agg));
        }
    }
    let last = scenes.len() - 1;
    let ratios: Vec<f64> = (0..rounds).map(|r| times[last][r] / times[0][r]).collect();
    let (lo, hi) = ratios
        .iter()
        .fold((f64::INFINITY, 0f64), |(a, b), &x| (a.min(x), b.max(x)));
    let ratio = median(ratios);
    scenes
        .iter()
        .zip(times)
        .enumerate()
        .map(|(k, ((n, _), t))| {
            let extra = if k == last {
                format!(", \"ratio_to_first\": {ratio:.3}, \"ratio_min\": {lo:.3}, \"ratio_max\": {hi:.3}, \"rounds\": {rounds}")
            } else {
                String::new()
            };
            format!(
                "{{\"kind\": \"{kind}\", \"n\": {n}, \"ns_per_ray\": {:.2}{extra}}}",
                median(t) * 1e9
            )
        })
        .collect()
}

/// The cost-growth meshes: UV spheres of `2·nu·nv` triangles, 100, 10,000 and 1,000,000
/// (`growth` times them, `profile growth-N` profiles one).
const GROWTH_MESHES: [(usize, usize); 3] = [(10, 5), (100, 50), (1000, 500)];

fn growth(quick: bool) {
    let rounds = if quick { 5 } else { 21 };
    let ns = [100usize, 10_000, 1_000_000];
    let mut rows = Vec::new();
    // Spheres in a layer facing the camera (the image covered the same at every N) and
    // in a cloud filling a cube (deeper for larger N).
    for (kind, make) in [
        (
            "spheres (front layer)",
            common::front as fn(usize) -> Aggregate,
        ),
        ("spheres (cloud)", common::cloud),
    ] {
        let scenes: Vec<_> = ns.iter().map(|&n| (n, make(n))).collect();
        rows.extend(growth_family(kind, &scenes, rounds));
    }
    let meshes: Vec<_> = GROWTH_MESHES
        .iter()
        .map(|&(nu, nv)| {
            (
                2 * nu * nv,
                common::one_mesh(Arc::new(common::mesh(nu, nv))),
            )
        })
        .collect();
    rows.extend(growth_family("triangles", &meshes, rounds));
    println!("{{\"growth\": [{}]}}", rows.join(", "));
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let quick = args.iter().any(|a| a == "--quick");
    match args.first().map(String::as_str) {
        Some("mesh") => mesh(Path::new(args.get(1).expect("peers mesh DIR")), quick),
        Some("growth") => growth(quick),
        Some("profile") => profile(
            args.get(1).map(String::as_str).unwrap_or("coherent"),
            match args.get(2).map(|n| n.parse::<usize>()) {
                None => 1,
                Some(Ok(n)) => n,
                Some(Err(e)) => {
                    eprintln!("peers profile SET [PASSES]: PASSES {:?}: {e}", args[2]);
                    std::process::exit(2);
                }
            },
        ),
        _ => {
            eprintln!("usage: peers mesh DIR [--quick] | peers growth [--quick] | peers profile SET[-any|-nearest]|growth-N [PASSES] (see scripts/bench-peers.sh)");
            std::process::exit(2);
        }
    }
}
