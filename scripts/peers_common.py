"""What the parts of scripts/bench_peers.py share: where our binaries are, a timed run,
the spread of ratios, and our peers bench."""

import json
import os
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
# Ours is the build README.md gives: the plain `cargo build --release` (and `cargo bench`,
# whose profile is the release one, for the peers bench).
BIN_DIR = os.path.join(TARGET, "release")
RENDERER = os.path.join(BIN_DIR, "renderer")
CONFORMANCE = os.path.join(BIN_DIR, "conformance")
BUILD = "plain `cargo build --release`"


def run_timed(argv, cwd=None):
    """Runs argv; returns (wall s, CPU s of the child, stdout+stderr)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if status != 0:
        raise RuntimeError(f"{argv[0]} failed ({status}):\n{out.decode(errors='replace')[-2000:]}")
    return wall, ru.ru_utime + ru.ru_stime, out.decode(errors="replace")


def spread(ratios):
    return f"{min(ratios):.2f}–{max(ratios):.2f}" if len(ratios) > 1 else "—"


def peers_bench(*args):
    out = subprocess.run(["cargo", "bench", "-q", "-p", "renderer", "--bench", "peers", "--", *args],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def med(x):
    """The median (the upper one of an even count)."""
    return sorted(x)[len(x) // 2]
