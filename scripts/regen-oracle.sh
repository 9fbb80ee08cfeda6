#!/usr/bin/env bash
# The closed-form oracle (conformance/docs/oracle.md) computes its images at gate time, so
# it has no committed references: this script exists because every registered reference
# has one (the gate's messages name scripts/regen-<reference>.sh), and it says so.
#
#   scripts/regen-oracle.sh [--check] [FILTER]   nothing to regenerate; exits 0
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac
check=""
if [ "${1:-}" = "--check" ]; then check="--check"; shift; fi
cargo run -q -p conformance -- regen oracle $check "${1:-}"
