#!/usr/bin/env bash
# Builds rubdyn and runs the fast test suite (the README's test command; .ci/run calls it).
#   scripts/test.sh              Release build in build/, all default tests through ctest
#   scripts/test.sh --sanitize   the same with AddressSanitizer + UndefinedBehaviorSanitizer,
#                                in build-asan/
# Installs missing Debian packages first (scripts/install-deps.sh; needs root when it must).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build
flags=(-DCMAKE_BUILD_TYPE=Release)
if [ "${1:-}" = "--sanitize" ]; then
  build=build-asan
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DRUBDYN_SANITIZE=ON)
fi

bash scripts/install-deps.sh
cmake -S . -B "$build" "${flags[@]}" -DRUBDYN_TEST_ONLY= -DRUBDYN_WARNINGS_AS_ERRORS=ON > /dev/null
cmake --build "$build" -j2
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" --output-on-failure -j2
