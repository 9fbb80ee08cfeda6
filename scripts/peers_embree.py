"""Embree 4 (embreex) against our peers bench, for scripts/bench_peers.py."""

import os
import time

from peers_common import peers_bench, spread


def embree(outdir, quick):
    import embreex.mesh_construction as mc
    import embreex.rtcore_scene as rtcs
    import numpy as np

    d = os.path.join(outdir, "mesh")
    secs = 0.3 if quick else 2.0
    pairs = 1 if quick else 3
    # Ours (the peers bench, which also writes the mesh and the rays) and Embree alternate,
    # `pairs` times; each row reports the medians and the range of the per-pair ratios.
    samples, names, order = {}, {}, []

    def add(key, name, kind, a, b):
        if key not in samples:
            samples[key], names[key] = [], (name, kind)
            order.append(key)
        samples[key].append((a, b))

    for _ in range(pairs):
        ours = peers_bench("mesh", d, *(["--quick"] if quick else []))
        v = np.fromfile(os.path.join(d, "vertices.f32"), dtype=np.float32).reshape(-1, 3)
        idx = np.fromfile(os.path.join(d, "indices.u32"), dtype=np.uint32).reshape(-1, 3).astype(np.int32)
        t0 = time.perf_counter()
        scene = rtcs.EmbreeScene()
        mc.TriangleMesh(scene, v, idx)
        scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commits the BVH
        add("build", "BVH build, 1M triangles (s)", "time", ours["build_seconds"], time.perf_counter() - t0)
        for s in ours["sets"]:
            r = np.fromfile(os.path.join(d, f"rays_{s['name']}.f32"), dtype=np.float32).reshape(-1, 7)
            o, dirs = np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:6])
            tmax = np.ascontiguousarray(r[:, 6])
            tmax = np.where(np.isinf(tmax), np.float32(1e30), tmax).astype(np.float32)
            res = {}
            for q in ("INTERSECT", "OCCLUDED"):
                hits = scene.run(o, dirs, dists=tmax, query=q)
                t0, n = time.perf_counter(), 0
                while time.perf_counter() - t0 < secs:
                    scene.run(o, dirs, dists=tmax, query=q)
                    n += len(o)
                res[q] = (n / (time.perf_counter() - t0) / 1e6, int((np.asarray(hits) >= 0).sum()))
            for run in s["runs"]:
                th = run["threads"]
                add((s["name"], th, "c"), f"{s['name']}: closest hit, ours {th} thread(s) (Mrays/s)", "rate",
                    run["closest_mrays"], res["INTERSECT"][0])
                add((s["name"], th, "a"), f"{s['name']}: any hit, ours {th} thread(s) (Mrays/s)", "rate",
                    run["any_mrays"], res["OCCLUDED"][0])
            if res["INTERSECT"][1] != s["runs"][0]["hits"]:
                add((s["name"], "hits"), f"{s['name']}: hits (ours / Embree)", "count",
                    s["runs"][0]["hits"], res["INTERSECT"][1])
    med = lambda x: sorted(x)[len(x) // 2]
    rows = []
    for key in order:
        (name, kind), ab = names[key], samples[key]
        ratios = [a / b for a, b in ab]
        rows.append((name, med([a for a, _ in ab]), med([b for _, b in ab]), kind, med(ratios), spread(ratios)))
    md = ["### Embree 4 (embreex, one thread), the same 1M-triangle mesh and rays", "",
          f"{ours['triangles']:,} triangles, 640 x 480 camera rays; {pairs} alternating pair(s) (ours, then Embree). "
          "Medians; ratio = ours / Embree, the median of the per-pair ratios (above 1: we are faster; for build "
          "time, below 1), spread = their range.", "",
          "| measurement | ours | Embree | ratio (spread) |", "|---|---:|---:|---:|"]
    for name, a, b, kind, ratio, sp in rows:
        md.append(f"| {name} | {a:.3f} | {b:.3f} | {ratio:.2f} ({sp}) |")
    return md, {"embree": rows}
