#!/usr/bin/env bash
# Mutation testing of the core modules with cargo-mutants: each mutant (one small change to
# the source, such as `<` for `<=` or a function body replaced by a default value) is built
# and run against the whole gate (`cargo test --workspace`); a mutant the gate does not
# fail is "missed". A full run is about 2,900 mutants, so it is split into shards (48 by
# default, about 61 mutants and one to two hours each here); conformance/docs/mutation.md
# has the results.
#
#   scripts/mutants.sh K [N]        run shard K of N (0 <= K < N; N defaults to 48)
#   scripts/mutants.sh --list       list every mutant of the examined files
#
# Results go to $CARGO_TARGET_DIR/mutants/shard-K-of-N/mutants.out (caught.txt,
# missed.txt, timeout.txt, unviable.txt, outcomes.json and a log per mutant). The mutants
# are made in a worktree of the committed HEAD ($CARGO_TARGET_DIR/mutants/src) and built in
# $CARGO_TARGET_DIR/mutants/build, shared by the shards, so dependencies are compiled once.
# The run is nice'd: it is meant to run in the background.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac

if ! command -v cargo-mutants >/dev/null 2>&1; then
    echo "cargo-mutants not found: installing it with cargo install" >&2
    cargo install cargo-mutants --locked
fi

# The core modules (issue 11): camera, transform, shapes, aggregate, BVH, boxes, ray
# offsets, samplers, both light-transport models, and the comparison and statistics code.
FILES=(
    -f 'renderer/src/camera.rs'
    -f 'renderer/src/transform.rs'
    -f 'renderer/src/shapes/*.rs'
    -f 'renderer/src/aggregate.rs'
    -f 'renderer/src/bvh.rs'
    -f 'renderer/src/aabb.rs'
    -f 'renderer/src/spawn.rs'
    -f 'renderer/src/sampler.rs'
    -f 'renderer/src/shading.rs'
    -f 'renderer/src/physical.rs'
    -f 'conformance/src/povray/compare.rs'
    -f 'conformance/src/mitsuba/compare.rs'
)

if [ "${1:-}" = "--list" ]; then
    exec cargo mutants --list --workspace "${FILES[@]}"
fi

k="${1:?usage: scripts/mutants.sh K [N]}"
n="${2:-48}"
target="${CARGO_TARGET_DIR:-$PWD/target}"
out="$target/mutants/shard-$k-of-$n"
src="$target/mutants/src"
mkdir -p "$out"

# The mutants are made in a checkout of the committed HEAD at a fixed path (a detached git
# worktree, $target/mutants/src), in place. cargo-mutants' default copies the tree to a
# new temporary folder per run, and a new path makes cargo rebuild every workspace crate
# before the first mutant; here a run after the first rebuilds only what changed. A run
# that was stopped halfway leaves a mutated file behind: the reset below undoes it.
head="$(git rev-parse HEAD)"
if [ -n "$(git status --porcelain --untracked-files=no)" ]; then
    echo "note: uncommitted changes are not mutated: the run tests HEAD ($head)" >&2
fi
if ! git -C "$src" rev-parse --git-dir >/dev/null 2>&1; then
    rm -rf "$src"
    git worktree prune
    git worktree add --detach "$src" "$head" >/dev/null
fi
git -C "$src" reset -q --hard
git -C "$src" clean -q -fd
git -C "$src" checkout -q --detach "$head"

# Speed, without changing what is tested: no debug info (linking the 30-odd test binaries
# is most of a mutant's build), the mold linker when it is installed, and the scene fuzzer
# (renderer/tests/fuzz.rs, 20 s by default) for 2 s: its inputs are random, so a mutant
# only it could catch would be caught by chance; the deterministic tests decide.
export CARGO_PROFILE_DEV_DEBUG=0 CARGO_PROFILE_TEST_DEBUG=0 FUZZ_SECONDS=2
# RUSTFLAGS replaces the target-cpu of .cargo/config.toml, so it is repeated here: without
# it the AVX node test (bvh::slab) would not be compiled, and its mutants never tested.
if command -v mold >/dev/null 2>&1; then
    cpu=""
    [ "$(uname -m)" = x86_64 ] && cpu="-C target-cpu=x86-64-v3"
    export RUSTFLAGS="${RUSTFLAGS:-$cpu} -C link-arg=-fuse-ld=mold"
else
    echo "note: mold not found (apt-get install mold): linking each mutant takes longer" >&2
fi

# --test-workspace=true: every mutant runs the whole gate, not only its own crate's tests.
# --in-place runs one mutant at a time (the machines here have two cores anyway).
# --timeout: a mutant that makes the gate run past 5 minutes (an endless traversal, say)
#   counts as caught by timeout; the unmutated gate takes about 30 s.
cd "$src"
CARGO_TARGET_DIR="$target/mutants/build" nice -n 19 cargo mutants \
    --in-place \
    --workspace --test-workspace=true \
    --shard "$k/$n" --sharding round-robin \
    --timeout 300 \
    "${FILES[@]}" \
    --output "$out"
