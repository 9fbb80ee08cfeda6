"""Our cost growth from 100 to 10^6 primitives, for scripts/bench_peers.py."""


from peers_common import peers_bench


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
