#!/usr/bin/env bash
# Wall clock of the working tree against a base commit, measured in one run: the two
# builds alternate (base then new, new then base, ...), so a slow phase of the shared
# machine falls on both, and each row is the median of the per-pair ratios (new / base)
# with their range. For speed work whose effect is smaller than the machine's drift
# between runs (up to 2x here), which separate runs cannot resolve.
#
#   scripts/ab-bench.sh [BASE] [--pairs N] [--only mesh,physical]
#
# BASE defaults to HEAD (the last commit). mesh: `peers mesh --quick` (the 1M-triangle
# mesh, closest and any hit on four ray sets, 1 and 2 threads; above 1, new is faster).
# physical: the four Mitsuba scenes of scripts/bench-peers.sh at 128 x 128, 64 spp, the
# sobol sampler, one thread, render time as the CLI reports it (below 1, new is faster),
# and whether the two images are the same bits. Pairs: 4 by default.
#
# The base is built in a worktree under ${CARGO_TARGET_DIR:-target}/ab/ (its own target
# directory, kept between runs); output goes to ${CARGO_TARGET_DIR:-target}/ab/ab.md.
set -euo pipefail
cd "$(dirname "$0")/.."
base_ref=HEAD; pairs=4; only="mesh,physical"
while [ $# -gt 0 ]; do
    case "$1" in
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
        --pairs) pairs="$2"; shift;;
        --only) only="$2"; shift;;
        -*) echo "unknown option $1 (see --help)" >&2; exit 2;;
        *) base_ref="$1";;
    esac
    shift
done
for part in ${only//,/ }; do
    case "$part" in mesh|physical) ;; *) echo "ab-bench.sh: --only takes mesh and physical, not '$part'" >&2; exit 2;; esac
done
case "$pairs" in ''|*[!0-9]*|0) echo "ab-bench.sh: --pairs takes a count of at least 1, not '$pairs'" >&2; exit 2;; esac
base="$(git rev-parse --verify -q "$base_ref^{commit}")" ||
    { echo "ab-bench.sh: '$base_ref' names no commit" >&2; exit 2; }
root="$PWD"
target="$(realpath -m "${CARGO_TARGET_DIR:-$root/target}")"
work="$target/ab"
. scripts/base-build.sh
base_build "$work" "$base"

# The peers bench's executable, built in the given folder with the given target directory.
peers_bin() {
    (cd "$1" && CARGO_TARGET_DIR="$2" cargo bench -q -p renderer --bench peers --no-run \
        --message-format=json) |
        python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["target"]["name"] == "peers":
        print(m["executable"])'
}
base_peers="$(peers_bin "$work/src" "$work/target")"
new_peers="$(peers_bin "$root" "$target")"
if [ -z "$base_peers" ] || [ -z "$new_peers" ]; then
    echo "ab-bench.sh: no peers bench executable came out of the build (base: '$base_peers', new: '$new_peers')" >&2
    exit 1
fi
python3 scripts/ab_bench.py "$work" --pairs "$pairs" --only "$only" \
    --base "$work/target/release/renderer" "$base_peers" \
    --new "$target/release/renderer" "$new_peers" --base-name "$(git rev-parse --short "$base")"
