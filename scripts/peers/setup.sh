#!/bin/sh
# Sets up the optional peers (CGAL, Open3D, PyMeshLab) for external methods and
# experiments/peers.toml: Debian's libraries Open3D needs, then a virtual environment in
# .peers/venv (repository root) with exactly these pinned packages. Idempotent.
#
#   scripts/peers/setup.sh
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
venv="$root/.peers/venv"
if command -v apt-get >/dev/null 2>&1; then
    missing=""
    for p in libusb-1.0-0 libgl1 libgomp1 libegl1 python3-venv; do
        dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
    done
    if [ -n "$missing" ]; then
        sudo=""
        [ "$(id -u)" -ne 0 ] && sudo="sudo"
        $sudo apt-get update -qq
        # shellcheck disable=SC2086
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing
    fi
fi
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q -r "$root/scripts/peers/requirements.txt"
"$venv/bin/python" "$root/scripts/peers/peer.py" check
