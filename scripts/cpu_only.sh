#!/usr/bin/env bash
# The CPU-reference-only build (-DSTABINT_WITH_OPENCL=OFF, into build-cpu-only/): builds the
# library, stabint-run and a few CPU test programs without the OpenCL headers or ICD loader,
# checks that the library references no OpenCL symbol, and runs those programs. CI runs it.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build=build-cpu-only
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DSTABINT_WITH_OPENCL=OFF -DSTABINT_BUILD_BENCHMARKS=OFF -DSTABINT_WERROR=ON
cmake --build "$build" -j"$(nproc)" --target stabint stabint-run test_interaction test_oscillator test_c_api

if nm "$build/libstabint.a" | grep -q " U cl[A-Z]"; then
  echo "cpu_only: libstabint.a references OpenCL symbols" >&2
  exit 1
fi
"$build/tests/test_interaction"
"$build/tests/test_oscillator"
"$build/tests/test_c_api" scenes
"$build/tools/run/stabint-run" --scene cloth --frames 10 --quiet
if "$build/tools/run/stabint-run" --scene cloth --frames 1 --backend opencl --quiet 2>/dev/null; then
  echo "cpu_only: --backend opencl should fail without OpenCL" >&2
  exit 1
fi
echo "cpu_only: the CPU-only build works"
