#!/usr/bin/env bash
# Regenerates the POV-Ray references: installs POV-Ray 3.7 if it is missing, exports each
# catalog scene to SDL, renders it at pixel centres (-A) to a half-float EXR in
# references/povray/, and records tool, version, command, scene hashes and date in
# references/manifest.toml.
#
#   scripts/regen-povray.sh [FILTER]           regenerate the scenes FILTER selects: a whole
#                                              name (or povray::NAME) that scene alone, else
#                                              every scene whose name contains FILTER
#   scripts/regen-povray.sh --check [FILTER]   re-render from scratch into a temporary folder
#                                              and check the result equals the committed files
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac

if ! command -v povray >/dev/null 2>&1; then
    echo "povray not found: installing it with apt-get" >&2
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq povray >/dev/null
fi
# The first run warns that ~/.povray/3.7/povray.conf is missing; an empty one silences it.
mkdir -p "$HOME/.povray/3.7" && touch "$HOME/.povray/3.7/povray.conf"

check=""
if [ "${1:-}" = "--check" ]; then check="--check"; shift; fi
# The dev profile is optimized (Cargo.toml), and shares its build with `cargo test`.
cargo run -q -p conformance -- regen povray $check "${1:-}"
