#!/usr/bin/env bash
# Checks that a change did not change any result: renders every catalog and example scene
# (EXR with every AOV at 1 and 7 spp, and PNG at 1 spp) with the renderer built
# from a base commit and from the working tree, and compares the files byte for byte.
# Speed work that should not change a result (acceleration never does; ARCHITECTURE.md)
# runs this before it is committed.
#
#   scripts/same-bits.sh [BASE]        BASE defaults to HEAD (the last commit)
#
# The base is built in a worktree under ${CARGO_TARGET_DIR:-target}/same-bits/ (its own
# target directory, kept between runs); the renders go there too. Exits 1 and names the
# scenes whose output differs.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac
base="$(git rev-parse "${1:-HEAD}")"
root="$PWD"
target="$(realpath -m "${CARGO_TARGET_DIR:-$root/target}")"
work="$target/same-bits"
. scripts/base-build.sh
base_build "$work" "$base"
old="$work/target/release/renderer"
new="$target/release/renderer"
. scripts/compare-renders.sh
compare_renders "$old" "$new" "$work" "DIFFERENT from $base" || exit 1
echo "same bits: $((RENDERS / 3)) scenes at 1 and 7 spp (EXR with AOVs) and at 1 spp (PNG), base $base" >&2
