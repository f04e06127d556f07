#!/usr/bin/env bash
# Fuzzes the four loaders and the two checkpoint readers (a Simulator's, a batch's) with libFuzzer: builds the harnesses of fuzz/ with clang into
# build-fuzz/ (library instrumented with ASan + UBSan + coverage) and runs each for SECONDS
# (default 60), starting from the seed corpus fuzz/corpus/<harness>/. New inputs go to
# build-fuzz/corpus/<harness>/, never into the repository; a crash, sanitizer report, hang
# (-timeout) or runaway memory (-rss_limit_mb) leaves its input in build-fuzz/artifacts/<harness>/
# and fails the run.
#   bash scripts/fuzz.sh                 # 60 s per harness
#   bash scripts/fuzz.sh 3600 json       # one hour of the JSON harness only
# Reproduce a finding: build-fuzz/fuzz/fuzz_<harness> build-fuzz/artifacts/<harness>/crash-...
set -euo pipefail
cd "$(dirname "$0")/.."

seconds="${1:-60}"
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(obj tetgen medit json checkpoint batch_checkpoint)

bash scripts/install-deps.sh
build=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DSTABINT_SANITIZE=address,undefined,fuzzer-no-link -DSTABINT_BUILD_FUZZERS=ON \
  -DSTABINT_BUILD_TESTS=OFF -DSTABINT_BUILD_TOOLS=OFF -DSTABINT_BUILD_BENCHMARKS=OFF
targets=()
for h in "${harnesses[@]}"; do targets+=(--target "fuzz_$h"); done
cmake --build "$build" -j"$(nproc)" "${targets[@]}"

# UBSan stops at its first report, so that libFuzzer sees it as a crash and keeps the input.
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:${UBSAN_OPTIONS:-}"
export ASAN_OPTIONS="detect_leaks=1:${ASAN_OPTIONS:-}"
failed=()
for h in "${harnesses[@]}"; do
  corpus="$build/corpus/$h"
  artifacts="$build/artifacts/$h"
  mkdir -p "$corpus" "$artifacts"
  dict=()
  [ -f "fuzz/$h.dict" ] && dict=(-dict="fuzz/$h.dict")
  echo "fuzz: $h for ${seconds} s"
  # -max_len: large enough for the seeds and for long lines and big counts; -rss_limit_mb: the
  # loaders must not need more than this for such inputs.
  if ! "$build/fuzz/fuzz_$h" "$corpus" "fuzz/corpus/$h" "${dict[@]}" -max_total_time="$seconds" \
      -timeout=20 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1 \
      -artifact_prefix="$artifacts/" > "$build/fuzz_$h.log" 2>&1; then
    tail -n 60 "$build/fuzz_$h.log"
    failed+=("$h")
  else
    grep -E "^stat::number_of_executed_units|^stat::new_units_added" "$build/fuzz_$h.log" | sed "s/^/fuzz: $h: /"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in: ${failed[*]} (inputs under $build/artifacts/)" >&2
  exit 1
fi
echo "fuzz: no findings (${harnesses[*]}, ${seconds} s each)"
