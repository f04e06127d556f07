#!/usr/bin/env bash
# The README's test command: installs missing dependencies, configures and builds (Release) into
# build/, and runs the whole test suite: ctest (extra arguments go to it, e.g. -L cpu, -R Oscillator),
# then the Python package's build and pytest suite (scripts/python.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSTABINT_WERROR=ON
cmake --build build -j"$(nproc)"
(cd build && ctest --output-on-failure -j"$(nproc)" "$@")
# The Python package (.venv, build/python) and its pytest suite, after the C++ suite.
bash scripts/python.sh
