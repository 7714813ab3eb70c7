#!/usr/bin/env bash
# One-time (and idempotent) set-up of a fresh Debian machine for maizeviz:
# system libraries for Qt/VTK and the virtual screen, then a venv in .venv with maizeviz and
# its test tools. Safe to run again: it installs only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

apt_pkgs=(python3 python3-venv python3-pip xvfb xauth libgl1 libegl1 libglx-mesa0 libxrender1
          libxkbcommon-x11-0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0
          libxcb-xinerama0 libxcb-randr0 libxcb-shape0 libxcb-xkb1 libxcb-cursor0 libdbus-1-3
          libfontconfig1 gcc libc6-dev python3-dev)
missing=()
if command -v dpkg >/dev/null 2>&1; then
  for p in "${apt_pkgs[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
  done
fi
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "setup: installing ${missing[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "setup: warning: missing system packages (${missing[*]}); install them as root" >&2
  fi
fi

PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip >/dev/null
.venv/bin/python -m pip install -q -e ".[gui,sweep,test]"
# the install above built Embree's ray-packet kernel (maizeviz/mesh/_packets.c, setup.py);
# without a C compiler maizeviz traces with embreex's single rays (the same hits, slower)
.venv/bin/maizeviz --info | grep "^ray kernel" | sed 's/^/setup: /' >&2
echo "setup: ready (.venv/bin/maizeviz)" >&2
