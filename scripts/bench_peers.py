#!/usr/bin/env python3
"""Wall-clock throughput side by side with the peers, in one run (scripts/bench-peers.sh).

    bench_peers.py OUTDIR [--quick] [--only embree,povray,mitsuba,growth]

Each row is a ratio measured in this run: ours and the peer alternate, and the spread is
the range of the per-pair ratios. Writes OUTDIR/peers.md and OUTDIR/peers.json.
- Embree 4 (embreex): the ~1M-triangle mesh and the four ray sets our `peers` bench wrote,
  closest hit (`INTERSECT`) and any hit (`OCCLUDED`), plus the BVH build, in alternating
  pairs (ours, then Embree; three, one with --quick). embreex traces
  a batch with one thread (rtcIntersect1 per ray), so the peer column is one thread.
- POV-Ray 3.7: N = 1, 100, 10,000 spheres over a plane with shadows, with no reflection,
  reflective spheres, and reflective spheres and floor; exported by our SDL exporter, at
  pixel centres (-A), 2 threads; whole-process wall and CPU time, and POV-Ray's own
  trace time.
- Mitsuba 3 (scalar_rgb): four catalog scenes at 256 x 256; samples per second at equal
  spp, and the time to reach the RMSE of Mitsuba's 256-spp independent image (each image's
  own error, the reference's noise taken off; the sample count where each sampler gets
  there, from renders at 4 to 256 spp), ours against Mitsuba's best sampler for the scene.
- Cost growth: time per primary ray from 100 to 10^6 spheres and triangles (ours).
"""

import json
import math
import os
import re
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
# scripts/bench-peers.sh points these at the profile-guided build (scripts/build-pgo.sh
# --env) unless it is run with --plain.
BIN_DIR = os.environ.get("PEERS_BIN_DIR", os.path.join(TARGET, "release"))
RENDERER = os.path.join(BIN_DIR, "renderer")
CONFORMANCE = os.path.join(BIN_DIR, "conformance")
BUILD = "profile-guided (scripts/build-pgo.sh)" if "PEERS_BIN_DIR" in os.environ else "plain `cargo build --release`"


def run_timed(argv, cwd=None):
    """Runs argv; returns (wall s, CPU s of the child, stdout+stderr)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        raise RuntimeError(f"{argv[0]} failed ({status}):\n{out.decode(errors='replace')[-2000:]}")
    return wall, ru.ru_utime + ru.ru_stime, out.decode(errors="replace")


def spread(ratios):
    return f"{min(ratios):.2f}–{max(ratios):.2f}" if len(ratios) > 1 else "—"


def peers_bench(*args):
    env = dict(os.environ)
    if "PEERS_BENCH_TARGET_DIR" in env:
        env["CARGO_TARGET_DIR"] = env["PEERS_BENCH_TARGET_DIR"]
        env["RUSTFLAGS"] = env.get("PEERS_BENCH_RUSTFLAGS", "")
    out = subprocess.run(["cargo", "bench", "-q", "-p", "renderer", "--bench", "peers", "--", *args],
                         cwd=ROOT, capture_output=True, text=True, check=True, env=env).stdout
    return json.loads(out.strip().splitlines()[-1])


# ---------------------------------------------------------------------------- Embree

def embree(outdir, quick):
    import numpy as np
    import embreex.mesh_construction as mc
    import embreex.rtcore_scene as rtcs

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


# ---------------------------------------------------------------------------- POV-Ray

def whitted_scene(n, refl, w, h):
    import random
    rnd = random.Random(n)
    side = max(1, math.ceil(math.sqrt(n)))
    r = 0.4 * 8.0 / side
    mats = {"none": (0, 0), "spheres": (0.4, 0), "all": (0.4, 0.3)}[refl]
    lines = [f"""[camera.look_at]
from = [0, 6, -12]
at = [0, 0, 0]
up = [0, 1, 0]
fov = 50

[render]
width = {w}
height = {h}
max_depth = 5

[[lights]]
position = [-10, 15, -10]

[materials.ball]
color = [0.8, 0.3, 0.2]
phong = 0.5
reflection = {mats[0]}

[materials.floor]
color = [0.7, 0.7, 0.7]
reflection = {mats[1]}

[[objects]]
type = "plane"
material = "floor"
"""]
    k = 0
    for i in range(side):
        for j in range(side):
            if k >= n:
                break
            x = -4 + 8 * (i + 0.5) / side + rnd.uniform(-0.1, 0.1) * r
            z = -4 + 8 * (j + 0.5) / side
            lines.append(f"""[[objects]]
type = "sphere"
material = "ball"
transform = [{{ scale = {r:.6f} }}, {{ translate = [{x:.6f}, {r:.6f}, {z:.6f}] }}]
""")
            k += 1
    return "\n".join(lines)


def povray(outdir, quick):
    d = os.path.join(outdir, "whitted")
    os.makedirs(d, exist_ok=True)
    w, h = (480, 360) if quick else (1920, 1440)
    pairs = 1 if quick else 3
    md = ["### POV-Ray 3.7, the same scenes exported by our SDL exporter", "",
          f"{w} x {h}, pixel centres (`-A`), 2 threads each, shadows, max trace level 5; {pairs} alternating pair(s) per scene. "
          "Ratio = ours / POV-Ray (below 1: we are faster); spread = range of the per-pair ratios.", "",
          "| spheres | reflective | ours wall (s) | POV-Ray wall (s) | wall ratio | ours CPU (s) | POV-Ray CPU (s) | CPU ratio (spread) | POV-Ray trace (s) |",
          "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    rows = []
    for n in (1, 100, 10000):
        for refl in ("none", "spheres", "all"):
            name = f"n{n}_{refl}"
            toml = os.path.join(d, name + ".toml")
            open(toml, "w").write(whitted_scene(n, refl, w, h))
            subprocess.run([CONFORMANCE, "export-pov", toml, "-o", os.path.join(d, name + ".pov")], check=True)
            ow, oc, pw, pc, tr, cr = [], [], [], [], [], []
            for _ in range(pairs):
                a = run_timed([RENDERER, "render", toml, "-o", os.path.join(d, name + "_ours.png"), "--threads", "2"])
                b = run_timed(["povray", f"+I{name}.pov", f"+O{name}_pov.png", f"+W{w}", f"+H{h}", "-D", "-A", "+WT2", "+FN"], cwd=d)
                m = re.search(r"Trace Time:.*\(\s*([\d.]+) seconds\)", b[2])
                ow.append(a[0]); oc.append(a[1]); pw.append(b[0]); pc.append(b[1])
                tr.append(float(m.group(1)) if m else float("nan"))
                cr.append(a[1] / b[1])
            med = lambda x: sorted(x)[len(x) // 2]
            rows.append({"n": n, "reflective": refl, "ours_wall": med(ow), "pov_wall": med(pw), "ours_cpu": med(oc),
                         "pov_cpu": med(pc), "cpu_ratio": med(cr), "pov_trace": med(tr)})
            md.append(f"| {n:,} | {refl} | {med(ow):.2f} | {med(pw):.2f} | {med(ow) / med(pw):.2f} | {med(oc):.2f} | {med(pc):.2f} | "
                      f"{med(cr):.2f} ({spread(cr)}) | {med(tr):.2f} |")
    return md, {"povray": rows}


# ---------------------------------------------------------------------------- Mitsuba

MI_SCENES = ["mi_area_soft_shadow", "mi_mirror_sphere", "mi_glass_sphere", "mi_cornell"]
MI_SAMPLERS = ["independent", "stratified", "multijitter", "ldsampler"]
# The reference's sampler: stratified, so that its own noise is far below the errors it measures.
REF_SAMPLER = "multijitter"
# "X adaptive": sampler X with render.adaptive (renderer/docs/physical.md), whose counts are
# the averages the pixels took; "X adaptive light": that, with LIGHT_PATHS light paths per
# camera sample for the caustics seen directly (render.light_paths).
OURS_SAMPLERS = ["independent", "stratified", "sobol", "stratified adaptive", "sobol adaptive",
                 "sobol adaptive light"]
LIGHT_PATHS = 0.25


def crossing(pts, target):
    """The sample count at which an error ladder [(spp, error)] (ascending spp) first
    reaches `target`: interpolated in log-log between the two counts around the crossing
    (error falls as a power of the count between them); extrapolated from the last count
    at 1/sqrt(spp) when the ladder never reaches it, and from the first when its first
    count is already below."""
    if not target > 0.0:
        raise RuntimeError(f"target error {target}: Mitsuba's image measured no error of its own, "
                           "so no time to reach it can be read (a reference as noisy as the image?)")
    prev = None
    for spp, e in pts:
        if e == target:
            return spp  # (the line's own formula can round below it)
        if e <= target:
            if prev is None:
                return spp * (e / target) ** 2
            s0, e0 = prev
            if e <= 0.0:
                return s0  # the log-log line's limit as the error goes to 0
            f = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e))
            return math.exp(math.log(s0) + f * (math.log(spp) - math.log(s0)))
        prev = (spp, e)
    spp, e = pts[-1]
    return spp * (e / target) ** 2


def refine(pts, target, measure, counts_between, rounds=8):
    """The error ladder `pts` [(spp, error)] with the counts next to its crossing of
    `target` measured too, ascending. The log-log line between two ladder counts is a
    model, and a poor one where a sampler changes its regime between them: our adaptive
    sampling has no pilot below 8 spp and renders every pixel alike, so its 4-spp error
    lies on the plain sampler's curve and its 16-spp error on the adaptive one's, and the
    line between them put the Cornell box's crossing at 14.6 spp where renders at 13 and
    14 spp measured it at 13.5. Each round takes the two measured counts around the
    crossing (0 below the first) and measures, among the counts the sampler can take
    strictly between them, the nearest on either side of the crossing; it stops when none
    is left, so the crossing ends between two neighbouring counts the sampler can take, or
    after `rounds` rounds (a non-monotonic ladder, as `sobol` at counts that are not powers
    of two gives, can leave a wider bracket). A crossing beyond the ladder's last count is left
    extrapolated. `measure(spp)` renders at `spp` and returns (the count taken, error);
    `counts_between(lo, hi)` lists the counts to ask for whose taken counts lie strictly
    between lo and hi, ascending by the count taken."""
    pts = sorted(pts)
    for _ in range(rounds):
        spp = crossing(pts, target)
        lo = max([n for n, _ in pts if n <= spp], default=0)
        hi = min([n for n, _ in pts if n > spp], default=None)
        if hi is None:
            break
        inner = counts_between(lo, hi)
        below = [c for c, taken in inner if taken <= spp]
        above = [c for c, taken in inner if taken > spp]
        new = below[-1:] + above[:1]
        if not new:
            break
        pts = sorted(pts + [measure(c) for c in new])
    return pts


def mitsuba_scene(name, size):
    """Catalog scene NAME of conformance/scenes/mitsuba as text, at size x size pixels."""
    text = open(os.path.join(ROOT, "conformance/scenes/mitsuba", name + ".toml")).read()
    text = re.sub(r"(?m)^width = \d+", f"width = {size}", text)
    return re.sub(r"(?m)^height = \d+", f"height = {size}", text)


def with_sampler(text, sampler):
    """A scene's text with our `sampler` set in its [render] table ("X adaptive": sampler X
    with adaptive sampling on; "X adaptive light": and LIGHT_PATHS light paths)."""
    name, *flags = sampler.split(" ")
    extra = "\nadaptive = true" if "adaptive" in flags else ""
    extra += f"\nlight_paths = {LIGHT_PATHS}" if "light" in flags else ""
    return re.sub(r"(?m)^\[render\]$", f'[render]\nsampler = "{name}"{extra}', text, count=1)


def mitsuba(outdir, quick):
    import numpy as np
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)  # the samplers' notes on rounding their counts
    d = os.path.join(outdir, "mitsuba")
    os.makedirs(d, exist_ok=True)
    size = 128 if quick else 256
    ref_spp = 256 if quick else 2048
    top = 16 if quick else 256
    # Powers of 4: Mitsuba's ldsampler rounds a count up to a square power of two (at
    # least 4) and its stratified sampler to a square; each point is placed at the count
    # the sampler really took (`mi_count`).
    ladder = [4 ** k for k in range(1, 5) if 4 ** k <= top]
    md = ["### Mitsuba 3 (scalar_rgb), the same scenes exported by our Mitsuba exporter", "",
          f"{size} x {size}. Samples/s at {top} spp (ours 2 threads; Mitsuba's scalar variant uses every core). "
          f"Time to RMSE: the time each needs to reach the RMSE of Mitsuba's {top}-spp independent image. Errors are "
          f"the images' own: taken against the mean of two {ref_spp}-spp Mitsuba `{REF_SAMPLER}` references (seeds 7 "
          "and 8), with the references' own noise (a quarter of their mean squared difference) taken off. Each "
          f"sampler renders at {', '.join(map(str, ladder))} spp (the counts each really takes), then, up to eight "
          "times, at the counts it can take nearest the crossing on either side, until the crossing lies between two "
          "neighbouring counts it can take (our adaptive sampling has no pilot below 8 spp, so the line from the "
          "4-spp to the 16-spp count joins two regimes); the count where its error reaches the target is interpolated "
          f"between the two measured around it (log-log), and its time is that count at the time per sample of its {top}-spp "
          "render. Mitsuba's best sampler for the scene is the one that gets there first, and so is ours "
          "(independent, stratified, sobol, and stratified and sobol with adaptive sampling, whose counts are the "
          f"averages the pixels took, and sobol adaptive with {LIGHT_PATHS} light paths per camera sample for the "
          "caustics seen directly, `light`, in the scenes where they are on: elsewhere it renders sobol adaptive's "
          "bits and is left out). Ratio = ours / best Mitsuba (below 1: we are faster); the three last columns are "
          "our best without adaptive sampling, its ratio, and the ratio the ladder's counts alone would give for the "
          "two best samplers.", "",
          "| scene | ours Msamples/s | Mitsuba Msamples/s | our best sampler | its spp to target | its time (s) "
          "| best Mitsuba sampler | its spp | its time (s) | ratio | our best, not adaptive | its ratio "
          "| ladder alone |",
          "|---|---:|---:|---|---:|---:|---|---:|---:|---:|---|---:|---:|"]
    rows = []
    for name in MI_SCENES:
        text = mitsuba_scene(name, size)
        toml = os.path.join(d, name + ".toml")
        open(toml, "w").write(text)
        xml = os.path.join(d, name + ".xml")
        subprocess.run([CONFORMANCE, "export-mitsuba", toml, "-o", xml, "--spp", "16"], check=True)
        base_xml = open(xml).read()

        def mi_count(sampler, spp):
            smp = mi.load_dict({"type": sampler, "sample_count": 4})
            smp.set_sample_count(spp)
            return smp.sample_count()

        def mi_render(sampler, spp, seed=0):
            x = base_xml.replace('<sampler type="independent">', f'<sampler type="{sampler}">')
            p = os.path.join(d, f"{name}_{sampler}.xml")
            open(p, "w").write(x)
            scene = mi.load_file(p)
            t0 = time.perf_counter()
            img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
            return time.perf_counter() - t0, img, mi_count(sampler, spp)

        def ours_render(sampler, spp):
            # Render time as the CLI reports it (scene loading and the file write excluded,
            # as for Mitsuba, whose mi.render is timed alone).
            # With adaptive sampling the count is the average the pixels took (the log's).
            tag = sampler.replace(" ", "_")
            st = os.path.join(d, f"{name}_ours_{tag}.toml")
            open(st, "w").write(with_sampler(text, sampler))
            out = os.path.join(d, f"{name}_ours_{tag}_{spp}.exr")
            _, _, log = run_timed([RENDERER, "render", st, "-o", out, "--spp", str(spp), "--threads", "2"])
            m = re.search(r"([\d.]+) spp, ([\d.]+) s ->", log)
            img = np.array(mi.Bitmap(out), dtype=np.float64)[:, :, :3]
            return max(float(m.group(2)), 1e-4), img, float(m.group(1))

        # The reference: two independent renders, whose difference measures their own
        # noise (each pixel's error variance of the mean is a quarter of E[(r1 - r2)^2]).
        _, r1, _ = mi_render(REF_SAMPLER, ref_spp, seed=7)
        _, r2, _ = mi_render(REF_SAMPLER, ref_spp, seed=8)
        ref = (r1[:, :, :3] + r2[:, :, :3]) / 2
        floor2 = float(np.mean((r1[:, :, :3] - r2[:, :, :3]) ** 2)) / 4
        # An image's own error: its mean squared difference to the reference, less the
        # reference's own part (independent of the image's, so their squares add).
        own = lambda img: math.sqrt(max(float(np.mean((img[:, :, :3] - ref) ** 2)) - floor2, 0.0))

        def same_images(a, b):
            # Whether our samplers a and b gave the same bits at every count.
            files = lambda s, spp: os.path.join(d, f"{name}_ours_{s.replace(' ', '_')}_{spp}.exr")
            return all(open(files(a, spp), "rb").read() == open(files(b, spp), "rb").read()
                       for spp in ladder)

        def ladder_of(render):
            # Each point at the count the render really took.
            pts = []
            for spp in ladder:
                t, img, n = render(spp)
                pts.append((n, t, own(img)))
            return pts

        def ours_between(lo, hi):
            # Our renders take the count asked for (adaptive ones on average, to 0.1 %).
            return [(c, c) for c in range(round(lo) + 1, round(hi))]

        def mi_between(sampler):
            # Mitsuba rounds some samplers' counts up (stratified to a square, ldsampler to
            # a power of four, multijitter up for some counts: 18 -> 20, 21 -> 24, 32 -> 35).
            def between(lo, hi):
                taken = {}
                for c in range(int(lo) + 1, int(math.ceil(hi))):
                    n = mi_count(sampler, c)
                    if lo < n < hi:
                        taken.setdefault(n, c)
                return [(c, n) for n, c in sorted(taken.items())]
            return between

        def measured(render):
            def measure(spp):
                _, img, n = render(spp)
                return n, own(img)
            return measure

        # Ours and Mitsuba alternate sampler by sampler, so a slow phase of the machine
        # falls on both.
        ours_pts, mi_pts = {}, {}
        for k in range(max(len(OURS_SAMPLERS), len(MI_SAMPLERS))):
            if k < len(OURS_SAMPLERS):
                s = OURS_SAMPLERS[k]
                ours_pts[s] = ladder_of(lambda spp, s=s: ours_render(s, spp))
            if k < len(MI_SAMPLERS):
                s = MI_SAMPLERS[k]
                mi_pts[s] = ladder_of(lambda spp, s=s: mi_render(s, spp))
        target = mi_pts["independent"][-1][2]
        # Light paths are on only in scenes with mirror or glass objects (and where they are
        # exact): elsewhere "X light" renders X's bits, and only the clock would tell them
        # apart, so it is left out.
        candidates = [s for s in OURS_SAMPLERS
                      if not (s.endswith(" light") and same_images(s, s[:-len(" light")]))]

        # Each sampler's errors next to its crossing measured, not read off the ladder's
        # line (`refine`); the time a sample stays its top count's.
        ours_err = {s: refine([(n, e) for n, _, e in ours_pts[s]], target,
                              measured(lambda spp, s=s: ours_render(s, spp)), ours_between)
                    for s in candidates}
        mi_err = {s: refine([(n, e) for n, _, e in mi_pts[s]], target,
                            measured(lambda spp, s=s: mi_render(s, spp)), mi_between(s))
                  for s in MI_SAMPLERS}

        def time_to(pts, err):
            spp = crossing(err, target)
            return spp, spp * pts[-1][1] / pts[-1][0]

        ours_best = min(candidates, key=lambda s: time_to(ours_pts[s], ours_err[s])[1])
        ours_spp, ours_t = time_to(ours_pts[ours_best], ours_err[ours_best])
        best = min(MI_SAMPLERS, key=lambda s: time_to(mi_pts[s], mi_err[s])[1])
        best_spp, best_t = time_to(mi_pts[best], mi_err[best])
        # The same without adaptive sampling: a fixed count in every pixel, as Mitsuba's.
        plain = [s for s in OURS_SAMPLERS if "adaptive" not in s.split(" ")]
        plain_best = min(plain, key=lambda s: time_to(ours_pts[s], ours_err[s])[1])
        plain_t = time_to(ours_pts[plain_best], ours_err[plain_best])[1]
        px = size * size * top
        ours_rate = px / ours_pts["independent"][-1][1] / 1e6
        mi_rate = px / mi_pts["independent"][-1][1] / 1e6
        # Every count measured (the ladder's and the refinement's), and what the ladder
        # alone would have given (`ladder_*`), so that a run shows what refining moved.
        errors = {f"ours {s}": ours_err.get(s) or [(n, e) for n, _, e in ours_pts[s]] for s in OURS_SAMPLERS}
        errors.update({f"mitsuba {s}": mi_err[s] for s in MI_SAMPLERS})
        ladder_only = lambda pts: time_to(pts, [(n, e) for n, _, e in pts])
        (ladder_ours_spp, ladder_ours_t), (ladder_best_spp, ladder_best_t) = \
            ladder_only(ours_pts[ours_best]), ladder_only(mi_pts[best])
        ladder_ratio = ladder_ours_t / ladder_best_t
        rows.append({"scene": name, "ours_msps": ours_rate, "mitsuba_msps": mi_rate, "ours_sampler": ours_best,
                     "ours_spp": ours_spp, "ours_time": ours_t, "best_sampler": best, "best_spp": best_spp,
                     "best_time": best_t, "ratio": ours_t / best_t, "plain_sampler": plain_best,
                     "plain_time": plain_t, "plain_ratio": plain_t / best_t, "target_rmse": target,
                     "reference_rmse": math.sqrt(floor2), "own_rmse_by_spp": errors,
                     "ladder_ours_spp": ladder_ours_spp, "ladder_best_spp": ladder_best_spp,
                     "ladder_ratio": ladder_ratio})
        md.append(f"| {name} | {ours_rate:.2f} | {mi_rate:.2f} | {ours_best} | {ours_spp:.1f} | {ours_t:.3f} | {best} | "
                  f"{best_spp:.1f} | {best_t:.3f} | {ours_t / best_t:.2f} | {plain_best} | {plain_t / best_t:.2f} | "
                  f"{ladder_ratio:.2f} |")
    return md, {"mitsuba": rows}


# ---------------------------------------------------------------------------- growth

def growth(outdir, quick):
    g = peers_bench("growth", *(["--quick"] if quick else []))["growth"]
    kinds = ["spheres (front layer)", "spheres (cloud)", "triangles"]
    md = ["### Cost growth (ours, one thread, 128 x 128 primary rays)", "",
          "| primitives | " + " | ".join(f"{k} (ns/ray)" for k in kinds) + " |", "|---:|---:|---:|---:|"]
    by = {(r["kind"], r["n"]): r["ns_per_ray"] for r in g}
    for n in sorted({r["n"] for r in g}):
        md.append(f"| {n:,} | " + " | ".join(f"{by.get((k, n), float('nan')):.1f}" for k in kinds) + " |")
    md.append("")
    md.append("The sizes of a family are timed alternately, one pass each per round; the growth is the median "
              "of the per-round ratios, with their range.")
    for r in g:
        if "ratio_to_first" in r:
            first = min(x["n"] for x in g if x["kind"] == r["kind"])
            md.append(f"\n{r['kind']}: {r['n']:,} / {first:,} primitives costs {r['ratio_to_first']:.2f}× per ray "
                      f"({r['ratio_min']:.2f}–{r['ratio_max']:.2f} over {r['rounds']} rounds).")
    return md, {"growth": g}


def main():
    outdir = os.path.abspath(sys.argv[1])
    quick = "--quick" in sys.argv
    only = None
    if "--only" in sys.argv:
        only = sys.argv[sys.argv.index("--only") + 1].split(",")
    os.makedirs(outdir, exist_ok=True)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    md = [f"Measured {when} by `scripts/bench-peers.sh{' --quick' if quick else ''}` on {os.cpu_count()} cores, "
          f"ours the {BUILD} build "
          "(shared with other tenants: wall-clock figures move by up to 2x between runs; the ratios, measured "
          "in alternating pairs in one run, move much less).", ""]
    data = {"measured": when, "quick": quick, "build": BUILD}
    for name, fn in (("embree", embree), ("povray", povray), ("mitsuba", mitsuba), ("growth", growth)):
        if only and name not in only:
            continue
        print(f"== {name}", file=sys.stderr, flush=True)
        part, d = fn(outdir, quick)
        md += part + [""]
        data.update(d)
    text = "\n".join(md)
    open(os.path.join(outdir, "peers.md"), "w").write(text)
    json.dump(data, open(os.path.join(outdir, "peers.json"), "w"), indent=1, default=str)
    print(text)


if __name__ == "__main__":
    main()
