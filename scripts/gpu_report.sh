#!/usr/bin/env bash
# The GPU measurement in one go, for a machine lent for 30 minutes (10 per command): installs
# what is missing, finds the GPU's OpenCL platform, builds, runs the OpenCL tests on the GPU and
# the GPU benchmark set, and writes JSON and a short markdown report.
#
#   scripts/gpu_report.sh [--quick] [--out DIR] [--device P:D] [STAGE...]
#
# STAGEs, in this order by default (all of them): deps build test bench report. `bench` is
# bench-frame bench-cg bench-scaling bench-auto bench-blend bench-solver bench-batch bench-rows
# (most wanted first;
# bench-rows times a few OpenCL cases with each row of launch sizes of host/backend/device_profiles.cpp,
# STABINT_OPENCL_PROFILE, to tune the device's row); each can be given
# alone, so that every command stays under a lending's 10 minutes (a benchmark stage stops after
# STABINT_BENCH_TIMEOUT, 200 s), e.g. four commands on the lent machine:
#   scripts/gpu_report.sh deps build test;        cp -r results/gpu "$OUT/"
#   scripts/gpu_report.sh bench-frame bench-cg;   cp -r results/gpu "$OUT/"
#   scripts/gpu_report.sh bench-scaling bench-auto; cp -r results/gpu "$OUT/"
#   scripts/gpu_report.sh bench-batch bench-rows report; cp -r results/gpu "$OUT/"
# Every stage writes under DIR (default results/gpu, ignored by git, so it stays between the
# commands); `report` summarises whatever is there.
#   --quick      the check of the script (a few minutes on PoCL): the benchmarks' quick mode
#                (STABINT_BENCH_QUICK=1: 0.02 s per case, the scaling families to 71 x 71, the
#                16k cloth 5 steps), a few batch cases, four groups of OpenCL tests
#   --bundle F   use the archive of scripts/gpu_bundle.sh (built on a machine with the packages)
#                instead of the deps and build stages, for a GPU machine that cannot install them
#   --device P:D the OpenCL platform and device (indices or name substrings, as
#                STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE). Default: the first GPU that
#                stabint-run --list-devices shows, else its first device (PoCL on a machine
#                without GPU), so the script runs the same here and there.
# Environment: STABINT_GPU_BUILD_DIR (default build-gpu), JOBS (default: the cores),
# STABINT_BENCH_TIMEOUT (seconds per benchmark stage, default 200; the JSON of a stage cut short
# keeps its finished cases).
# Outputs: devices.txt, clinfo.txt, nvidia-smi.txt, build.log, ctest.log, ctest-junit.xml,
# bench-<stage>.json and bench-rows-<row>.json (Google Benchmark; .txt: its console output),
# report.md (docs/benchmarks.md, "GPU report").
set -euo pipefail
cd "$(dirname "$0")/.."

quick=0
out=results/gpu
device=""
bundle=""
stages=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --out) shift; out="${1:?--out needs a folder}" ;;
    --device) shift; device="${1:?--device needs PLATFORM:DEVICE}" ;;
    --bundle) shift; bundle="${1:?--bundle needs the archive of scripts/gpu_bundle.sh}" ;;
    -h|--help) sed -n '2,36p' "$0"; exit 0 ;;
    deps|build|test|bench|bench-frame|bench-cg|bench-scaling|bench-batch|bench-auto|bench-blend|bench-solver|bench-rows|report) stages+=("$1") ;;
    *) echo "gpu_report: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
  shift
done
[ ${#stages[@]} -eq 0 ] && stages=(deps build test bench report)
expanded=()
for s in "${stages[@]}"; do
  if [ "$s" = bench ]; then
    expanded+=(bench-frame bench-cg bench-scaling bench-auto bench-blend bench-solver bench-batch bench-rows)
  else
    expanded+=("$s")
  fi
done
stages=("${expanded[@]}")

build_dir="${STABINT_GPU_BUILD_DIR:-build-gpu}"
jobs="${JOBS:-$(nproc)}"
bench_timeout="${STABINT_BENCH_TIMEOUT:-200}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
log() { echo "gpu_report: $*" >&2; }

# --- the NVIDIA OpenCL ICD ----------------------------------------------------------------------
# A driver installed without its ICD file (common in containers, which mount the driver's
# libraries but not /etc/OpenCL/vendors/nvidia.icd) is invisible to the ICD loader: then a private
# vendors folder with the system's ICD files and one for libnvidia-opencl.so.1 is used
# (OCL_ICD_VENDORS, ocl-icd's override). Debian's package is nvidia-opencl-icd (non-free), which
# must match the driver's version; it is not installed here.
nvidiaIcd() {
  command -v nvidia-smi >/dev/null 2>&1 || return 0
  nvidia-smi >"$out/nvidia-smi.txt" 2>&1 || true
  if grep -qsi nvidia /etc/OpenCL/vendors/*.icd 2>/dev/null; then return 0; fi
  local lib
  lib="$( (ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ {print $NF; exit}') || true)"
  [ -z "$lib" ] && lib="$(find /usr/lib /usr/lib64 /usr/local/nvidia /usr/lib/x86_64-linux-gnu -name 'libnvidia-opencl.so.1' 2>/dev/null | head -1 || true)"
  if [ -z "$lib" ]; then
    log "an NVIDIA driver is present but not its OpenCL library (libnvidia-opencl.so.1): install the driver's OpenCL part (Debian: nvidia-opencl-icd of the driver's version)"
    return 0
  fi
  mkdir -p "$out/icd"
  cp /etc/OpenCL/vendors/*.icd "$out/icd/" 2>/dev/null || true
  echo "$lib" >"$out/icd/nvidia.icd"
  export OCL_ICD_VENDORS="$out/icd"
  log "NVIDIA ICD file missing: using $out/icd (OCL_ICD_VENDORS) with $lib"
}

# --- the device ---------------------------------------------------------------------------------
# Sets STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE (read by the tests' and benchmarks'
# backends) and writes devices.txt and device.txt.
selectDevice() {
  local run="$build_dir/tools/run/stabint-run"
  [ -x "$run" ] || { log "no $run: run the build stage first"; exit 1; }
  "$run" --list-devices >"$out/devices.txt"
  command -v clinfo >/dev/null 2>&1 && clinfo >"$out/clinfo.txt" 2>&1 || true
  local line
  if [ -n "$device" ]; then
    export STABINT_OPENCL_PLATFORM="${device%%:*}" STABINT_OPENCL_DEVICE="${device#*:}"
    line="given with --device $device"
  else
    line="$(grep -m1 'gpu: yes' "$out/devices.txt" || grep -m1 '^platform ' "$out/devices.txt" || true)"
    if [ -z "$line" ]; then
      log "no OpenCL device (devices.txt); the OpenCL tests and cases would be skipped"
      cat "$out/devices.txt" >&2
      exit 1
    fi
    export STABINT_OPENCL_PLATFORM="$(sed -E 's/^platform ([0-9]+) device ([0-9]+):.*/\1/' <<<"$line")"
    export STABINT_OPENCL_DEVICE="$(sed -E 's/^platform ([0-9]+) device ([0-9]+):.*/\2/' <<<"$line")"
  fi
  [ -n "$device" ] || grep -q 'gpu: yes' <<<"$line" || log "no GPU found: measuring $line"
  echo "$line" >"$out/device.txt"
  echo "STABINT_OPENCL_PLATFORM=$STABINT_OPENCL_PLATFORM STABINT_OPENCL_DEVICE=$STABINT_OPENCL_DEVICE" >>"$out/device.txt"
}

# --- the benchmark sets -------------------------------------------------------------------------
# Regexes over stabint_bench's cases (--benchmark_list_tests); every set has the CPU reference's
# cases beside the OpenCL ones, so that the report compares them on the same machine.
benchFilter() {
  case "$1" in
    # The tet bar's frame (30 steps) and the 128 x 128 Chebyshev cloth (16,384 particles).
    bench-frame) echo '^frame/' ;;
    # The device CG against the host factor, per BE iteration, and on the growing tet bars.
    bench-cg) echo '^global_step(_scaling)?/' ;;
    # Cloth 10 x 10 to 224 x 224: where a GPU overtakes the CPU (Auto's threshold).
    bench-scaling) echo '^scaling_(iteration|step)/' ;;
    # The blend's cost over BE per step (speed issue: at most 1.10 on every backend).
    bench-blend) echo '^blend_vs_be/' ;;
    # L-BFGS's and plain PD's time per iteration (convergence issue: at most 1.2x on every backend).
    bench-solver) echo '^convergence/(peercloth50|tetbar50x10x10)/(plain|lbfgs)/(10|20)/' ;;
    # Many scenes at once against one simulator per scene.
    bench-batch)
      if [ "$quick" = 1 ]; then echo '^batch/cloth10/BE/[^/]+/(batch|separate)/scenes:100/'; else echo '^batch/'; fi ;;
    # One BE iteration on spring and triangle cloths and tet bars: Auto's rule per element type.
    bench-auto) echo '^auto_iteration/' ;;
    # Per row of launch sizes: an element pass-bound iteration, the device CG and the 16k frame.
    bench-rows) echo '^(iteration/tetbar50x10x10/BE|global_step/tetbar50x10x10/cg10|frame/cloth128x128/BE-chebyshev-cg10)/opencl-' ;;
  esac
}

# runBench STAGE [NAME]: the stage's cases into NAME.json and NAME.txt (NAME: the stage).
runBench() {
  local stage="$1" name="${2:-$1}"
  local json="$out/$name.json"
  local bench="$build_dir/bench/stabint_bench"
  [ -x "$bench" ] || { log "no $bench: run the build stage first"; exit 1; }
  log "$name: $(benchFilter "$stage") (at most ${bench_timeout}s)"
  local status=0
  STABINT_BENCH_QUICK="$quick" timeout "$bench_timeout" "$bench" --benchmark_filter="$(benchFilter "$stage")" \
    --benchmark_out="$json" --benchmark_out_format=json >"$out/$name.txt" 2>&1 || status=$?
  [ "$status" = 124 ] && log "$name: cut short after ${bench_timeout}s (the finished cases are kept)"
  [ "$status" != 0 ] && [ "$status" != 124 ] && log "$name: stabint_bench exited with $status ($out/$name.txt)"
  return 0
}

# --- a prebuilt bundle (scripts/gpu_bundle.sh) ----------------------------------------------------
# Unpacks the build at the absolute path its ctest files name: where that path's folder does not
# exist (a lent machine), it becomes a link to this checkout, whose sources the tests read.
# Libraries the system has are taken from the system (its C++ runtime may be newer than the
# carried one, and its OpenCL driver may need that).
unbundle() {
  local tmp
  tmp="$(mktemp -d)"
  tar -C "$tmp" -xzf "$bundle"
  local path
  path="$(cat "$tmp/build_dir.txt")"
  if [ -d "$path" ]; then
    log "bundle: $path exists; using it as it is"
  else
    local src
    src="$(dirname "$path")"
    if [ ! -e "$src" ]; then
      mkdir -p "$(dirname "$src")"
      ln -s "$PWD" "$src"
      log "bundle: linked $src to this checkout"
    fi
    [ -d "$src/$(basename "$path")" ] || mv "$tmp/$(basename "$path")" "$src/$(basename "$path")"
  fi
  mkdir -p "$out/lib"
  local lib
  for lib in "$tmp"/lib/*; do
    if ldconfig -p 2>/dev/null | grep -q "[[:space:]]$(basename "$lib") "; then continue; fi
    cp "$lib" "$out/lib/"
  done
  export LD_LIBRARY_PATH="$out/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  build_dir="$path"
  log "bundle: build $path (commit $(cat "$tmp/commit.txt" 2>/dev/null)), carried libraries: $(ls "$out/lib" | tr '\n' ' ')"
  rm -rf "$tmp"
}

# The OpenCL tests without ctest (a machine whose CMake has no ctest): each executable, through
# GoogleTest's filter for the OpenCL cases of the backend suite.
gtestOpenCL() {
  local exe status=0 filter
  for exe in "$build_dir"/tests/test_*; do
    [ -x "$exe" ] && [ -f "$exe" ] || continue
    case "$(basename "$exe")" in test_opencl_*) filter='*' ;; *) filter='OpenCL/*' ;; esac
    [ "$quick" = 1 ] && ! grep -Eq 'auto_backend|opencl_backend|oscillator' <<<"$exe" && continue
    echo "== $exe --gtest_filter=$filter"
    (cd "$build_dir/tests" && "$exe" --gtest_filter="$filter") || status=1
  done
  return $status
}

nvidiaIcd
if [ -n "$bundle" ]; then
  unbundle
  stages=($(printf '%s\n' "${stages[@]}" | grep -Evx 'deps|build'))
fi
for stage in "${stages[@]}"; do
  case "$stage" in
    deps)
      # Only the packages to build and run (no renderers, sanitizers or docs); a machine without
      # root goes on with what it has.
      bash scripts/install-deps.sh --build-only || log "install-deps failed; going on with the installed packages"
      ;;
    build)
      log "building into $build_dir (-j$jobs)"
      {
        cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSTABINT_BUILD_BENCHMARKS=ON -DSTABINT_BUILD_TOOLS=ON
        cmake --build "$build_dir" -j "$jobs"
      } >"$out/build.log" 2>&1 || { tail -30 "$out/build.log" >&2; exit 1; }
      ;;
    test)
      selectDevice
      # The OpenCL tests (ctest label `opencl`) on the selected device; a failure is reported, and
      # the benchmarks still run.
      args=(-L opencl --output-on-failure -j "$jobs" --output-junit "$out/ctest-junit.xml")
      [ "$quick" = 1 ] && args+=(-R 'AutoBackend|DeviceProfiles|OpenCLBackend|Oscillator')
      if [ -z "${STABINT_NO_CTEST:-}" ] && command -v ctest >/dev/null 2>&1; then
        log "ctest ${args[*]}"
        (cd "$build_dir" && ctest "${args[@]}") >"$out/ctest.log" 2>&1 || log "OpenCL tests failed ($out/ctest.log)"
      else
        log "no ctest: the OpenCL test executables one by one"
        gtestOpenCL >"$out/ctest.log" 2>&1 || log "OpenCL tests failed ($out/ctest.log)"
      fi
      tail -3 "$out/ctest.log" >&2
      ;;
    bench-rows)
      selectDevice
      # A third of the stage's time per row, the rows most likely to fit first.
      rows=(nvidia-gpu amd-gpu intel-gpu cpu)
      saved_timeout="$bench_timeout"
      bench_timeout=$((saved_timeout / 3))
      for row in "${rows[@]}"; do
        STABINT_OPENCL_PROFILE="$row" runBench bench-rows "bench-rows-$row"
      done
      bench_timeout="$saved_timeout"
      ;;
    bench-*)
      selectDevice
      runBench "$stage"
      ;;
    report)
      /usr/bin/env python3 bench/gpu_report.py "$out" --quick "$quick" >"$out/report.md"
      log "wrote $out/report.md"
      ;;
  esac
done
