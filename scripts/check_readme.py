#!/usr/bin/env python3
"""Runs every command that README.md shows, so the README cannot drift.

Commands are the lines of its ```sh blocks and the inline `code` spans that start with
`cargo `, `scripts/` or `python3 `. Each is run the cheapest way that still exercises it:
renders at a tiny size into a scratch folder, tests as `--list` or `--no-run` (a dry run),
scripts with `--help`, and placeholders (FILTER, SCENE, NAME, N, K) replaced by real
values. A command no rule knows fails the check, naming its README line.

    python3 scripts/check_readme.py            run them all
    python3 scripts/check_readme.py --list     print each command and how it is run
"""

import os
import re
import shlex
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PREFIXES = ("cargo ", "scripts/", "python3 ")


def commands(text):
    """(line number, command) for every command README.md shows."""
    out, in_sh = [], False
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if s.startswith("```"):
            in_sh = s == "```sh"
            continue
        if in_sh:
            cmd = s.split("  #")[0].split(" # ")[0].strip()
            if cmd:
                out.append((n, cmd))
        else:
            for span in re.findall(r"`([^`]+)`", line):
                if span.startswith(PREFIXES) and not span.endswith("/"):
                    out.append((n, span.strip()))
    return out


def plan(cmd, scratch):
    """The argv that exercises `cmd`, or None when no rule covers it."""
    subst = {
        "[FILTER]": "prim_sphere_identity",
        "FILTER": "prim_sphere_identity",
        "SCENE.toml": "renderer/scenes/sphere.toml",
        "SCENE.pov": os.path.join(scratch, "scene.pov"),
        "SCENE.xml": os.path.join(scratch, "scene.xml"),
        "[--spp N]": "",
        "--spp N": "--spp 4",
    }
    if "export mitsuba" in cmd:
        # Mitsuba exports need a scene of the physical model.
        subst["SCENE.toml"] = "conformance/scenes/mitsuba/mi_diffuse_point.toml"
    for k, v in subst.items():
        cmd = cmd.replace(k, v)
    argv = shlex.split(cmd)
    if argv[:2] == ["cargo", "run"]:
        sep = argv.index("--")
        pkg, args = argv[argv.index("-p") + 1], argv[sep + 1:]
        if "--help" in args:
            return argv
        if pkg == "renderer" and args[:1] == ["render"]:
            # A tiny render into the scratch folder.
            o = args.index("-o")
            args[o + 1] = os.path.join(scratch, os.path.basename(args[o + 1]))
            return argv[: sep + 1] + args + ["--size", "16x12", "--spp", "1"]
        if pkg == "conformance" and args[:1] == ["new-scene"]:
            return argv[: sep + 1] + ["new-scene", "--help"]
        if pkg == "conformance" and args[:1] in (["run"], ["export"]):
            return argv
        return None
    if argv[:2] == ["cargo", "test"]:
        if "--list" in argv:
            return argv
        if "--test" in argv and "--workspace" not in argv:
            return argv  # a subset of the gate: cheap, run it
        return argv[:2] + ["--no-run"] + [a for a in argv[2:] if a != "--no-fail-fast"]
    if argv[:3] == ["cargo", "nextest", "run"]:
        return ["cargo", "nextest", "list"] + argv[3:]
    if argv[:2] == ["cargo", "bench"]:
        return argv + ["--no-run"]
    if argv[0].startswith("scripts/") and argv[0].endswith(".sh"):
        return [argv[0], "--help"]
    if argv[:2] == ["python3", "scripts/gen_catalog.py"]:
        return argv  # deterministic: the tree must not change
    if argv[:2] == ["python3", "scripts/check_readme.py"]:
        return argv + ["--list"]
    return None


def main():
    text = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read()
    listing = "--list" in sys.argv[1:]
    failures = []
    before = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True).stdout
    with tempfile.TemporaryDirectory() as scratch:
        for n, cmd in commands(text):
            argv = plan(cmd, scratch)
            if argv is None:
                failures.append(f"README.md:{n}: no rule runs `{cmd}`; add one to scripts/check_readme.py")
                continue
            if listing:
                print(f"README.md:{n}: {cmd}\n    runs: {shlex.join(argv)}")
                continue
            r = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True)
            ok = r.returncode == 0
            print(f"{'ok  ' if ok else 'FAIL'} README.md:{n}: {shlex.join(argv)}")
            if not ok:
                tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-15:])
                failures.append(f"README.md:{n}: `{cmd}` exited {r.returncode}:\n{tail}")
    after = subprocess.run(["git", "status", "--porcelain"], cwd=ROOT, capture_output=True, text=True).stdout
    if not listing and after != before:
        failures.append("running the README's commands changed the checkout:\n" + after)
    if failures:
        print("\n".join(failures), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
