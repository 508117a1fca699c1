#!/usr/bin/env bash
# The main job (the README's first command): installs the dependencies, builds rubdyn, checks the
# reference case, writes its Campbell diagram and runs it with the event-driven integrator into
# out/reference/, printing a one-screen summary.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/configure.sh build   # the flags scripts/test.sh uses: one build for both
cmake --build build -j2 --target rubdyn
./build/rubdyn check cases/reference.toml
./build/rubdyn campbell cases/reference.toml --out out/reference
./build/rubdyn run cases/reference.toml --out out/reference
