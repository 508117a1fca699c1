#!/usr/bin/env bash
# Installs every dependency of rubdyn from Debian 12 packages. Idempotent: when everything is
# present it does nothing (no apt-get update, no network). Run as root (or with sudo).
#   scripts/install-deps.sh          what the build, the tests and the figures need
#   scripts/install-deps.sh --peer   also python3-siconos (Siconos 4.4), the external peer of
#                                    validation/siconos/ (not a dependency of rubdyn itself)
set -euo pipefail

# Build and test dependencies (libraries, compiler, build tools) and the figure/validation stack.
packages=(
  g++ cmake make git
  libsundials-dev      # SUNDIALS 6.4.1: CVODE, IDA, dense linear algebra
  libeigen3-dev        # fixed-size linear algebra for the 7-dof model
  libfmt-dev           # formatting
  catch2               # Catch2 v2.13 (tests)
  libtomlplusplus-dev  # TOML parser: line+column of every node and of parse errors; compiled library
  libcli11-dev         # command line
  libbenchmark-dev     # Google Benchmark (bench/)
  python3-matplotlib python3-numpy python3-scipy   # figures and studies in validation/
  pybind11-dev python3-pybind11 python3-dev   # the Python module rubdyn (python/)
  python3-pytest       # its tests (python/tests, run through ctest)
  valgrind             # memcheck tests of the event engine; bench/instructions.py
)

if [ "${1:-}" = "--peer" ]; then
  packages+=(python3-siconos)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
