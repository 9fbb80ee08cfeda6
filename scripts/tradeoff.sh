#!/usr/bin/env bash
# Measures error against the Mitsuba reference versus render time for three scenes, for
# this renderer (every sampler) and for Mitsuba, in one run (pip-installs Mitsuba if needed).
#
#   scripts/tradeoff.sh                 write ${CARGO_TARGET_DIR:-target}/conformance/tradeoff.md and .svg
#   scripts/tradeoff.sh --write-docs    also rewrite conformance/docs/tradeoff.md and tradeoff.svg
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
    ""|--write-docs) ;;
    *) echo "unknown option $1 (see --help)" >&2; exit 2;;
esac
if ! python3 -c "import mitsuba, numpy" >/dev/null 2>&1; then
    python3 -m pip install --quiet mitsuba numpy
fi
cargo run --release -q -p conformance --bin tradeoff -- "$@"
