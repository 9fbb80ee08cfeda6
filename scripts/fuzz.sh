#!/usr/bin/env bash
# Runs the scene fuzzer (renderer/tests/fuzz.rs) for longer than the gate does: mutated
# committed scenes through parse, build and tiny renders, in a child process so crashes
# and hangs are caught. Prints the number of inputs run; on a failure, the input is kept
# and named.
#
#   scripts/fuzz.sh [SECONDS] [SEED] [RENDER_EVERY]
#       default 600 seconds, seed 1, one input in 16 rendered (0: parse + build only,
#       the fastest mode). Built with --release.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
set +e
FUZZ_SECONDS="${1:-600}" FUZZ_SEED="${2:-1}" FUZZ_RENDER_EVERY="${3:-16}" \
    cargo test -q --release -p renderer --test fuzz -- test01 --nocapture >"$log" 2>&1
rc=$?
set -e
grep -E "fuzz:|crashed|hangs" "$log" || tail -30 "$log"
exit $rc
