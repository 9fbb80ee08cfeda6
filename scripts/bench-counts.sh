#!/usr/bin/env bash
# Instruction-count benchmarks (renderer/benches/counts.rs, gungraun over Callgrind) against
# the committed baseline renderer/benches/baseline.json. Prints a table of each count
# against the baseline with the change in %, writes it to
# ${CARGO_TARGET_DIR:-target}/conformance/bench.md (the conformance report shows it) and
# bench.json, and fails when any count grows by more than the baseline's limit (+3 %).
# Installs valgrind (apt-get) and the gungraun-runner matching the gungraun crate
# (cargo install) when they are missing. The whole set takes about 3 minutes.
#
#   scripts/bench-counts.sh                 run, compare, fail on growth beyond the limit
#   scripts/bench-counts.sh --accept        run and write the counts as the new baseline
#   scripts/bench-counts.sh --filter PAT    only benchmarks matching PAT (e.g. '*frame*')
set -euo pipefail
cd "$(dirname "$0")/.."
accept=""; filter=""
while [ $# -gt 0 ]; do
    case "$1" in
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
        --accept) accept="--accept";;
        --filter) filter="$2"; shift;;
        *) echo "unknown option $1 (see --help)" >&2; exit 2;;
    esac
    shift
done

if ! command -v valgrind >/dev/null 2>&1; then
    echo "valgrind not found: installing it with apt-get" >&2
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq valgrind >/dev/null
fi
# The runner must be the crate's version exactly (renderer/Cargo.toml pins gungraun).
want="$(sed -n 's/^gungraun = "=\([0-9.]*\)"/\1/p' renderer/Cargo.toml)"
have="$(gungraun-runner --version 2>/dev/null | awk '{print $2}' || true)"
if [ "$have" != "$want" ]; then
    echo "installing gungraun-runner $want (found '${have:-none}')" >&2
    cargo install gungraun-runner --version "$want" --locked
fi

target="${CARGO_TARGET_DIR:-target}"
out="$target/conformance"
mkdir -p "$out"
args=(--output-format=json)
[ -n "$filter" ] && args+=("$filter")
cargo bench -q -p renderer --bench counts -- "${args[@]}" > "$out/bench-raw.jsonl"
python3 scripts/bench_counts.py "$out/bench-raw.jsonl" renderer/benches/baseline.json "$out" $accept ${filter:+--partial}
