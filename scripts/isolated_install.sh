#!/usr/bin/env bash
# The install a new user runs: `pip install .` with build isolation (pip's default: the build
# requirements of pyproject.toml in a temporary environment of their own) into a throwaway virtual
# environment, then `import stabint` and steps of a cloth from outside the checkout. CI runs it
# (.ci/run); scripts/python.sh is the developers' incremental path (--no-build-isolation).
#   --extras   installs `.[distributed,io]` instead and imports stabint.distributed and stabint.io
#
# What a rebuild reuses: pip builds every isolated install in a new temporary environment, and
# scikit-build-core clears the CMake cache and CMakeFiles/ (where the objects are) of its build
# folder whenever that environment changes, so no build folder carries objects from one isolated
# build to the next. The compiler's output is reused instead, through ccache (install-deps.sh
# installs it; without it every build compiles everything): the build folder is fixed,
# build/python-isolated/<wheel tag> (not scripts/python.sh's build/python/, whose cache the
# isolated builds would clear), and CCACHE_BASEDIR makes the paths inside the checkout relative, so
# the compile commands repeat and a rebuild compiles only the files that include nanobind (from
# the temporary environment's path).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"

target=.
case "${1:-}" in
  --extras) target=".[distributed,io]" ;;
  "") ;;
  *) echo "isolated_install: unknown option $1 (--extras)" >&2; exit 2 ;;
esac

work="$(mktemp -d "${TMPDIR:-/tmp}/stabint-isolated.XXXXXX")"
trap 'rm -rf "$work"' EXIT
# Debian's python3, as scripts/python.sh's .venv.
/usr/bin/python3 -m venv "$work/venv"

export SKBUILD_BUILD_DIR="$root/build/python-isolated/{wheel_tag}"
CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)"
export CMAKE_BUILD_PARALLEL_LEVEL
if command -v ccache >/dev/null 2>&1; then
  export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache CCACHE_BASEDIR="$root"
fi

start=$(date +%s)
"$work/venv/bin/pip" install -q "$target"
echo "isolated_install: pip install $target took $(($(date +%s) - start)) s"

# From the temporary folder: the installed package is imported, not python/stabint.
cd "$work"
STABINT_EXTRAS="$([ "$target" = . ] && echo 0 || echo 1)" "$work/venv/bin/python" - <<'EOF'
import os
import sys

import numpy as np

import stabint

assert stabint.__file__.startswith(sys.prefix), f"imported {stabint.__file__}, not the venv's package"
sim = stabint.Simulator(stabint.cloth_grid(nx=8, ny=8, pinned=[0]), stabint.SimulatorOptions())
x0 = sim.positions
for _ in range(10):
    report = sim.step()
x = sim.positions
# Ten steps of 1/30 s under gravity: the free corner falls, and nothing is lost.
assert np.isfinite(x).all() and x[-1, 1] < x0[-1, 1] - 1e-3, (x0[-1], x[-1])
assert report.step == 9 and np.isfinite(report.energy.total)
if os.environ["STABINT_EXTRAS"] == "1":
    import stabint.distributed  # noqa: F401
    import stabint.io  # noqa: F401
print(f"isolated_install: stabint imported from {os.path.dirname(stabint.__file__)} and stepped")
EOF
