#!/usr/bin/env bash
# Measures error against the Mitsuba reference versus render time for three scenes, for
# this renderer (every sampler) and for Mitsuba, in one run. Writes
# conformance/docs/tradeoff.md and conformance/docs/tradeoff.svg.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! python3 -c "import mitsuba, numpy" >/dev/null 2>&1; then
    python3 -m pip install --quiet mitsuba numpy
fi
cargo run --release -q -p conformance --bin tradeoff
