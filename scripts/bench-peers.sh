#!/usr/bin/env bash
# Wall-clock throughput side by side with the peers, in one run: Embree 4 (embreex) on the
# same ~1M-triangle mesh and rays, POV-Ray 3.7 on the same exported Whitted scenes, Mitsuba 3
# on the same exported physical scenes, and our cost growth from 100 to 10^6 primitives.
# Installs POV-Ray (apt-get) and Mitsuba, numpy and embreex (pip) when they are missing.
# Writes ${CARGO_TARGET_DIR:-target}/bench-peers/peers.md and peers.json.
#
#   scripts/bench-peers.sh                  the full run (about 30 minutes here)
#   scripts/bench-peers.sh --quick          small sizes and one pair each (a few minutes)
#   scripts/bench-peers.sh --only embree,growth     some of embree, povray, mitsuba, growth
#   scripts/bench-peers.sh --write-docs     also put the table into renderer/docs/performance.md
#   scripts/bench-peers.sh --plain          time the plain `cargo build --release` binaries
#                                           instead of the profile-guided build
#
# Ours is the profile-guided build of scripts/build-pgo.sh (the same bits, which that
# script checks on every catalog and example scene; about 10 % faster; 6 more minutes), unless --plain.
set -euo pipefail
cd "$(dirname "$0")/.."
quick=""; only=""; write_docs=""; plain=""
while [ $# -gt 0 ]; do
    case "$1" in
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
        --quick) quick="--quick";;
        --only) only="$2"; shift;;
        --write-docs) write_docs=1;;
        --plain) plain=1;;
        *) echo "unknown option $1 (see --help)" >&2; exit 2;;
    esac
    shift
done
if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
if ! command -v povray >/dev/null 2>&1; then
    echo "povray not found: installing it with apt-get" >&2
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq povray >/dev/null
fi
mkdir -p "$HOME/.povray/3.7" && touch "$HOME/.povray/3.7/povray.conf"
if ! python3 -c "import mitsuba, numpy, embreex" >/dev/null 2>&1; then
    echo "installing mitsuba, numpy and embreex with pip" >&2
    python3 -m pip install --quiet mitsuba numpy embreex
fi
cargo build -q --release -p renderer -p conformance
if [ -z "$plain" ]; then
    eval "$(scripts/build-pgo.sh --env)"
fi
out="${CARGO_TARGET_DIR:-target}/bench-peers"
python3 scripts/bench_peers.py "$out" $quick ${only:+--only "$only"}
if [ -n "$write_docs" ]; then
    python3 - "$out/peers.md" renderer/docs/performance.md <<'PY'
import sys
table, doc = open(sys.argv[1]).read(), sys.argv[2]
text = open(doc).read()
a, b = "<!-- peers:begin -->\n", "<!-- peers:end -->"
i, j = text.index(a) + len(a), text.index(b)
open(doc, "w").write(text[:i] + table + "\n" + text[j:])
print("updated " + doc)
PY
fi
