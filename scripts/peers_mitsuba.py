"""Mitsuba 3 on physical scenes exported by our Mitsuba exporter, for scripts/bench_peers.py.

Mitsuba is run as its own users run it: its fast CPU variant `llvm_ad_rgb` (wide SIMD over
many samples at once, the kernel JIT-compiled by LLVM; Debian's libLLVM 19, found through
DRJIT_LIBLLVM_PATH, which scripts/bench-peers.sh sets) is the headline, each timed render
after a warm-up render of the same kernel, so that the compile is not timed; `scalar_rgb`
is a second column. Both render on every core, ours on two threads (the machine's two).

Two questions, two ratios, on the four catalog scenes and the four of
scripts/bench_scenes.py that are in no catalog:
- The same algorithm: the independent sampler at a fixed count on both sides, and on ours
  no adaptive sampling, no specular guides and no light paths: Mitsuba's estimator, so the
  ratio of samples per second is the tracer's speed.
- The best of each: the time each side needs to reach the same error with its best
  sampler and options. The error target is the RMSE of Mitsuba's independent image at the
  top count; each sampler's error ladder finds the count where it gets there (refined next
  to the crossing), and that count is then rendered and timed, on both sides.
"""

import math
import os
import re
import subprocess
import sys
import time

import bench_scenes
from peers_common import CONFORMANCE, RENDERER, ROOT, med, run_timed, spread

CATALOG = ["mi_area_soft_shadow", "mi_mirror_sphere", "mi_glass_sphere", "mi_cornell"]
SCENES = CATALOG + bench_scenes.NAMES
VARIANT = "llvm_ad_rgb"
SCALAR = "scalar_rgb"
MI_SAMPLERS = ["independent", "stratified", "multijitter", "ldsampler"]
# The reference's sampler: stratified, so that its own noise is far below the errors it measures.
REF_SAMPLER = "multijitter"
# Our configurations: a sampler, then flags. "adaptive": render.adaptive (the count is the
# average the pixels took); "light": LIGHT_PATHS light paths per camera sample for the
# caustics seen directly; "noguides": render.guides off (path scenes); "one":
# render.light_sampling = "one" (one light a vertex, as Mitsuba picks one emitter; else
# every light). Without "noguides", a path scene has its specular guides, on by default.
# SAME is Mitsuba's estimator.
SAME = "independent noguides one"
OURS_CONFIGS = ["independent", "stratified", "sobol", "sobol adaptive",
                "sobol adaptive light", "sobol adaptive noguides", "sobol adaptive one"]
LIGHT_PATHS = 0.25
# Mitsuba's llvm variant holds every sample of a render in flight at once; the references'
# thousands of samples a pixel are rendered as passes of this many, with their own seeds.
REF_PASS_SPP = 128
# The configurations of each side timed in every pair at their crossing counts (the rest
# once, in the first pair).
FINALISTS = 2


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
    """The error ladder `pts` [(spp, error)] with the counts next to its crossing of `target`
    measured too, ascending. The log-log line between two ladder counts is a model, and a
    poor one where a sampler changes its regime between them: our adaptive sampling had no
    pilot below 8 spp before 2026-11-29 (now below 2) and rendered every pixel alike there,
    so its 4-spp error lay on the plain sampler's curve and its 16-spp error on the adaptive
    one's, and the line between them put the Cornell box's crossing at 14.6 spp where
    renders at 13 and 14 spp measured it at 13.5. Each round takes the two measured counts
    around the crossing (0 below the first) and measures, among the counts the sampler can
    take strictly between them, the nearest on either side of the crossing; it stops when
    none is left, so the crossing ends between two neighbouring counts the sampler can take,
    or after `rounds` rounds (a non-monotonic ladder, as `sobol` at counts that are not
    powers of two gives, can leave a wider bracket). A crossing beyond the ladder's last
    count is left extrapolated. `measure(spp)` renders at `spp` and returns (the count
    taken, error); `counts_between(lo, hi)` lists the counts to ask for whose taken counts
    lie strictly between lo and hi, ascending by the count taken."""
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


def scene_text(name, size):
    """Scene NAME (a catalog scene of conformance/scenes/mitsuba or one of bench_scenes)
    as text, at size x size pixels."""
    if name in bench_scenes.SCENES:
        return bench_scenes.text(name, size)
    text = open(os.path.join(ROOT, "conformance/scenes/mitsuba", name + ".toml")).read()
    text = re.sub(r"(?m)^width = \d+", f"width = {size}", text)
    return re.sub(r"(?m)^height = \d+", f"height = {size}", text)


def with_config(text, config):
    """A scene's text with our configuration `config` (see OURS_CONFIGS) in its [render]
    table."""
    name, *flags = config.split(" ")
    path = re.search(r'(?m)^integrator = "path"', text) is not None
    extra = f'\nsampler = "{name}"\nadaptive = {"true" if "adaptive" in flags else "false"}'
    extra += f'\nlight_sampling = "{"one" if "one" in flags else "all"}"'
    if path:
        extra += f"\nlight_paths = {LIGHT_PATHS if 'light' in flags else 0}"
        extra += f"\nguides = {'false' if 'noguides' in flags else 'true'}"
    return re.sub(r"(?m)^\[render\]$", "[render]" + extra, text, count=1)


def mitsuba(outdir, quick):
    import mitsuba as mi
    import numpy as np

    if VARIANT not in mi.variants():
        raise RuntimeError(f"this Mitsuba has no {VARIANT} variant")
    mi.set_log_level(mi.LogLevel.Error)  # the samplers' notes on rounding their counts
    d = os.path.join(outdir, "mitsuba")
    os.makedirs(d, exist_ok=True)
    size = 128 if quick else 256
    ref_spp = 256 if quick else 512
    top = 16 if quick else 256
    same_spp = 16 if quick else 64
    pairs = 1 if quick else 3
    # Powers of 4: Mitsuba's ldsampler rounds a count up to a square power of two (at
    # least 4) and its stratified sampler to a square; each point is placed at the count
    # the sampler really took (`mi_count`).
    ladder = [4 ** k for k in range(1, 5) if 4 ** k <= top]
    md = [f"### Mitsuba 3 (`{VARIANT}`, and `{SCALAR}` for the same algorithm), the same scenes exported by our "
          "Mitsuba exporter", "",
          f"{size} x {size}, ours on 2 threads, Mitsuba on every core (2); each Mitsuba render timed after a warm-up "
          f"render of the same kernel (the JIT compile excluded); {pairs} alternating pair(s), seeds 0..{pairs - 1} "
          "for Mitsuba (ours is deterministic). The catalog scenes first, then the four of scripts/bench_scenes.py, "
          "which are in no catalog.", "",
          f"**The same algorithm** (the independent sampler at {same_spp} spp; ours without adaptive sampling, "
          "specular guides or light paths, and with one light a vertex: Mitsuba's estimator): samples per second, ratio = ours / Mitsuba "
          "(above 1: we are faster), the median of the per-pair ratios and their range.", "",
          f"| scene | ours Msamples/s | {VARIANT} Msamples/s | ratio (spread) | {SCALAR} Msamples/s | ratio (spread) |",
          "|---|---:|---:|---:|---:|---:|"]
    best_md = ["", f"**The best of each**: the time to reach the RMSE of Mitsuba's {top}-spp independent image "
               f"(`{VARIANT}`, the mean of seeds 0 and 1). Errors are the images' own: taken against the mean of two "
               f"{ref_spp}-spp Mitsuba `{REF_SAMPLER}` references (seeds from 1000 and 2000 up, {REF_PASS_SPP} spp a "
               "pass), the references' own noise (a quarter of their mean squared difference) taken off. Each "
               f"sampler renders at {', '.join(map(str, ladder))} spp (the counts each really takes; from 16 spp on, it "
               "stops at the first count whose error is at or below the target), then, up to "
               "eight times, at the counts it can take nearest the crossing on either side; the count where its "
               "error reaches the target is interpolated between the two measured around it (log-log). That count, "
               "rounded up to one the sampler takes, is then rendered and timed, in alternating pairs: the time is "
               f"a real render's. The first pair times every configuration of both sides; the others only each "
               f"side's {FINALISTS} fastest in the first (the best is the fastest median of those; the fixed-count "
               "column's time is its first pair's). Ours: " + ", ".join(OURS_CONFIGS) + " (`adaptive`: adaptive sampling, its count "
               f"the average the pixels took; `light`: {LIGHT_PATHS} light paths per camera sample, in the scenes "
               "where they are on; `noguides`: no specular guides, on by default in path scenes; `one`: one light "
               "a vertex, as Mitsuba, where ours takes every light by default; a configuration that renders "
               "another's bits in a scene is left out there). Mitsuba: "
               + ", ".join(MI_SAMPLERS) + ". Ratio = ours / Mitsuba for the best of each (below 1: we are faster), "
               "the median of the per-pair ratios and their range.", "",
               "| scene | our best | its spp | its time (s) | Mitsuba's best | its spp | its time (s) | ratio (spread) "
               "| our best at a fixed count | its ratio |",
               "|---|---|---:|---:|---|---:|---:|---:|---|---:|"]
    rows = []
    for name in SCENES:
        print(f"   {name}", flush=True, file=sys.stderr)
        text = scene_text(name, size)
        if name in bench_scenes.SCENES:
            bench_scenes.write(name, d, size)  # the mesh it names, beside it
        toml = os.path.join(d, name + ".toml")
        open(toml, "w").write(text)
        xml = os.path.join(d, name + ".xml")
        subprocess.run([CONFORMANCE, "export", "mitsuba", toml, "-o", xml, "--spp", "16"], check=True)
        base_xml = open(xml).read()
        loaded = {}

        def mi_scene(variant, sampler):
            if (variant, sampler) not in loaded:
                mi.set_variant(variant)
                x = base_xml.replace('<sampler type="independent">', f'<sampler type="{sampler}">')
                p = os.path.join(d, f"{name}_{sampler}.xml")
                open(p, "w").write(x)
                loaded[(variant, sampler)] = mi.load_file(p)
            mi.set_variant(variant)
            return loaded[(variant, sampler)]

        def mi_count(sampler, spp):
            mi.set_variant(VARIANT)
            smp = mi.load_dict({"type": sampler, "sample_count": 4})
            smp.set_sample_count(spp)
            return smp.sample_count()

        def mi_render(sampler, spp, seed=0, variant=VARIANT, timed=False):
            """(seconds, image, count taken); `timed`: after a warm-up render of the same
            kernel (llvm), so that the time is the render's, not the compile's."""
            scene = mi_scene(variant, sampler)
            if timed and variant != SCALAR:
                np.array(mi.render(scene, spp=spp, seed=seed))
            t0 = time.perf_counter()
            img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
            return time.perf_counter() - t0, img[:, :, :3], mi_count(sampler, spp)

        def ours_render(config, spp):
            # Render time as the CLI reports it (scene loading and the file write excluded,
            # as for Mitsuba, whose mi.render is timed alone).
            tag = config.replace(" ", "_")
            st = os.path.join(d, f"{name}_ours_{tag}.toml")
            open(st, "w").write(with_config(text, config))
            out = os.path.join(d, f"{name}_ours_{tag}_{spp}.exr")
            _, _, log = run_timed([RENDERER, "render", st, "-o", out, "--spp", str(spp), "--threads", "2"])
            m = re.search(r"([\d.]+) spp, ([\d.]+) s ->", log)
            img = np.array(mi.Bitmap(out), dtype=np.float64)[:, :, :3]
            return max(float(m.group(2)), 1e-4), img, float(m.group(1))

        # The same algorithm, in alternating pairs.
        px = size * size * same_spp / 1e6
        same = []
        for k in range(pairs):
            a = ours_render(SAME, same_spp)[0]
            b = mi_render("independent", same_spp, seed=k, timed=True)[0]
            c = mi_render("independent", same_spp, seed=k, variant=SCALAR, timed=True)[0]
            same.append((px / a, px / b, px / c))
        r_llvm = [o / m for o, m, _ in same]
        r_scalar = [o / s for o, _, s in same]
        ours_rate, llvm_rate, scalar_rate = (med([t[i] for t in same]) for i in range(3))
        md.append(f"| {name} | {ours_rate:.2f} | {llvm_rate:.2f} | {med(r_llvm):.2f} ({spread(r_llvm)}) | "
                  f"{scalar_rate:.2f} | {med(r_scalar):.2f} ({spread(r_scalar)}) |")

        # The reference: two independent renders, whose difference measures their own
        # noise (each pixel's error variance of the mean is a quarter of E[(r1 - r2)^2]).
        def reference(seed0):
            passes = max(1, ref_spp // REF_PASS_SPP)
            acc = 0.0
            for k in range(passes):
                acc = acc + mi_render(REF_SAMPLER, min(ref_spp, REF_PASS_SPP), seed=seed0 + k)[1]
            return acc / passes

        r1, r2 = reference(1000), reference(2000)
        ref = (r1 + r2) / 2
        floor2 = float(np.mean((r1 - r2) ** 2)) / 4
        # An image's own error: its mean squared difference to the reference, less the
        # reference's own part (independent of the image's, so their squares add).
        own = lambda img: math.sqrt(max(float(np.mean((img - ref) ** 2)) - floor2, 0.0))
        target = (own(mi_render("independent", top, seed=0)[1]) + own(mi_render("independent", top, seed=1)[1])) / 2

        def same_images(a, b):
            # Whether our configurations a and b gave the same bits at every ladder count
            # both rendered (each ladder renders 4 and 16 spp at least).
            files = lambda c, spp: os.path.join(d, f"{name}_ours_{c.replace(' ', '_')}_{spp}.exr")
            both = [spp for spp in ladder if os.path.exists(files(a, spp)) and os.path.exists(files(b, spp))]
            return bool(both) and all(open(files(a, spp), "rb").read() == open(files(b, spp), "rb").read()
                                      for spp in both)

        def ladder_of(render):
            # Each point at the count the render really took: (count, error). The ladder
            # stops at the first count whose error is at or below the target (but never
            # before 16 spp): the crossing lies below it, and the counts above it (the
            # costliest renders of the ladder) would not move it.
            out = []
            for spp in ladder:
                _, img, n = render(spp)
                out.append((n, own(img)))
                if spp >= 16 and out[-1][1] <= target:
                    break
            return out

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

        # Error ladders, ours and Mitsuba's alternating, each refined next to its crossing.
        ours_err, mi_err = {}, {}
        for k in range(max(len(OURS_CONFIGS), len(MI_SAMPLERS))):
            if k < len(OURS_CONFIGS):
                c = OURS_CONFIGS[k]
                render = lambda spp, c=c: ours_render(c, spp)
                ours_err[c] = refine(ladder_of(render), target, measured(render), ours_between)
            if k < len(MI_SAMPLERS):
                s = MI_SAMPLERS[k]
                render = lambda spp, s=s: mi_render(s, spp)
                mi_err[s] = refine(ladder_of(render), target, measured(render), mi_between(s))
        # A flag the scene has no use for renders another configuration's bits: left out
        # (light paths and guides are on only in scenes with mirror or glass objects).
        configs = []
        for c in OURS_CONFIGS:
            if any(same_images(c, e) for e in configs):
                continue
            configs.append(c)

        def ours_count(c):
            return max(1, math.ceil(crossing(ours_err[c], target) - 1e-9))

        def mi_count_at(s):
            want = crossing(mi_err[s], target)
            c = max(1, math.ceil(want - 1e-9))
            while mi_count(s, c) < want - 1e-9:
                c += 1
            return c

        # Real renders at each crossing count, in alternating pairs. The first pair
        # renders every configuration of both sides once; the other pairs only each
        # side's FINALISTS fastest in it (the rest are left with their one time: a
        # configuration more than a few per cent behind the second in one render is
        # not the best, and three renders of every one were most of the part's time).
        ours_t = {c: [] for c in configs}
        mi_t = {s: [] for s in MI_SAMPLERS}
        ours_in, mi_in = list(configs), list(MI_SAMPLERS)
        for k in range(pairs):
            if k == 1:
                ours_in = sorted(configs, key=lambda c: ours_t[c][0])[:FINALISTS]
                mi_in = sorted(MI_SAMPLERS, key=lambda s: mi_t[s][0])[:FINALISTS]
            for c in ours_in:
                ours_t[c].append(ours_render(c, ours_count(c))[0])
            for s in mi_in:
                mi_t[s].append(mi_render(s, mi_count_at(s), seed=k, timed=True)[0])
        ours_best = min(ours_in, key=lambda c: med(ours_t[c]))
        best = min(mi_in, key=lambda s: med(mi_t[s]))
        fixed = [c for c in configs if "adaptive" not in c.split(" ")]
        fixed_best = min(fixed, key=lambda c: ours_t[c][0])
        ratios = [a / b for a, b in zip(ours_t[ours_best], mi_t[best])]
        fixed_ratio = ours_t[fixed_best][0] / mi_t[best][0]
        rows.append({"scene": name, "catalog": name in CATALOG, "same_spp": same_spp,
                     "ours_msps": ours_rate, "llvm_msps": llvm_rate, "scalar_msps": scalar_rate,
                     "same_ratio": med(r_llvm), "same_spread": spread(r_llvm),
                     "same_ratio_scalar": med(r_scalar), "same_spread_scalar": spread(r_scalar),
                     "target_rmse": target, "reference_rmse": math.sqrt(floor2),
                     "ours_best": ours_best, "ours_spp": ours_count(ours_best), "ours_time": med(ours_t[ours_best]),
                     "mi_best": best, "mi_spp": mi_count(best, mi_count_at(best)), "mi_time": med(mi_t[best]),
                     "best_ratio": med(ratios), "best_spread": spread(ratios),
                     "fixed_best": fixed_best, "fixed_ratio": fixed_ratio,
                     "ours_times": ours_t, "mi_times": mi_t,
                     "errors": {**{f"ours {c}": ours_err[c] for c in OURS_CONFIGS},
                                **{f"mitsuba {s}": mi_err[s] for s in MI_SAMPLERS}}})
        r = rows[-1]
        best_md.append(f"| {name} | {ours_best} | {r['ours_spp']} | {r['ours_time']:.3f} | {best} | {r['mi_spp']} | "
                       f"{r['mi_time']:.3f} | {r['best_ratio']:.2f} ({r['best_spread']}) | {fixed_best} | "
                       f"{fixed_ratio:.2f} |")
    return md + best_md, {"mitsuba": rows}
