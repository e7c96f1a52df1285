#!/usr/bin/env bash
# Installs what seamvox needs from Debian 12 packages (when missing), then configures and builds
# a Release build in ./build. As root it runs apt-get itself; otherwise it prints the exact
# apt-get line and stops.
set -euo pipefail
cd "$(dirname "$0")/.."

# libopenblas0-pthread is not linked directly: it replaces Debian's reference BLAS/LAPACK behind
# CHOLMOD's supernodal factorization (about 2x faster factorizations measured here).
# pybind11-dev, python3-dev, python3-numpy: the Python module (tools/python); python3-pytest runs
# its tests (tests/python) under ctest.
packages=(cmake make g++ libopenvdb-dev libboost-iostreams-dev zlib1g-dev libtbb-dev
  libeigen3-dev libsuitesparse-dev libdraco-dev libgtest-dev libopenblas0-pthread
  libopenmpi-dev openmpi-bin pybind11-dev python3-dev python3-numpy python3-pytest)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  line="apt-get install -y --no-install-recommends ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "seamvox setup: missing Debian packages. Run as root:" >&2
    echo "  apt-get update && $line" >&2
    exit 1
  fi
  echo "seamvox setup: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $line || { apt-get update && $line; }
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$jobs"
