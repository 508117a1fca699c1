#!/usr/bin/env bash
# Configures a build folder with the one set of flags that the README's two commands share
# (scripts/run-reference.sh, scripts/test.sh): the second builds only what the first did not
# (the tests, the Python module), instead of rebuilding everything with other flags.
#   scripts/configure.sh [BUILD_DIR] [extra cmake arguments...]   (default BUILD_DIR: build)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build}
shift || true
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DRUBDYN_TEST_ONLY= -DRUBDYN_WARNINGS_AS_ERRORS=ON \
  "$@" > /dev/null
