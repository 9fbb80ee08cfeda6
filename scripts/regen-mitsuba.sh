#!/usr/bin/env bash
# Regenerates the Mitsuba 3 references: installs Mitsuba (and numpy) with pip if missing,
# exports each catalog scene of conformance/scenes/mitsuba to XML, and renders:
#   references/mitsuba/<scene>.geom.exr   pixel-centre geometry (distance, normal, hit mask)
#   references/mitsuba/<scene>.exr        radiance through the `moment` integrator
# recording tool, version, command, spp, scene hashes and date in references/manifest.toml.
# Rendered with Mitsuba's scalar_rgb variant, or for radiance with MITSUBA_VARIANT (for
# llvm_ad_rgb, with DRJIT_LIBLLVM_PATH: conformance/docs/mitsuba.md).
#
#   scripts/regen-mitsuba.sh [FILTER] [--spp N]      regenerate (default 8192 spp) the scenes
#                                                    FILTER selects: a whole name (or
#                                                    mitsuba::NAME) that scene alone, else
#                                                    every scene whose name contains FILTER
#   scripts/regen-mitsuba.sh --check [FILTER]        re-render into a temporary folder and
#                                                    check against the committed files
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac

if ! python3 -c "import mitsuba, numpy" >/dev/null 2>&1; then
    echo "Mitsuba not found: installing it with pip" >&2
    python3 -m pip install --quiet mitsuba numpy
fi

check=""
if [ "${1:-}" = "--check" ]; then check="--check"; shift; fi
# The dev profile is optimized (Cargo.toml), and shares its build with `cargo test`.
cargo run -q -p conformance -- regen mitsuba $check "$@"
