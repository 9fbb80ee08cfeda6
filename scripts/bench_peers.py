#!/usr/bin/env python3
"""Wall-clock throughput side by side with the peers, in one run (scripts/bench-peers.sh).

    bench_peers.py OUTDIR [--quick] [--only embree,povray,mitsuba,growth]

Each row is a ratio measured in this run: ours and the peer alternate, and the spread is
the range of the per-pair ratios. Writes OUTDIR/peers.md and OUTDIR/peers.json. Each peer
is run as its own users run it, and ours is the plain `cargo build --release`:
- Embree 4 (embreex, peers_embree.py): the ~1M-triangle mesh and the four ray sets our
  `peers` bench wrote, closest hit and any hit on 1 and 2 threads each, Embree in its
  default mode (the headline) and in robust mode, plus the BVH build; both sides store
  every ray's result, and the closest hits are compared ray by ray.
- POV-Ray 3.7 (peers_povray.py): N = 1, 100, 10,000 spheres over a plane with shadows,
  with no reflection, reflective spheres, and reflective spheres and floor; exported by
  our SDL exporter, at pixel centres (-A), 2 threads; whole-process wall and CPU time,
  and POV-Ray's own trace time.
- Mitsuba 3 (peers_mitsuba.py): `llvm_ad_rgb` (and `scalar_rgb`) on four catalog scenes
  and four in no catalog (bench_scenes.py) at 256 x 256: samples per second with the same
  algorithm, and the time each side's best sampler needs to reach the same error, timed
  on real renders at the crossing count.
- Cost growth (peers_growth.py): time per primary ray from 100 to 10^6 spheres and
  triangles (ours).
"""

import json
import os
import sys
import time

from peers_common import BUILD
from peers_embree import embree
from peers_growth import growth
from peers_mitsuba import mitsuba
from peers_povray import povray


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
    text = "\n".join(md)
    for name, fn in (("embree", embree), ("povray", povray), ("mitsuba", mitsuba), ("growth", growth)):
        if only and name not in only:
            continue
        print(f"== {name}", file=sys.stderr, flush=True)
        part, d = fn(outdir, quick)
        md += part + [""]
        data.update(d)
        # Written after each part, so that a run stopped in a later part keeps the
        # finished parts' tables.
        text = "\n".join(md)
        open(os.path.join(outdir, "peers.md"), "w").write(text)
        json.dump(data, open(os.path.join(outdir, "peers.json"), "w"), indent=1, default=str)
    print(text)


if __name__ == "__main__":
    main()
