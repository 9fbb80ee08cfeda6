#!/usr/bin/env bash
# A profile-guided (PGO) release build of the renderer, the conformance tool and the peers
# bench: the same code and the same output bits as `cargo build --release`, laid out and
# inlined by what a training run measured (renderer/docs/performance.md, "A profile-guided
# build"). About 10 % faster on the physical scenes; the gate never uses it, and neither
# does scripts/bench-peers.sh: the training below runs the peers bench's own mesh and ray
# sets and the Mitsuba catalog scenes it times, so the peer comparison times the plain
# `cargo build --release` (renderer/docs/performance.md).
#
#   scripts/build-pgo.sh            builds into ${CARGO_TARGET_DIR:-target}/pgo/use
#   scripts/build-pgo.sh --env      also prints, for `eval`, where the builds are
#                                   (PEERS_BIN_DIR, PEERS_BENCH_TARGET_DIR, and the
#                                   PEERS_BENCH_RUSTFLAGS that `cargo bench` needs there)
#
# Steps: an instrumented build (target/pgo/instrumented); a training run on it, single
# threaded so the counts are the same each time (every catalog scene as written, the
# Mitsuba catalog's scenes with every sampler, with and without adaptive sampling and
# light paths, and the peers bench's quick mesh and growth runs); the counts merged by
# llvm-profdata (rustup's llvm-tools component, installed when missing: it must match
# rustc's LLVM); the builds that read them; a check that the PGO renderer gives the plain
# release build's bits on every catalog and example scene (scripts/same-bits.sh's
# comparison; it fails otherwise). The result is
# target/pgo/use/release/renderer and .../conformance, and the peers bench in
# target/pgo/bench, which `cargo bench` finds with the printed environment. About 6
# minutes here.
set -euo pipefail
cd "$(dirname "$0")/.."
print_env=""
case "${1:-}" in
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
    --env) print_env=1;;
    "") ;;
    *) echo "unknown option $1 (see --help)" >&2; exit 2;;
esac
target="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
pgo="$target/pgo"
host="$(rustc -vV | sed -n 's/^host: //p')"
profdata="$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-profdata"
if [ ! -x "$profdata" ]; then
    echo "llvm-profdata not found: installing rustup's llvm-tools component" >&2
    rustup component add llvm-tools >&2
fi
# RUSTFLAGS replaces .cargo/config.toml's flags, so its target CPU is repeated here.
base_flags=""
[ "$host" = x86_64-unknown-linux-gnu ] && base_flags="-C target-cpu=x86-64-v3"

# 1. Instrumented. Each binary learns from its own run: the renderer from renders, the
# peers bench from its mesh and growth runs. One profile for both would let the bench's
# millions of mesh rays make the renderer's integrators look cold (measured: no gain on
# the physical scenes with one merged profile, 10 % with the renderer's own).
rm -rf "$pgo/profiles" "$pgo/train"
mkdir -p "$pgo/profiles/renderer" "$pgo/profiles/peers" "$pgo/train/scenes"
# The variants below live in train/scenes, where the catalog's "../meshes/..." must resolve.
ln -s "$(realpath conformance/scenes/meshes)" "$pgo/train/meshes"
# The bench builds in a folder of its own: `cargo bench` also rebuilds the renderer binary,
# with the dev-dependencies' features, whose counts would not match the release build's
# functions (a renderer trained that way ran no faster than the plain build).
inst() {
    local dir="$1"
    shift
    RUSTFLAGS="$base_flags -Cprofile-generate=$pgo/profiles" CARGO_TARGET_DIR="$pgo/$dir" "$@"
}
echo "build-pgo: the instrumented build" >&2
inst instrumented cargo build -q --release -p renderer -p conformance
inst instrumented-bench cargo bench -q -p renderer --bench peers --no-run 2>/dev/null
renderer="$pgo/instrumented/release/renderer"

# 2. Training, one thread where the choice is ours (the mesh bench also times two).
echo "build-pgo: training" >&2
log="$pgo/train/log"
render() {
    LLVM_PROFILE_FILE="$pgo/profiles/renderer/%p.profraw" "$renderer" render "$@" --threads 1 2>>"$log" ||
        { cat "$log" >&2; echo "build-pgo: training failed" >&2; exit 1; }
}
for scene in $(find conformance/scenes -name '*.toml' | sort); do
    render "$scene" -o "$pgo/train/out.exr"
done
for scene in conformance/scenes/mitsuba/*.toml; do
    for sampler in independent stratified sobol; do
        for extra in "" "adaptive = true" "adaptive = true\nlight_paths = 0.5"; do
            sed "0,/^\[render\]$/s//[render]\nsampler = \"$sampler\"\n$extra/" "$scene" > "$pgo/train/scenes/scene.toml"
            render "$pgo/train/scenes/scene.toml" -o "$pgo/train/out.exr" --spp 16 --size 64x64
        done
    done
done
render conformance/scenes/mitsuba/mi_cornell.toml -o "$pgo/train/out.exr" --aov
render conformance/scenes/povray/$(ls conformance/scenes/povray | head -1) -o "$pgo/train/out.png"
for run in "mesh $pgo/train/mesh --quick" "growth --quick"; do
    # shellcheck disable=SC2086 # the words of $run are the bench's arguments
    LLVM_PROFILE_FILE="$pgo/profiles/peers/%p.profraw" inst instrumented-bench cargo bench -q -p renderer --bench peers -- $run >/dev/null
done

# 3. The counts, merged per binary.
"$profdata" merge -o "$pgo/renderer.profdata" "$pgo/profiles/renderer"
"$profdata" merge -o "$pgo/peers.profdata" "$pgo/profiles/peers"

# 4. The builds that read them: the renderer and the conformance tool in target/pgo/use,
# the peers bench in target/pgo/bench.
echo "build-pgo: the optimized builds" >&2
bench_flags="$base_flags -Cprofile-use=$pgo/peers.profdata"
RUSTFLAGS="$base_flags -Cprofile-use=$pgo/renderer.profdata" CARGO_TARGET_DIR="$pgo/use" \
    cargo build -q --release -p renderer -p conformance
RUSTFLAGS="$bench_flags" CARGO_TARGET_DIR="$pgo/bench" cargo bench -q -p renderer --bench peers --no-run 2>/dev/null

# 5. The same bits as the plain build: scripts/same-bits.sh's comparison, every catalog
# and example scene at 1 and 7 spp (EXR with every AOV) and as PNG.
echo "build-pgo: comparing the renders with the plain release build's" >&2
cargo build -q --release -p renderer
. scripts/compare-renders.sh
compare_renders "$target/release/renderer" "$pgo/use/release/renderer" "$pgo/check" \
    "build-pgo: the PGO build renders other bits than the plain one" || exit 1
echo "build-pgo: $pgo/use/release/renderer (the same bits in all $RENDERS renders)" >&2
if [ -n "$print_env" ]; then
    printf 'export PEERS_BIN_DIR=%q\nexport PEERS_BENCH_TARGET_DIR=%q\nexport PEERS_BENCH_RUSTFLAGS=%q\n' \
        "$pgo/use/release" "$pgo/bench" "$bench_flags"
fi
