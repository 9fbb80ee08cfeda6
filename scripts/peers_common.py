"""What the parts of scripts/bench_peers.py share: where our binaries are, a timed run,
the spread of ratios, and our peers bench."""

import json
import os
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
# scripts/bench-peers.sh points these at the profile-guided build (scripts/build-pgo.sh
# --env) unless it is run with --plain.
BIN_DIR = os.environ.get("PEERS_BIN_DIR", os.path.join(TARGET, "release"))
RENDERER = os.path.join(BIN_DIR, "renderer")
CONFORMANCE = os.path.join(BIN_DIR, "conformance")
BUILD = "profile-guided (scripts/build-pgo.sh)" if "PEERS_BIN_DIR" in os.environ else "plain `cargo build --release`"


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
    env = dict(os.environ)
    if "PEERS_BENCH_TARGET_DIR" in env:
        env["CARGO_TARGET_DIR"] = env["PEERS_BENCH_TARGET_DIR"]
        env["RUSTFLAGS"] = env.get("PEERS_BENCH_RUSTFLAGS", "")
    out = subprocess.run(["cargo", "bench", "-q", "-p", "renderer", "--bench", "peers", "--", *args],
                         cwd=ROOT, capture_output=True, text=True, check=True, env=env).stdout
    return json.loads(out.strip().splitlines()[-1])
