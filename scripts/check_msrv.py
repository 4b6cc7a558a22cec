#!/usr/bin/env python3
"""Checks that the workspace's rust-version is true.

Every workspace member must inherit the workspace's rust-version, and no locked
dependency built for this host may declare a newer one. Run from the repository root;
exits 1 naming what is wrong. Uses only `cargo metadata --locked --offline` when the
dependencies are already fetched (CI fetches them in its first cargo call).
"""

import json
import subprocess
import sys


def version(text):
    parts = [int(x) for x in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def main():
    host = subprocess.run(
        ["rustc", "-vV"], check=True, capture_output=True, text=True
    ).stdout
    host = next(l.split(": ", 1)[1] for l in host.splitlines() if l.startswith("host: "))
    meta = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--locked", "--filter-platform", host],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    members = set(meta["workspace_members"])
    used = {n["id"] for n in meta["resolve"]["nodes"]}
    problems = []
    declared = set()
    for p in meta["packages"]:
        if p["id"] in members:
            if not p.get("rust_version"):
                problems.append(f"{p['name']}: no rust-version (add rust-version.workspace = true)")
            else:
                declared.add(p["rust_version"])
    if len(declared) > 1:
        problems.append(f"workspace members disagree on rust-version: {sorted(declared)}")
    ours = max(declared, key=version) if declared else "0"
    for p in meta["packages"]:
        rv = p.get("rust_version")
        if p["id"] in members or p["id"] not in used or not rv:
            continue
        if version(rv) > version(ours):
            problems.append(
                f"locked dependency {p['name']} {p['version']} needs Rust {rv}, "
                f"above the workspace's rust-version {ours}"
            )
    if problems:
        print("rust-version check failed:", *problems, sep="\n  ")
        return 1
    print(f"rust-version {ours}: every member inherits it, no locked dependency needs more")
    return 0


if __name__ == "__main__":
    sys.exit(main())
