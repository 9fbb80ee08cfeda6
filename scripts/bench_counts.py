#!/usr/bin/env python3
"""Compares gungraun's JSON lines with the committed instruction-count baseline.

    bench_counts.py RAW.jsonl BASELINE.json OUTDIR [--accept] [--partial]

Writes OUTDIR/bench.md (the table) and OUTDIR/bench.json. Exits 1 when a count grew by
more than the baseline's limit, or when a benchmark is new or missing (unless --partial,
for a filtered run); --accept writes the counts as the new baseline instead.
"""

import datetime
import json
import subprocess
import sys


def counts(path):
    out = {}
    for line in open(path):
        line = line.strip()
        if not line.startswith("{"):
            continue
        d = json.loads(line)
        name = f"{d['group']}::{d['function_name']}" + (f".{d['id']}" if d.get("id") else "")
        ir = d["profiles"][0]["data"]["total"]["metrics"]["Ir"]["values"]["new"]
        out[name] = int(ir)
    return out


def toolchain():
    try:
        return subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "unknown"


def main():
    raw, base_path, outdir = sys.argv[1:4]
    accept, partial = "--accept" in sys.argv, "--partial" in sys.argv
    now = counts(raw)
    if not now:
        sys.exit(f"no benchmark results in {raw}")
    try:
        base = json.load(open(base_path))
    except FileNotFoundError:
        base = {"limit_percent": 3.0, "counts": {}}
    limit = float(base.get("limit_percent", 3.0))
    # Counts are stable on one toolchain, and move by a few percent between compilers, so
    # a mismatch is said on every run and in the failure message.
    base_tc, tc = base.get("toolchain"), toolchain()
    tc_note = ""
    if base_tc and base_tc != tc:
        tc_note = (f"the baseline was taken with {base_tc} and this run used {tc}: counts differ between compilers; "
                   f"compare with the baseline's toolchain (rustup toolchain install {base_tc.split()[1]}, "
                   f"then RUSTUP_TOOLCHAIN={base_tc.split()[1]} scripts/bench-counts.sh) or accept on purpose")
    old = base.get("counts", {})
    rows, bad = [], []
    for name in sorted(set(now) | set(old)):
        a, b = old.get(name), now.get(name)
        if b is None:
            if not partial:
                bad.append(f"{name}: in the baseline but not run (removed? accept with --accept)")
            rows.append((name, a, None, None, "not run"))
            continue
        if a is None:
            bad.append(f"{name}: not in the baseline (new? accept with scripts/bench-counts.sh --accept)")
            rows.append((name, None, b, None, "NEW"))
            continue
        change = 100.0 * (b - a) / a
        verdict = "ok" if change <= limit else f"SLOWER (> +{limit:g} %)"
        if change > limit:
            bad.append(f"{name}: {a:,} -> {b:,} instructions ({change:+.2f} %, limit +{limit:g} %)")
        rows.append((name, a, b, change, verdict))
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    md = [f"Instruction counts (Callgrind `Ir`), measured {when} with {tc} by `scripts/bench-counts.sh`, "
          f"against renderer/benches/baseline.json (limit +{limit:g} %)."
          + (f" **Toolchain differs:** {tc_note}." if tc_note else ""), "",
          "| benchmark | baseline | now | change | verdict |", "|---|---:|---:|---:|---|"]
    for name, a, b, ch, v in rows:
        md.append(f"| {name} | {'—' if a is None else f'{a:,}'} | {'—' if b is None else f'{b:,}'} | "
                  f"{'' if ch is None else f'{ch:+.2f} %'} | {v} |")
    table = "\n".join(md) + "\n"
    print(table)
    open(f"{outdir}/bench.md", "w").write(table)
    json.dump({"measured": when, "toolchain": tc, "baseline_toolchain": base_tc, "limit_percent": limit,
               "rows": [dict(zip(["name", "baseline", "now", "change_percent", "verdict"], r)) for r in rows]},
              open(f"{outdir}/bench.json", "w"), indent=1)
    if accept:
        merged = dict(old) if partial else {}
        merged.update(now)
        json.dump({"limit_percent": limit, "toolchain": tc, "counts": dict(sorted(merged.items()))},
                  open(base_path, "w"), indent=1)
        open(base_path, "a").write("\n")
        print(f"accepted: {base_path} now holds these counts; commit it with a message that says why")
        return
    if bad:
        print("instruction-count gate FAILED:\n  " + "\n  ".join(bad), file=sys.stderr)
        if tc_note:
            print("NOTE: " + tc_note, file=sys.stderr)
        print("If the change is deliberate: scripts/bench-counts.sh --accept, and commit the baseline.", file=sys.stderr)
        sys.exit(1)
    print(f"instruction-count gate: {len(now)} benchmarks within +{limit:g} % of the baseline")
    if tc_note:
        print("NOTE: " + tc_note)


if __name__ == "__main__":
    main()
