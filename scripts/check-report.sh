#!/usr/bin/env bash
# Checks the conformance report in headless Chromium: runs `conformance run [FILTER]`,
# opens $CARGO_TARGET_DIR/conformance/index.html (default target/), and fails when an image
# does not load, a scene has no anchor, or the summary is missing.
#
#   scripts/check-report.sh [FILTER]      check the report of the scenes matching FILTER
#   scripts/check-report.sh --self-test   also show that the check fails on a broken image
#                                         and on a missing anchor (in a copy of the report)
#
# Installs Debian's chromium with apt-get when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0;; esac
self_test=""
if [ "${1:-}" = "--self-test" ]; then self_test=1; shift; fi

if ! command -v chromium >/dev/null 2>&1; then
    echo "chromium not found: installing it with apt-get" >&2
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi

target="${CARGO_TARGET_DIR:-target}"
# A failing scene (exit 1) still writes the report: the gate judges the scenes, this checks
# the page. Any other exit (a build error, a filter that matches nothing) stops here.
set +e
cargo run -q -p conformance -- run "${1:-}" >/dev/null
rc=$?
set -e
if [ "$rc" -gt 1 ]; then echo "conformance run failed (exit $rc)" >&2; exit "$rc"; fi
report="$(cd "$target/conformance" && pwd)"

check() {  # check DIR: dump the DOM after load and verify it
    local dir="$1" profile
    profile="$(mktemp -d)"
    timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --user-data-dir="$profile" --virtual-time-budget=10000 --dump-dom \
        "file://$dir/index.html" 2>/dev/null > "$profile/dom.html"
    python3 - "$dir/results.json" "$profile/dom.html" <<'PY'
import json, re, sys
results = json.load(open(sys.argv[1]))
dom = open(sys.argv[2], encoding="utf-8").read()
problems = []
body = re.search(r"<body([^>]*)>", dom)
attrs = dict(re.findall(r'data-([a-z-]+)="([^"]*)"', body.group(1) if body else ""))
if "images" not in attrs:
    problems.append("the page's load handler did not run (no data-images on <body>)")
elif int(attrs["images"]) == 0:
    problems.append("the page has no images")
elif attrs.get("broken-images") != "0":
    m = re.search(r'<p id="broken">([^<]*)</p>', dom)
    problems.append("broken images: " + (m.group(1) if m else attrs.get("broken-images", "?")))
if 'id="summary"' not in dom:
    problems.append("no summary (id=\"summary\")")
for row in results["rows"]:
    anchor = row.get("anchor") or row["scene"]
    if f'<tr id="{anchor}"' not in dom:
        problems.append(f'no anchor for {row["reference"]}/{row["scene"]} (index.html#{anchor})')
if problems:
    print("report check FAILED:\n  " + "\n  ".join(problems))
    sys.exit(1)
print(f'report check: {attrs["images"]} images loaded, {len(results["rows"])} scene anchors, summary present')
PY
    local rc=$?
    rm -rf "$profile"
    return $rc
}

check "$report"
if [ -n "$self_test" ]; then
    copy="$(mktemp -d)"
    trap 'rm -rf "$copy"' EXIT
    cp -r "$report/." "$copy/"
    rm "$(find "$copy" -name difference.png -o -name z.png | head -1)"
    if check "$copy" >/dev/null; then echo "self-test FAILED: a missing image passed" >&2; exit 1; fi
    cp -r "$report/." "$copy/"
    first="$(python3 -c 'import json,sys;r=json.load(open(sys.argv[1]))["rows"][0];print(r.get("anchor") or r["scene"])' "$copy/results.json")"
    sed -i "s/<tr id=\"$first\"/<tr/" "$copy/index.html"
    if check "$copy" >/dev/null; then echo "self-test FAILED: a missing anchor passed" >&2; exit 1; fi
    echo "self-test: a missing image and a missing anchor each fail the check"
fi
