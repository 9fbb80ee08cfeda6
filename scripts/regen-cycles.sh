#!/usr/bin/env bash
# Regenerates the Blender Cycles references: installs bpy 5.0.1 (Blender as a Python module,
# about 1 GB) with numpy into a venv at target/cycles-venv if it is missing (bpy 5.0.1 needs
# Python 3.11), exports each scene of the physical catalog (conformance/scenes/mitsuba) to
# JSON, and renders:
#   references/cycles/<scene>.geom.exr   geometry (distance, normal, hit mask)
#   references/cycles/<scene>.exr        radiance: the mean and the variance of 16 seeds
# recording tool, version, command, spp, scene hashes and date in references/manifest.toml
# (conformance/docs/cycles.md).
#
#   scripts/regen-cycles.sh [FILTER]          regenerate the scenes FILTER selects
#   scripts/regen-cycles.sh --check [FILTER]  re-render into a temporary folder and check
#                                             against the committed files
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac

venv=target/cycles-venv
if ! "$venv/bin/python" -c "import bpy, numpy" >/dev/null 2>&1; then
    py=$(command -v python3.11 || command -v python3)
    if ! "$py" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))'; then
        echo "bpy 5.0.1 needs Python 3.11 ($py is $("$py" --version))" >&2
        exit 1
    fi
    echo "bpy not found: installing bpy 5.0.1 into $venv" >&2
    rm -rf "$venv"
    "$py" -m venv "$venv"
    "$venv/bin/python" -m pip install --quiet bpy==5.0.1 numpy
fi
export CYCLES_PYTHON="$PWD/$venv/bin/python"

check=""
if [ "${1:-}" = "--check" ]; then check="--check"; shift; fi
cargo run -q -p conformance -- regen cycles $check "$@"
