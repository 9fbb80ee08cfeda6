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
