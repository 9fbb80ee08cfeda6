#!/usr/bin/env bash
# Measures the f32/f64 precision trade in one run: builds the measurement tool in both
# precisions and runs it. Needs only cargo and python3.
#
#   scripts/precision.sh                write the tables to ${CARGO_TARGET_DIR:-target}/conformance/precision.md
#   scripts/precision.sh --write-docs   also write them into renderer/docs/precision.md (between
#                                       the "precision:begin" and "precision:end" markers)
set -euo pipefail
cd "$(dirname "$0")/.."
write_docs=""
case "${1:-}" in
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
    --write-docs) write_docs=1;;
    "") ;;
    *) echo "unknown option $1 (see --help)" >&2; exit 2;;
esac
out="${CARGO_TARGET_DIR:-target}/conformance"
mkdir -p "$out"
f32=$(cargo run --release -q -p conformance --bin precision)
f64=$(cargo run --release -q -p conformance --features f64 --bin precision)
python3 - "$f32" "$f64" "$out/precision.md" "$write_docs" <<'PY'
import sys, datetime, platform, os
rows = [l.split("|") for out in sys.argv[1:3] for l in out.strip().splitlines()]
def get(kind): return [r[1:] for r in rows if r[0] == kind]
md = []
md.append(f"Measured {datetime.date.today()} by `scripts/precision.sh` on {os.cpu_count()} cores ({platform.machine()}); both builds in one run.\n")
md.append("### Throughput\n")
md.append("| build | primary rays, 10,000-sphere cloud, 1 thread (Mrays/s) | shaded, `shade_refract_sphere`, 1 thread (Mpixels/s): robust / fixed 1e-3 / none |")
md.append("|---|---|---|")
spawn = get("SPAWN")
for p, mr in get("THROUGHPUT"):
    shaded = " / ".join(r[2] for r in spawn if r[0] == p)
    md.append(f"| {p} | {mr} | {shaded} |")
md.append("\n### A unit sphere far from the eye: t error (ulps of the build's precision) against the f64 closed form\n")
md.append("| distance / radius | build | median | 99th percentile | max | wrong hit/miss outside the 8·ε·D band |")
md.append("|---|---|---|---|---|---|")
for p, ratio, med, p99, mx, wrong in sorted(get("FARSPHERE"), key=lambda r: (float(r[1]), r[0])):
    md.append(f"| {float(ratio):.0e} | {p} | {med} | {p99} | {mx} | {wrong} of 20,000 |")
md.append("\n### The whole scene and camera translated: pixels whose object id changes (%)\n")
md.append("| translation | f32 | f64 |")
md.append("|---|---|---|")
shift = {(r[0], r[1]): r[2] for r in get("SHIFT")}
for s in sorted({r[1] for r in get("SHIFT")}, key=float):
    md.append(f"| {float(s):.0e} | {shift.get(('f32', s), '-')} | {shift.get(('f64', s), '-')} |")
md.append("\n### Depth range inside one view: surfaces a relative gap apart at distance D from the eye\n")
md.append("A rectangle lies a gap g = ρ·D above a plane, both at distance D from the eye, seen from above (the eye is the render-space origin, so rebasing cannot help). The table gives the percentage of the central pixels, all on the rectangle, that show the plane instead: where the two surfaces merge.\n")
depth = get("DEPTH")
rels = sorted({r[2] for r in depth}, key=lambda v: -float(v))
md.append("| D | build | " + " | ".join(f"ρ = {float(r):.0e}" for r in rels) + " |")
md.append("|---|---|" + "---|" * len(rels))
for d in sorted({r[1] for r in depth}, key=float):
    for p in ("f32", "f64"):
        vals = {r[2]: r[3] for r in depth if r[0] == p and r[1] == d}
        md.append(f"| {float(d):.0e} | {p} | " + " | ".join(vals.get(r, "-") for r in rels) + " |")
md.append("\n### Self-intersection strategies\n")
md.append("Self-hits: spawned rays (uniform over the outward hemisphere) that hit their own sphere again, over 4,000 random instances (rotation, non-uniform scale). Leaks: shadow rays from a plane that pass a thin plate held a small gap above it.\n")
md.append("| build | strategy | self-hits at the origin (%) | self-hits, translation 1e5 (%) | self-hits, translation 1e6 and scale 1e±4 (%) | leaks, gap 1e-2 (%) | leaks, gap 1e-4 (%) |")
md.append("|---|---|---|---|---|---|---|")
for p, name, _thr, h0, h1, h2, l1, l2 in spawn:
    md.append(f"| {p} | {name} | {h0} | {h1} | {h2} | {l1} | {l2} |")
table = "\n".join(md) + "\n"
open(sys.argv[3], "w").write(table)
print(table)
print("wrote " + sys.argv[3])
if not sys.argv[4]:
    sys.exit(0)
path = "renderer/docs/precision.md"
text = open(path).read()
a, b = "<!-- precision:begin -->\n", "<!-- precision:end -->"
i, j = text.index(a) + len(a), text.index(b)
open(path, "w").write(text[:i] + table + text[j:])
print("updated " + path)
PY
