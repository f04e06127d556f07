#!/usr/bin/env bash
# Builds and tests the Python package: creates .venv (Debian's python3) when missing, installs
# the pinned build and test requirements (python/requirements.txt, from PyPI), installs the
# package from this checkout (`pip install .`, incremental in build/python/) and runs pytest.
# Extra arguments go to pytest. scripts/test.sh runs it after ctest.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -x .venv/bin/python ]; then
  /usr/bin/python3 -m venv .venv
fi
.venv/bin/python -m pip install -q -r python/requirements.txt
# No build isolation: the pinned scikit-build-core and nanobind in .venv keep build/python's
# CMake cache valid between runs, so a rerun only rebuilds what changed.
CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)" .venv/bin/python -m pip install -q --no-build-isolation .
# Run from python/tests so that the installed package is imported, not the source folder.
cd python/tests
../../.venv/bin/python -m pytest -q "$@"
