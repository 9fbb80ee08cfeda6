"""POV-Ray 3.7 on Whitted scenes exported by our SDL exporter, for scripts/bench_peers.py."""

import math
import os
import re
import subprocess

from peers_common import CONFORMANCE, RENDERER, med, run_timed, spread


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
            subprocess.run([CONFORMANCE, "export", "povray", toml, "-o", os.path.join(d, name + ".pov")], check=True)
            ow, oc, pw, pc, tr, cr = [], [], [], [], [], []
            for _ in range(pairs):
                a = run_timed([RENDERER, "render", toml, "-o", os.path.join(d, name + "_ours.png"), "--threads", "2"])
                b = run_timed(["povray", f"+I{name}.pov", f"+O{name}_pov.png", f"+W{w}", f"+H{h}", "-D", "-A", "+WT2", "+FN"], cwd=d)
                m = re.search(r"Trace Time:.*\(\s*([\d.]+) seconds\)", b[2])
                ow.append(a[0]); oc.append(a[1]); pw.append(b[0]); pc.append(b[1])
                tr.append(float(m.group(1)) if m else float("nan"))
                cr.append(a[1] / b[1])
            rows.append({"n": n, "reflective": refl, "ours_wall": med(ow), "pov_wall": med(pw), "ours_cpu": med(oc),
                         "pov_cpu": med(pc), "cpu_ratio": med(cr), "pov_trace": med(tr)})
            md.append(f"| {n:,} | {refl} | {med(ow):.2f} | {med(pw):.2f} | {med(ow) / med(pw):.2f} | {med(oc):.2f} | {med(pc):.2f} | "
                      f"{med(cr):.2f} ({spread(cr)}) | {med(tr):.2f} |")
    return md, {"povray": rows}
