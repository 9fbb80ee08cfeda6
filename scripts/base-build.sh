# Sourced, not run, by scripts/same-bits.sh and scripts/ab-bench.sh: the release renderer
# built at a base commit beside the working tree's.
#
#   base_build WORK COMMIT
#
# checks COMMIT out in WORK/src (a detached worktree, kept between runs, made anew when it
# is missing or broken), builds the release renderer there into WORK/target, then builds
# the working tree's into its own target directory.
base_build() {
    local work="$1" base="$2"
    mkdir -p "$work"
    # A worktree of its own: a folder without one would let git find the enclosing
    # checkout (the target directory is usually inside it) and check the base out there.
    if [ ! -e "$work/src/.git" ] ||
        [ "$(git -C "$work/src" rev-parse --show-toplevel 2>/dev/null)" != "$(realpath "$work/src")" ]; then
        rm -rf "$work/src"
        git worktree prune
        git worktree add --detach "$work/src" "$base" >/dev/null
    fi
    git -C "$work/src" checkout -q --detach "$base"
    echo "building the base ($base) and the working tree" >&2
    (cd "$work/src" && CARGO_TARGET_DIR="$work/target" cargo build -q --release -p renderer)
    cargo build -q --release -p renderer
}
