"""Mitsuba 3 on physical scenes exported by our Mitsuba exporter, for scripts/bench_peers.py."""

import math
import os
import re
import subprocess
import time

from peers_common import CONFORMANCE, RENDERER, ROOT, run_timed

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
    import mitsuba as mi
    import numpy as np
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
