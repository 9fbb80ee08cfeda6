#!/usr/bin/env bash
# Mutation testing of the core modules with cargo-mutants: each mutant (one small change to
# the source, such as `<` for `<=` or a function body replaced by a default value) is built
# and run against the whole gate (`cargo test --workspace`); a mutant the gate does not
# fail is "missed". A full run is about 2,800 mutants, so it is split into shards that take
# roughly half an hour each here; conformance/docs/mutation.md has the results.
#
#   scripts/mutants.sh K [N]        run shard K of N (0 <= K < N; N defaults to 48)
#   scripts/mutants.sh --list       list every mutant of the examined files
#
# Results go to $CARGO_TARGET_DIR/mutants/shard-K-of-N/mutants.out (caught.txt,
# missed.txt, timeout.txt, unviable.txt, outcomes.json and a log per mutant). The mutants
# are built in $CARGO_TARGET_DIR/mutants/build, shared by the shards, so dependencies are
# compiled once. The run is nice'd: it is meant to run in the background.
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
    -f 'conformance/src/mitsuba/stats.rs'
)

if [ "${1:-}" = "--list" ]; then
    exec cargo mutants --list --workspace "${FILES[@]}"
fi

k="${1:?usage: scripts/mutants.sh K [N]}"
n="${2:-48}"
target="${CARGO_TARGET_DIR:-$PWD/target}"
out="$target/mutants/shard-$k-of-$n"
mkdir -p "$out"
# --test-workspace=true: every mutant runs the whole gate, not only its own crate's tests.
# -j 1: one build at a time (the machines here have two cores).
# --timeout: a mutant that makes the gate run past 5 minutes (an endless traversal, say)
#   counts as caught by timeout; the unmutated gate takes about 15 s.
CARGO_TARGET_DIR="$target/mutants/build" nice -n 19 cargo mutants \
    --workspace --test-workspace=true \
    --shard "$k/$n" --sharding round-robin \
    -j 1 --timeout 300 \
    "${FILES[@]}" \
    --output "$out"
