"""Embree 4 (embreex) against our peers bench, for scripts/bench_peers.py.

Embree is run as its own users run it: its default scene flags (`robust=False` in
embreex, whose own default is Embree's opt-in robust mode, which is timed as a second
column), single-ray queries (`rtcIntersect1`, `rtcOccluded1`), and as many threads as
ours: embreex releases the GIL inside `run`, so Python threads, each taking chunks of
the rays from a shared queue as rayon's workers do on our side, trace in parallel.
Both sides store every ray's result: Embree its hit record (`output=True`: distance,
primitive, u, v and normal) or its occlusion flag, ours the distance and the primitive,
or the flag. Our closest hit is timed twice: as Embree reports one
(`Aggregate::nearest`: distance, normal, barycentrics, surface and primitive, the
headline) and with our full shading record (`Aggregate::intersect`, what the renderer's
integrators use; the "our full record" rows), each against the same Embree figures. The
"our stream" rows time our calls that take many rays at once and walk 16 of them
interleaved (`Aggregate::intersect_many`, which the renderer's camera rays use, and
`Aggregate::occluded_many`) against the same single-ray Embree figures: Embree 4 has no
stream call and embreex does not expose its packets, so that choice favours us. Our
closest hits are compared with Embree's ray by ray.
"""

import os
import threading
import time

from peers_common import med, peers_bench, spread

# Rays per `run` call: large enough that Python's part of a call is a fraction of a per
# cent of Embree's work, small enough that two threads share the work evenly.
CHUNK = 16384


def embree_scene(v, idx, robust):
    """An embreex scene of the mesh, committed; returns (scene, build seconds)."""
    import embreex.mesh_construction as mc
    import embreex.rtcore_scene as rtcs
    import numpy as np

    t0 = time.perf_counter()
    scene = rtcs.EmbreeScene(robust=robust)
    mc.TriangleMesh(scene, v, idx)
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commits the BVH
    return scene, time.perf_counter() - t0


def trace(scene, o, d, tmax, query, threads):
    """One pass over the rays on `threads` threads; returns the stored results: for a
    closest hit (distance, primitive), for any hit the occlusion flags."""
    import numpy as np

    n = len(o)
    t_out, p_out = np.empty(n, np.float32), np.empty(n, np.int32)
    chunks = list(range(0, n, CHUNK))
    lock = threading.Lock()

    def worker():
        while True:
            with lock:
                if not chunks:
                    return
                a = chunks.pop()
            b = min(a + CHUNK, n)
            # `run` writes the hit distances into the array it is given: a copy.
            if query == "INTERSECT":
                r = scene.run(o[a:b], d[a:b], dists=tmax[a:b].copy(), query=query, output=True)
                t_out[a:b], p_out[a:b] = r["tfar"], r["primID"]
            else:
                p_out[a:b] = scene.run(o[a:b], d[a:b], dists=tmax[a:b].copy(), query=query)

    if threads == 1:
        worker()
    else:
        pool = [threading.Thread(target=worker) for _ in range(threads)]
        for t in pool:
            t.start()
        for t in pool:
            t.join()
    return t_out, p_out


def rate(scene, o, d, tmax, query, threads, secs):
    """Mrays/s of `trace` repeated for at least `secs` seconds (after one pass untimed)."""
    trace(scene, o, d, tmax, query, threads)
    t0, n = time.perf_counter(), 0
    while time.perf_counter() - t0 < secs:
        trace(scene, o, d, tmax, query, threads)
        n += len(o)
    return n / (time.perf_counter() - t0) / 1e6


def agreement(d, name, t, prim):
    """How our closest hits of ray set `name` (written by the peers bench) compare with
    Embree's `t` and `prim`: (rays, same hit or miss, same primitive, the largest relative
    distance difference among rays that hit the same primitive)."""
    import numpy as np

    ot = np.fromfile(os.path.join(d, f"ours_t_{name}.f32"), dtype=np.float32)
    op = np.fromfile(os.path.join(d, f"ours_prim_{name}.u32"), dtype=np.uint32).astype(np.int64)
    op[op == 0xFFFFFFFF] = -1
    ehit, ohit = prim >= 0, op >= 0
    same = (prim == op) & ehit
    rel = np.abs(ot[same].astype(np.float64) - t[same]) / np.maximum(np.abs(t[same]), 1e-30)
    return len(op), int((ehit == ohit).sum()), int(same.sum() + (~ehit & ~ohit).sum()), float(rel.max(initial=0.0))


def embree(outdir, quick):
    import numpy as np

    d = os.path.join(outdir, "mesh")
    secs = 0.3 if quick else 2.0
    pairs = 1 if quick else 3
    # Ours (the peers bench, which also writes the mesh, the rays and our hits) and Embree
    # alternate, `pairs` times; each row reports the medians and the range of the per-pair
    # ratios.
    samples, names, order = {}, {}, []
    agree = {}

    def add(key, name, a, b, c):
        if key not in samples:
            samples[key], names[key] = [], name
            order.append(key)
        samples[key].append((a, b, c))

    for _ in range(pairs):
        ours = peers_bench("mesh", d, *(["--quick"] if quick else []))
        v = np.fromfile(os.path.join(d, "vertices.f32"), dtype=np.float32).reshape(-1, 3)
        idx = np.fromfile(os.path.join(d, "indices.u32"), dtype=np.uint32).reshape(-1, 3).astype(np.int32)
        fast, fast_build = embree_scene(v, idx, robust=False)
        robust, robust_build = embree_scene(v, idx, robust=True)
        add("build", "BVH build, 1M triangles (s; Embree builds on every core, ours on one)",
            ours["build_seconds"], fast_build, robust_build)
        for s in ours["sets"]:
            r = np.fromfile(os.path.join(d, f"rays_{s['name']}.f32"), dtype=np.float32).reshape(-1, 7)
            o, dirs = np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:6])
            tmax = np.ascontiguousarray(r[:, 6])
            tmax = np.where(np.isinf(tmax), np.float32(1e30), tmax).astype(np.float32)
            t, prim = trace(fast, o, dirs, tmax, "INTERSECT", 1)
            agree[s["name"]] = agreement(d, s["name"], t, prim)
            for run in s["runs"]:
                th = run["threads"]
                peer = {q: (rate(fast, o, dirs, tmax, q, th, secs), rate(robust, o, dirs, tmax, q, th, secs))
                        for q in ("INTERSECT", "OCCLUDED")}
                for q, kind, ours_rate in (("INTERSECT", "closest hit", run["closest_mrays"]),
                                           ("INTERSECT", "closest hit, our full record", run["record_mrays"]),
                                           ("INTERSECT", "closest hit, our full record, our stream", run["record_stream_mrays"]),
                                           ("OCCLUDED", "any hit", run["any_mrays"]),
                                           ("OCCLUDED", "any hit, our stream", run["any_stream_mrays"])):
                    add((s["name"], kind, th), f"{s['name']}: {kind}, {th} thread{'s' if th > 1 else ''} each (Mrays/s)",
                        ours_rate, *peer[q])
        del fast, robust
    rows = []
    for key in order:
        ab = samples[key]
        build = key == "build"
        # A ratio above 1 means we are faster (for the build, below 1).
        r1 = [a / b for a, b, _ in ab]
        r2 = [a / c for a, _, c in ab]
        rows.append({"measurement": names[key], "ours": med([a for a, _, _ in ab]),
                     "embree": med([b for _, b, _ in ab]), "embree_robust": med([c for _, _, c in ab]),
                     "ratio": med(r1), "spread": spread(r1), "ratio_robust": med(r2), "spread_robust": spread(r2),
                     "build": build, "key": list(key) if isinstance(key, tuple) else key})
    md = ["### Embree 4 (embreex), the same 1M-triangle mesh and rays, as many threads each", "",
          f"{ours['triangles']:,} triangles, 640 x 480 camera rays; {pairs} alternating pair(s) (ours, then Embree). "
          "Embree in its default mode (the headline) and in robust mode (embreex's default, an opt-in in Embree "
          "that trades speed for watertightness), single-ray queries, on as many threads as ours (Python threads "
          f"taking {CHUNK:,}-ray chunks from a queue; embreex releases the GIL inside `run`). Both sides store "
          "every ray's result. Our closest hit reports what Embree's does (`Aggregate::nearest`: distance, normal, "
          "barycentrics, surface, primitive); the \"our full record\" rows time `Aggregate::intersect`, which "
          "also builds the point, its error bound, the shading normal, the uv and the material, against the "
          "same Embree figures. The \"our stream\" rows time our calls that take many rays and walk 16 at a "
          "time interleaved (`intersect_many`, `occluded_many`) against the same single-ray Embree figures: "
          "Embree 4 has no stream call and embreex does not expose its packets, so that choice favours us. Medians; ratio = ours / Embree, the median of the per-pair ratios (above 1: we "
          "are faster; for build time, below 1), spread = their range.", "",
          "| measurement | ours | Embree | ratio (spread) | Embree robust | ratio (spread) |",
          "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        md.append(f"| {r['measurement']} | {r['ours']:.3f} | {r['embree']:.3f} | {r['ratio']:.2f} ({r['spread']}) | "
                  f"{r['embree_robust']:.3f} | {r['ratio_robust']:.2f} ({r['spread_robust']}) |")
    md += ["", "Our closest hits against Embree's (default mode), ray by ray:", "",
           "| ray set | rays | same hit or miss | same triangle (or both miss) | largest relative distance difference, same triangle |",
           "|---|---:|---:|---:|---:|"]
    for name, (n, hm, tri, rel) in agree.items():
        md.append(f"| {name} | {n:,} | {hm:,} | {tri:,} | {rel:.1e} |")
    return md, {"embree": rows, "embree_agreement": agree}
