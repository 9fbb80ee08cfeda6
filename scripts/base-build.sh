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
    if ! git -C "$work/src" rev-parse --git-dir >/dev/null 2>&1; then
        rm -rf "$work/src"
        git worktree prune
        git worktree add --detach "$work/src" "$base" >/dev/null
    fi
    git -C "$work/src" checkout -q --detach "$base"
    echo "building the base ($base) and the working tree" >&2
    (cd "$work/src" && CARGO_TARGET_DIR="$work/target" cargo build -q --release -p renderer)
    cargo build -q --release -p renderer
}
