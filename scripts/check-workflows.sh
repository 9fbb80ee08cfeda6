#!/usr/bin/env bash
# Runs the workflows of conformance/docs/workflows.md, as written there, on a scratch copy
# of the catalog and references (CONFORMANCE_ROOT points the conformance tools at it), so
# the checkout is never touched. Installs POV-Ray with apt-get when it is missing.
#
#   scripts/check-workflows.sh     add a scene, regenerate a stale reference, review a
#                                  failure, waive a deliberate divergence and retire it
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac
repo="$(pwd)"
before="$(git status --porcelain 2>/dev/null || true)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$repo/target}"

if ! command -v povray >/dev/null 2>&1; then
    echo "povray not found: installing it with apt-get" >&2
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq povray >/dev/null
fi
mkdir -p "$HOME/.povray/3.7" && touch "$HOME/.povray/3.7/povray.conf"

root="$(mktemp -d)"
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/conformance"
cp -r conformance/scenes "$root/conformance/"
cp conformance/waivers.toml "$root/conformance/"
cp -r references "$root/"
export CONFORMANCE_ROOT="$root"
scene="$root/conformance/scenes/povray/wf_demo.toml"
log="$root/log.txt"

step() { echo "== $*"; }
gate() {  # gate EXPECT: run the scene's test and require EXPECT (pass, fail, ignored)
    set +e
    cargo test -q --test catalog povray::wf_demo -- --exact >"$log" 2>&1
    local rc=$?
    set -e
    case "$1" in
        pass) [ $rc -eq 0 ] && grep -q "1 passed" "$log" ;;
        ignored) [ $rc -eq 0 ] && grep -q "1 ignored" "$log" ;;
        fail) [ $rc -ne 0 ] && grep -q "povray/wf_demo:" "$log" ;;
    esac || { echo "expected the test to $1, got (exit $rc):"; cat "$log"; exit 1; }
}
expect() { grep -qF -- "$1" "$log" || { echo "expected output to contain: $1"; cat "$log"; exit 1; }; }

step "1. add a scene and generate its reference"
cargo run -q -p conformance -- new-scene wf_demo --catalog povray
gate pass

step "2. regenerate a stale reference"
sed -i 's/^color = \[0.85, 0.55, 0.3\]/color = [0.3, 0.55, 0.85]/' "$scene"
gate fail
expect "STALE"
expect "scripts/regen-povray.sh wf_demo"
scripts/regen-povray.sh wf_demo
gate pass

step "3. review a failure (a reference that disagrees with our render)"
cp "$root/references/povray/wf_demo.exr" "$root/good.exr"
sed -i 's/^color = \[0.3, 0.55, 0.85\]/color = [0.3, 0.56, 0.85]/' "$scene"
scripts/regen-povray.sh wf_demo
cp "$root/good.exr" "$root/references/povray/wf_demo.exr"   # fresh hashes, other pixels
gate fail
expect "povray/wf_demo: FAIL"
expect "worst pixels"
img="$(grep -o '/[^ ]*/failures/wf_demo/difference.png' "$log" | head -1)"
[ -f "$img" ] || { echo "failure image $img does not exist"; cat "$log"; exit 1; }
set +e; cargo run -q -p conformance -- run wf_demo >"$log" 2>&1; rc=$?; set -e
[ $rc -eq 1 ] || { echo "conformance run wf_demo should exit 1, got $rc"; cat "$log"; exit 1; }
grep -q 'id="wf_demo"' "$CARGO_TARGET_DIR/conformance/index.html"

step "4. waive a deliberate divergence, then retire the waiver"
cat >>"$root/conformance/waivers.toml" <<TOML

[[waiver]]
scene = "povray/wf_demo"
check = "pixels"
reason = "workflow check: a deliberate divergence"
date = "2026-11-24"
TOML
gate ignored
expect "WAIVED: pixels check waived since 2026-11-24"
scripts/regen-povray.sh wf_demo     # the divergence is gone
gate fail
expect "STALE WAIVER"
python3 - "$root/conformance/waivers.toml" <<'PY'
import sys
p = sys.argv[1]
text = open(p).read()
open(p, "w").write(text[: text.index("\n[[waiver]]")] + "\n")
PY
gate pass
[ "$(git -C "$repo" status --porcelain 2>/dev/null || true)" = "$before" ] || { echo "the checkout changed"; exit 1; }
echo "workflows: all four ran as written"
