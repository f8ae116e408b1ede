#!/usr/bin/env bash
# Installs everything hairdyn needs on a fresh Debian 12 machine; quick when all is present.
#   Debian packages (apt-get): Blender 3.4, the C++ toolchain and libraries, Xvfb, ...
#   .venv (pip, pinned in scripts/requirements-bpy.txt): the newest bpy wheel that installs
#   for this machine's CPython 3.11, with numpy and pytest.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

APT_PACKAGES=(
  blender cmake g++ make pkg-config
  libglm-dev libopenmesh-dev libeigen3-dev pybind11-dev
  python3-dev python3-venv python3-numpy python3-pytest
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth
)

missing=()
for package in "${APT_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing Debian packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO=sudo; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# The bpy wheel is built for CPython 3.11; Debian 12's python3 is 3.11, the same ABI the
# native module is built for (one module serves the blender binary and the bpy wheel).
VENV="$ROOT/.venv"
REQUIREMENTS="$ROOT/scripts/requirements-bpy.txt"
STAMP="$VENV/.hairdyn-requirements"
if [ ! -x "$VENV/bin/python" ] || ! cmp -s "$REQUIREMENTS" "$STAMP"; then
  echo "setup: creating $VENV with $(tr '\n' ' ' < "$REQUIREMENTS")"
  rm -rf "$VENV"
  /usr/bin/python3.11 -m venv "$VENV"
  if ! "$VENV/bin/python" -m pip install --disable-pip-version-check -r "$REQUIREMENTS" \
      >"$VENV/pip.log" 2>&1; then
    cat "$VENV/pip.log"
    echo "setup: pip could not install $REQUIREMENTS (log above)" >&2
    exit 1
  fi
  cp "$REQUIREMENTS" "$STAMP"
fi
