#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (clang, build-asan/,
# RelWithDebInfo; the benchmark suite is not built). clang, not gcc: it can leave Eigen's headers
# out of UBSan (cmake/sanitizer_ignore.txt), which keeps the suite about as fast as ASan alone. Every sanitizer report is written to a file
# under build-asan/sanitizer-reports/ instead of being lost in a test's output, and any report
# fails the run, also when the test that triggered it passed (UBSan keeps running after a report,
# and so do tests that only check an exit status). Leaks count too, except inside the OpenCL
# driver stack (scripts/lsan.supp). Extra arguments go to ctest (e.g. -L cpu).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
build=build-asan
# A build directory configured with another compiler cannot be switched in place.
if [ -f "$build/CMakeCache.txt" ] && ! grep -q "^CMAKE_CXX_COMPILER:.*clang++" "$build/CMakeCache.txt"; then
  rm -rf "$build"
fi
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSTABINT_SANITIZE=address,undefined -DSTABINT_WERROR=ON \
  -DSTABINT_BUILD_BENCHMARKS=OFF
cmake --build "$build" -j"$(nproc)"

reports="$PWD/$build/sanitizer-reports"
rm -rf "$reports"
mkdir -p "$reports"
# log_path: one file per process that reported, <prefix>.<pid>. Child processes (the consumer
# example, stabint-run in the smoke tests) inherit the settings.
# use_sigaltstack=0 and use_tls=0: on some kernels the sanitizer runtime itself fails with PoCL's
# threads (it cannot unmap a thread's alternate signal stack, and LeakSanitizer's tracer crashes
# on the dynamic TLS of the libraries PoCL loads), failing OpenCL tests that have no defect.
# Neither weakens a check: without TLS as roots LeakSanitizer can only report more, not less.
export ASAN_OPTIONS="log_path=$reports/asan:detect_leaks=1:use_sigaltstack=0:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="log_path=$reports/ubsan:print_stacktrace=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="use_tls=0:suppressions=$PWD/scripts/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"

status=0
(cd "$build" && ctest --output-on-failure -j"$(nproc)" "$@") || status=$?

shopt -s nullglob
found=("$reports"/*)
if [ ${#found[@]} -gt 0 ]; then
  for f in "${found[@]}"; do
    echo "=== $f"
    cat "$f"
  done
  echo "sanitize: ${#found[@]} sanitizer report file(s) in $reports" >&2
  exit 1
fi
[ "$status" -eq 0 ] && echo "sanitize: no sanitizer reports, all tests passed"
exit "$status"
