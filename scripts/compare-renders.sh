# Sourced, not run, by scripts/same-bits.sh and scripts/build-pgo.sh: every catalog and
# example scene rendered by two renderer binaries and compared byte for byte.
#
#   compare_renders OLD NEW WORK WHAT
#
# renders each scene with OLD into WORK/old and with NEW into WORK/new: EXR with every AOV
# at 1 and 7 spp, and the 8-bit sRGB PNG at 1 spp (its own encoding path: a change there
# leaves every EXR alone). Sets RENDERS to the renders each binary made and DIFFER to
# those that differ or failed; when there are any, prints "WHAT in K of N renders:" and
# their list to stderr and returns 1. Run from the repository root.
compare_renders() {
    local old="$1" new="$2" work="$3" what="$4" scene name run spp ext aov side bin
    rm -rf "$work/old" "$work/new"
    mkdir -p "$work/old" "$work/new"
    DIFFER=()
    RENDERS=0
    while IFS= read -r scene; do
        name="$(echo "${scene#./}" | tr '/' '_')"
        for run in "1 exr --aov" "7 exr --aov" "1 png"; do
            read -r spp ext aov <<<"$run"
            for side in old new; do
                bin="$old"; [ "$side" = new ] && bin="$new"
                if ! "$bin" render "$scene" -o "$work/$side/$name.$spp.$ext" ${aov:+"$aov"} \
                    --spp "$spp" --threads 2 >/dev/null 2>&1; then
                    DIFFER+=("$scene ($spp spp, $ext): the $side renderer failed")
                fi
            done
            if ! cmp -s "$work/old/$name.$spp.$ext" "$work/new/$name.$spp.$ext"; then
                DIFFER+=("$scene ($spp spp, $ext)")
            fi
            RENDERS=$((RENDERS + 1))
        done
    done < <(find conformance/scenes renderer/scenes -name '*.toml' | sort)
    if [ "${#DIFFER[@]}" -gt 0 ]; then
        echo "$what in ${#DIFFER[@]} of $RENDERS renders:" >&2
        printf '  %s\n' "${DIFFER[@]}" >&2
        return 1
    fi
}
