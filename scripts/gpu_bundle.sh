#!/usr/bin/env bash
# Packs a built tree for a GPU machine that cannot install packages (no registry, no Eigen,
# CHOLMOD, GoogleTest or Google Benchmark): the OpenCL test executables with their ctest files,
# stabint_bench and stabint-run, stripped, and every shared library they need except the C
# library's own, into one archive. scripts/gpu_report.sh --bundle FILE unpacks it there in place
# of its deps and build stages.
#
#   scripts/gpu_bundle.sh [--build DIR] [--out FILE]
#
# DIR (default build) must be a Release build with tests, benchmarks and tools; FILE defaults to
# .gpu-bundle/stabint-gpu.tar.gz (ignored by git). The archive records DIR's absolute path, which
# the ctest files name: on the GPU machine gpu_report.sh links that path to the checkout when it
# does not exist there. The libraries come from this machine (Debian 12, glibc 2.36), so the
# other machine needs glibc 2.36 or newer; its OpenCL driver is found by the ICD loader carried
# here (ocl-icd).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
out=.gpu-bundle/stabint-gpu.tar.gz
while [ $# -gt 0 ]; do
  case "$1" in
    --build) shift; build="${1:?--build needs a folder}" ;;
    --out) shift; out="${1:?--out needs a file}" ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "gpu_bundle: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
  shift
done
build_abs="$(cd "$build" && pwd)"
for exe in bench/stabint_bench tools/run/stabint-run; do
  [ -x "$build_abs/$exe" ] || { echo "gpu_bundle: no $build/$exe (configure with benchmarks and tools)" >&2; exit 1; }
done

# Discovered-test lists older than their executables would be discovered again by ctest there,
# with this machine's CMake module path: list the tests here first, which refreshes them.
(cd "$build_abs" && ctest -N >/dev/null)

stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
root="$stage/$(basename "$build_abs")"
mkdir -p "$root/tests" "$root/bench" "$root/tools/run" "$stage/lib"

# The executables with OpenCL tests: test_opencl_* and those that run the backend suite
# (tests/backend_suite.hpp) on OpenCL too.
suites=$(grep -l 'backend_suite.hpp' tests/test_*.cpp | xargs -n1 basename | sed 's/\.cpp$//')
exes=()
for t in $(cd "$build_abs/tests" && ls test_opencl_* 2>/dev/null | grep -v '\.cmake$') $suites; do
  [ -x "$build_abs/tests/$t" ] && exes+=("tests/$t")
done
exes+=(bench/stabint_bench tools/run/stabint-run)
for exe in "${exes[@]}"; do
  strip -o "$root/$exe" "$build_abs/$exe"
  touch -r "$build_abs/$exe" "$root/$exe"
done
# The ctest files, with their times (a discovered-test list newer than its executable is not
# discovered again, which would need the CMake module of this machine's path).
(cd "$build_abs" && find . -name 'CTestTestfile.cmake' -o -name '*_include.cmake' -o -name '*_tests.cmake') |
  while read -r f; do mkdir -p "$root/$(dirname "$f")"; cp -p "$build_abs/$f" "$root/$f"; done

# Shared libraries, less the C library's (the loader, libc, libm, ...), which the other machine has.
for exe in "${exes[@]}"; do ldd "$build_abs/$exe"; done |
  awk '$3 ~ /^\// {print $3}' | sort -u |
  grep -Ev '/(ld-linux[^/]*|libc|libm|libpthread|libdl|librt|libresolv)\.so' |
  while read -r lib; do cp -L "$lib" "$stage/lib/"; done
echo "$build_abs" >"$stage/build_dir.txt"
git rev-parse --short HEAD >"$stage/commit.txt" 2>/dev/null || true

mkdir -p "$(dirname "$out")"
tar -C "$stage" -czf "$out" .
echo "gpu_bundle: $out ($(du -h "$out" | cut -f1)): ${#exes[@]} executables, $(ls "$stage/lib" | wc -l) libraries, from $build_abs"
