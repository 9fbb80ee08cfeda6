#!/usr/bin/env python3
"""The working tree against a base commit, wall clock in alternating pairs (scripts/ab-bench.sh).

    ab_bench.py OUTDIR --base RENDERER PEERS --new RENDERER PEERS [--base-name NAME]
                [--pairs N] [--only mesh,physical]

Pair k runs the base first when k is even and the new build first when it is odd, so
neither always runs in the other's wake. Each row is the median of the per-pair ratios
(new / base) with their range; the medians of the figures themselves are shown beside
them. Writes OUTDIR/ab.md and OUTDIR/ab.json.
"""

import hashlib
import json
import os
import re
import statistics
import subprocess
import sys

sys.dont_write_bytecode = True  # importing bench_peers must leave no __pycache__ in scripts/
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_peers import MI_SCENES, mitsuba_scene, run_timed, spread, with_sampler  # noqa: E402


def order(k):
    """The sides in the order pair k runs them."""
    return ("base", "new") if k % 2 == 0 else ("new", "base")


def rows(name, series, unit, better):
    """Markdown rows: (label, base values, new values) -> median base, median new, ratio."""
    out = []
    for label, base, new in series:
        ratios = [n / b for b, n in zip(base, new)]
        out.append(f"| {label} | {statistics.median(base):.3f} | {statistics.median(new):.3f} "
                   f"| {statistics.median(ratios):.3f} ({spread(ratios)}) |")
    head = [f"### {name}", "", f"{unit}; ratio = new / base, the median of the per-pair ratios "
            f"(range); {better}.", "", "| measurement | base | new | ratio (range) |", "|---|---:|---:|---:|"]
    return head + out


def mesh(outdir, bins, pairs):
    runs = {"base": [], "new": []}
    for k in range(pairs):
        for side in order(k):
            d = os.path.join(outdir, "mesh", side)
            os.makedirs(d, exist_ok=True)
            out = subprocess.run([bins[side][1], "mesh", d, "--quick"], capture_output=True,
                                 text=True, check=True).stdout
            runs[side].append(json.loads(out.strip().splitlines()[-1]))
    # Rows by set name and thread count, so a base whose bench lists its sets otherwise
    # still lines up; a row only one side has is left out.
    def figures(run):
        return {(s["name"], r["threads"], q): r[q + "_mrays"]
                for s in run["sets"] for r in s["runs"] for q in ("closest", "any")}
    base, new = [list(map(figures, runs[side])) for side in ("base", "new")]
    series = []
    for key in base[0]:
        if all(key in n for n in new):
            name, threads, q = key
            series.append((f"{name}: {q} hit, {threads} thread(s)", [b[key] for b in base],
                           [n[key] for n in new]))
    build = [("BVH build, 1M triangles (s)", [x["build_seconds"] for x in runs["base"]],
              [x["build_seconds"] for x in runs["new"]])]
    return (rows("Mesh (peers mesh --quick, Mrays/s)", series, "Mrays/s", "above 1, new is faster")
            + [""] + rows("Mesh build", build, "seconds", "below 1, new is faster")), runs


def physical(outdir, bins, pairs):
    d = os.path.join(outdir, "physical")
    os.makedirs(d, exist_ok=True)
    series, same, seconds = [], {}, {}
    for name in MI_SCENES:
        text = with_sampler(mitsuba_scene(name, 128), "sobol")
        scene = os.path.join(d, name + ".toml")
        open(scene, "w").write(text)
        secs = {"base": [], "new": []}
        digest = {}
        for k in range(pairs):
            for side in order(k):
                img = os.path.join(d, f"{name}_{side}.exr")
                _, _, log = run_timed([bins[side][0], "render", scene, "-o", img, "--spp", "64",
                                       "--threads", "1"])
                secs[side].append(float(re.search(r"spp, ([\d.]+) s ->", log).group(1)))
                digest[side] = hashlib.sha256(open(img, "rb").read()).hexdigest()
        same[name] = digest["base"] == digest["new"]
        seconds[name] = secs
        series.append((f"{name} ({'same bits' if same[name] else 'different bits'})",
                       secs["base"], secs["new"]))
    return rows("Physical scenes (128 x 128, 64 spp, sobol, one thread, render seconds)", series,
                "seconds", "below 1, new is faster"), {"same_bits": same, "seconds": seconds}


def main():
    args = sys.argv[1:]
    outdir = os.path.abspath(args[0])
    bins = {side: args[args.index("--" + side) + 1: args.index("--" + side) + 3] for side in ("base", "new")}
    pairs = int(args[args.index("--pairs") + 1]) if "--pairs" in args else 4
    only = args[args.index("--only") + 1].split(",") if "--only" in args else ["mesh", "physical"]
    base_name = args[args.index("--base-name") + 1] if "--base-name" in args else "base"
    unknown = set(only) - {"mesh", "physical"}
    if unknown or pairs < 1:
        sys.exit(f"ab_bench.py: --only takes mesh and physical, --pairs at least 1 (got {only}, {pairs})")
    os.makedirs(outdir, exist_ok=True)
    md = [f"Base {base_name} against the working tree, {pairs} alternating pair(s) on "
          f"{os.cpu_count()} cores.", ""]
    data = {}
    for name, fn in (("mesh", mesh), ("physical", physical)):
        if name in only:
            print(f"== {name}", file=sys.stderr, flush=True)
            part, d = fn(outdir, bins, pairs)
            md += part + [""]
            data[name] = d
    text = "\n".join(md)
    open(os.path.join(outdir, "ab.md"), "w").write(text)
    json.dump(data, open(os.path.join(outdir, "ab.json"), "w"), indent=1)
    print(text)


if __name__ == "__main__":
    main()
