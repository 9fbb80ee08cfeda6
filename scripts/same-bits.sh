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
rm -rf "$work/old" "$work/new"
mkdir -p "$work/old" "$work/new"
differ=()
n=0
while IFS= read -r scene; do
    name="$(echo "${scene#./}" | tr '/' '_')"
    # EXR with every AOV at 1 and 7 spp, and the 8-bit sRGB PNG at 1 spp (its own
    # encoding path: a change there leaves every EXR alone).
    for run in "1 exr --aov" "7 exr --aov" "1 png"; do
        read -r spp ext aov <<<"$run"
        for side in old new; do
            bin="$old"; [ "$side" = new ] && bin="$new"
            if ! "$bin" render "$scene" -o "$work/$side/$name.$spp.$ext" ${aov:+"$aov"} \
                --spp "$spp" --threads 2 >/dev/null 2>&1; then
                differ+=("$scene ($spp spp, $ext): the $side renderer failed")
            fi
        done
        if ! cmp -s "$work/old/$name.$spp.$ext" "$work/new/$name.$spp.$ext"; then
            differ+=("$scene ($spp spp, $ext)")
        fi
    done
    n=$((n + 1))
done < <(find conformance/scenes renderer/scenes -name '*.toml' | sort)
if [ "${#differ[@]}" -gt 0 ]; then
    echo "DIFFERENT from $base in ${#differ[@]} of $((3 * n)) renders:" >&2
    printf '  %s\n' "${differ[@]}" >&2
    exit 1
fi
echo "same bits: $n scenes at 1 and 7 spp (EXR with AOVs) and at 1 spp (PNG), base $base" >&2
