#!/usr/bin/env bash
# Builds rubdyn and runs the fast test suite (the README's test command; .ci/run calls it).
#   scripts/test.sh              Release build in build/, all default tests through ctest
#   scripts/test.sh --sanitize   the same with AddressSanitizer + UndefinedBehaviorSanitizer,
#                                in build-asan/
# Installs missing Debian packages first (scripts/install-deps.sh; needs root when it must).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build
flags=()  # scripts/configure.sh's Release flags, the ones scripts/run-reference.sh builds with
if [ "${1:-}" = "--sanitize" ]; then
  build=build-asan
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DRUBDYN_SANITIZE=ON)
fi

bash scripts/install-deps.sh
bash scripts/configure.sh "$build" "${flags[@]}"
cmake --build "$build" -j2
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" --output-on-failure -j2
