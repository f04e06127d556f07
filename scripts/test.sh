#!/usr/bin/env bash
# The README's test command: installs missing dependencies, configures and builds (Release) into
# build/, and runs the whole test suite. Extra arguments go to ctest (e.g. -L cpu, -R Oscillator).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
cd build
ctest --output-on-failure -j"$(nproc)" "$@"
