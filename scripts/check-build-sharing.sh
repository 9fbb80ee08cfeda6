#!/usr/bin/env bash
# Checks that the README's commands share one build: after `cargo test --workspace` has
# built, the quick start's render (`cargo run -p renderer`), `conformance run` and the
# subset command (`cargo test --test catalog NAME`) must compile nothing. A crate compiled
# again means the commands resolve different features of a shared dependency (README.md,
# "Build times"; the feature alignment in Cargo.toml and renderer/Cargo.toml).
#
#   scripts/check-build-sharing.sh     build the gate if needed, then check
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac

cargo test -q --workspace --no-run 2>/dev/null
status=0
for cmd in "build -p renderer --bin renderer" "build -p conformance --bin conformance" \
           "test --test catalog --no-run"; do
    out="$(cargo $cmd 2>&1)"
    if grep -q "Compiling" <<<"$out"; then
        echo "cargo $cmd compiled again after the gate's build:" >&2
        grep "Compiling" <<<"$out" >&2
        status=1
    fi
done
[ $status -eq 0 ] && echo "the quick start, conformance run and the subset command share the gate's build"
exit $status
