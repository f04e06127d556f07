#!/usr/bin/env bash
# Builds stabint_bench (Release), runs it and draws the charts.
#
#   scripts/bench.sh [--quick] [--no-build] [--repetitions N] [FILTER] [-- EXTRA_BENCHMARK_FLAGS...]
#
# FILTER is a Google Benchmark regex (--benchmark_filter), e.g. '^iteration/' or 'cloth50x50'.
# --quick (or STABINT_BENCH_QUICK=1) runs every case for 0.02 s instead of 0.1 s and the cloth
# scaling family only up to 71x71. --repetitions N repeats every case N times (the summary uses
# the fastest repetition): use it for the goal checks on a shared machine.
# Output: results/bench.json, results/charts/scaling.{png,svg}, results/bench_summary.md.
# Environment: STABINT_BENCH_BUILD_DIR (default build-bench), JOBS (default 2),
# STABINT_SKIP_DEPS=1 to skip scripts/install-deps.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

quick="${STABINT_BENCH_QUICK:-0}"
build=1
repetitions=1
filter=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --no-build) build=0 ;;
    --repetitions) shift; repetitions="${1:?--repetitions needs a count}" ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    --) shift; extra=("$@"); break ;;
    -*) echo "bench.sh: unknown option $1" >&2; exit 2 ;;
    *) filter="$1" ;;
  esac
  shift
done

build_dir="${STABINT_BENCH_BUILD_DIR:-build-bench}"
if [ "$build" = 1 ]; then
  if [ "${STABINT_SKIP_DEPS:-0}" != 1 ] && [ -x scripts/install-deps.sh ]; then
    scripts/install-deps.sh
  fi
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSTABINT_BUILD_BENCHMARKS=ON \
        -DSTABINT_BUILD_TOOLS=OFF >/dev/null
  cmake --build "$build_dir" --target stabint_bench -j "${JOBS:-2}"
fi

mkdir -p results/charts
args=(--benchmark_out=results/bench.json --benchmark_out_format=json)
[ -n "$filter" ] && args+=("--benchmark_filter=$filter")
if [ "$repetitions" -gt 1 ]; then
  args+=("--benchmark_repetitions=$repetitions" --benchmark_display_aggregates_only=true)
fi
STABINT_BENCH_QUICK="$quick" "$build_dir/bench/stabint_bench" "${args[@]}" "${extra[@]}"

/usr/bin/python3 bench/scaling_chart.py results/bench.json --charts results/charts \
  --summary results/bench_summary.md
