#!/usr/bin/env bash
# Wall-clock throughput side by side with the peers, each run as its own users run it, in
# one run: Embree 4 (embreex) in its default mode (and robust mode) on the same ~1M-triangle
# mesh and rays, on as many threads as ours; POV-Ray 3.7 on the same exported Whitted
# scenes; Mitsuba 3's fast `llvm_ad_rgb` variant (and `scalar_rgb`) on the same exported
# physical scenes, four of the catalog and four in no catalog; and our cost growth from
# 100 to 10^6 primitives. Ours is the plain `cargo build --release`, the build README.md
# gives. Installs POV-Ray and libLLVM 19 (apt-get) and Mitsuba, numpy and embreex (pip)
# when they are missing. Writes ${CARGO_TARGET_DIR:-target}/bench-peers/peers.md and peers.json.
#
#   scripts/bench-peers.sh                  the full run (31 minutes on a 2-core Zen 5, two hours on a Xeon; most of it Mitsuba)
#   scripts/bench-peers.sh --quick          small sizes and one pair each (a few minutes)
#   scripts/bench-peers.sh --only embree,growth     some of embree, povray, mitsuba, growth
#   scripts/bench-peers.sh --write-docs     also put the table into renderer/docs/performance.md
set -euo pipefail
cd "$(dirname "$0")/.."
quick=""; only=""; write_docs=""
while [ $# -gt 0 ]; do
    case "$1" in
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;;
        --quick) quick="--quick";;
        --only) only="$2"; shift;;
        --write-docs) write_docs=1;;
        *) echo "unknown option $1 (see --help)" >&2; exit 2;;
    esac
    shift
done
if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
need_apt=""
command -v povray >/dev/null 2>&1 || need_apt="povray"
# Mitsuba's llvm variants need a libLLVM newer than Debian 12's default 14/15, which abort
# on its kernels ("Cannot select ... fminimum"): libLLVM 19 works (conformance/docs/mitsuba.md).
llvm_lib() { ldconfig -p | awk '/libLLVM(-|\.so\.)19/ { print $NF; exit }'; }
[ -n "$(llvm_lib)" ] || need_apt="$need_apt libllvm19"
if [ -n "$need_apt" ]; then
    echo "installing$need_apt with apt-get" >&2
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq $need_apt >/dev/null
fi
export DRJIT_LIBLLVM_PATH="${DRJIT_LIBLLVM_PATH:-$(llvm_lib)}"
mkdir -p "$HOME/.povray/3.7" && touch "$HOME/.povray/3.7/povray.conf"
if ! python3 -c "import mitsuba, numpy, embreex" >/dev/null 2>&1; then
    echo "installing mitsuba, numpy and embreex with pip" >&2
    python3 -m pip install --quiet mitsuba numpy embreex
fi
cargo build -q --release -p renderer -p conformance
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
