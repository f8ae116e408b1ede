#!/usr/bin/env bash
# Installs everything hairdyn needs on a fresh Debian 12 machine; quick when all is present.
#   Debian packages (apt-get): Blender 3.4, the C++ toolchain and libraries, Xvfb, ...
#   .venv (pip, pinned in scripts/requirements-bpy.txt): the newest bpy wheel that installs
#   for this machine's CPython 3.11, with numpy, pytest and ruff (the style check).
#   .venv313 (pip, pinned in scripts/requirements-bpy313.txt), only where a CPython 3.13 exists
#   (on PATH or under pyenv): bpy 5.3 (Blender 5.1 and later run Python 3.13), numpy, pytest, the
#   pybind11 the 3.13 module is built with, and Dask for `cli.py wedge`.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

APT_PACKAGES=(
  blender cmake g++ make pkg-config
  libglm-dev libopenmesh-dev libeigen3-dev pybind11-dev
  python3-dev python3-venv python3-numpy python3-pytest
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-distributed python3-openvdb
  clang-format
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

# make_venv NAME PYTHON REQUIREMENTS: a venv with the pinned packages, remade when they change.
make_venv() {
  local venv="$ROOT/$1" python=$2 requirements="$ROOT/scripts/$3"
  local stamp="$venv/.hairdyn-requirements"
  if [ -x "$venv/bin/python" ] && cmp -s "$requirements" "$stamp"; then
    return
  fi
  echo "setup: creating $venv with $(tr '\n' ' ' < "$requirements")"
  rm -rf "$venv"
  "$python" -m venv "$venv"
  if ! "$venv/bin/python" -m pip install --disable-pip-version-check -r "$requirements" \
      >"$venv/pip.log" 2>&1; then
    cat "$venv/pip.log"
    echo "setup: pip could not install $requirements (log above)" >&2
    exit 1
  fi
  cp "$requirements" "$stamp"
}

# The bpy wheel is built for CPython 3.11; Debian 12's python3 is 3.11, the same ABI the
# native module is built for (one module serves the blender binary and the bpy wheel).
make_venv .venv /usr/bin/python3.11 requirements-bpy.txt

# Blender 5.1 and later run CPython 3.13; Debian 12 has none, pyenv may. CMake builds a second
# module for it from .venv313's interpreter (which carries the pybind11 it needs).
# (pyenv's shim on PATH fails unless 3.13 is selected, so each candidate is tried.)
python313=""
for candidate in $(command -v python3.13 || true) \
    $(ls -d "$HOME"/.pyenv/versions/3.13*/bin/python3.13 2>/dev/null | sort -rV); do
  if "$candidate" -c "import venv, sysconfig, os; \
      assert os.path.isfile(os.path.join(sysconfig.get_paths()['include'], 'Python.h'))" \
      >/dev/null 2>&1; then
    python313=$candidate
    break
  fi
done
if [ -n "$python313" ]; then
  make_venv .venv313 "$python313" requirements-bpy313.txt
else
  echo "setup: no CPython 3.13 with headers (python3.13 on PATH or under ~/.pyenv/versions):" \
       "skipping .venv313, so no native module for Blender 5.1+ and no bpy 5.3 test suite"
fi
