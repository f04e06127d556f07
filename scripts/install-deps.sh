#!/usr/bin/env bash
# Installs the Debian 12 packages stabint needs, but only those that are missing.
# Idempotent: a second run installs nothing. Nothing is downloaded at build or run time;
# this script is the only place packages come from (Debian's own archive via apt).
#   --build-only   only what the library, its tests and benchmarks need to build and run
#                  (scripts/gpu_report.sh on a bare machine: no charts, renderers, sanitizers)
set -euo pipefail

build_packages=(
  build-essential cmake pkg-config
  libeigen3-dev          # dense/sparse linear algebra, Eigen/CholmodSupport
  libsuitesparse-dev     # CHOLMOD: the prefactored global system
  ocl-icd-opencl-dev     # OpenCL ICD loader (libOpenCL.so) and C headers
  opencl-clhpp-headers   # CL/opencl.hpp C++ bindings
  pocl-opencl-icd        # CPU OpenCL device, so the OpenCL path runs without a GPU
  clinfo
  libgtest-dev libgmock-dev
  libbenchmark-dev
  nlohmann-json3-dev     # scene files
  libcgal-dev            # exact triangle-triangle tests of self-contact (tests/triangle_intersections.cpp)
  libgmp-dev libmpfr-dev # CGAL's CMake config requires both (libcgal-dev depends on them anyway)
  python3                # the reports of scripts/bench.sh and scripts/gpu_report.sh
)
packages=(
  "${build_packages[@]}"
  python3-matplotlib     # charts (used through /usr/bin/python3)
  python3-pil            # the teaser's and the drop's GIFs
  povray                 # renders the teaser and the soft-body drop (CPU ray tracer, headless)
  tetgen                 # meshes the main job's soft body (scripts/soft_body_mesh.sh)
  libcgal-demo           # ships the surface it meshes: CGAL's data/meshes/elephant.off (CC0)
  python3-venv python3-dev  # the Python package: .venv and the extension's headers (scripts/python.sh)
  ccache                 # the compiler cache of isolated `pip install .` builds (scripts/isolated_install.sh)
  clang libclang-rt-14-dev  # sanitizer build and libFuzzer harnesses (scripts/sanitize.sh, fuzz.sh)
  clang-format           # the tree's style (.clang-format, scripts/format.sh; checked in CI)
  doxygen                # the API reference of include/stabint/ (scripts/apidocs.sh; checked in CI)
)

case "${1:-}" in
  --build-only) packages=("${build_packages[@]}") ;;
  "") ;;
  *) echo "install-deps: unknown option $1 (--build-only)" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi

echo "install-deps: missing: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO=sudo
  else
    echo "install-deps: not root and no password-less sudo. Run as root:" >&2
    echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
  fi
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: done"
