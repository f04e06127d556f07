#!/usr/bin/env bash
# Trajectory hashes: one line per run, "<run id> <sha256>", for checking that a refactor of the
# stepping driver leaves every Simulator trajectory bit for bit as it was (diff two outputs).
#
#   bash scripts/trajectory_hashes.sh [BUILD_DIR] > hashes.txt     (BUILD_DIR defaults to build)
#
# Each run is `stabint-run` (tools/run) on one scene, integrator, solver and backend. Its hash
# covers the per-frame CSV without the timing columns (*_s: wall-clock seconds per phase), every
# VTK frame (positions and velocities printed to the last bit, and the .pvd's times), the exit
# status and standard error with --quiet (a refused step's message: the CSV stops there).
# Covered:
#   CPU reference: the built-in scenes (oscillator, chain, cloth, tetbar) and every scenes/*.json
#     (events, handles, colliders) x FE, SE, BE, BDF2, IM, blend x the default solver (L-BFGS)
#     and --acceleration none, and with --energy-limit 0.05 (refusals by the limit); BE, BDF2, IM
#     and blend also with Chebyshev, Anderson, Newton-CG, CG (with and without its tolerance), a
#     tolerance stop and L-BFGS's gradient stop; FRAMES frames (default 60);
#   OpenCL, when a device is listed (PoCL on a CPU counts), --precision double and float: the
#     same scenes, FE, SE, BE, BDF2, IM and blend with the default solver, OPENCL_FRAMES frames
#     (default 60).
# STABINT_THREADS is fixed (2), so that the CPU reference's threaded sums split the same way on
# any machine. Runs go two at a time (JOBS); the output is sorted by run id. About a minute and a
# half on a 2-core VM with PoCL.
set -euo pipefail

build=${1:-build}
run="$build/tools/run/stabint-run"
[[ -x "$run" ]] || { echo "no $run: build first" >&2; exit 1; }
root=$(cd "$(dirname "$0")/.." && pwd)
frames=${FRAMES:-60}
opencl_frames=${OPENCL_FRAMES:-60}
jobs=${JOBS:-2}
export STABINT_THREADS=2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

scenes=(oscillator chain cloth tetbar)
for f in "$root"/scenes/*.json; do scenes+=("$f"); done
# A run's scene name: the built-in's, or scenes/<file> (chain and tetbar are both).
scene_id() { [[ $1 == *.json ]] && echo "scenes/$(basename "$1" .json)" || echo "$1"; }
integrators=(FE SE BE BDF2 IM blend)
# The other solver options, "<id>|<arguments>", for the implicit integrators on the CPU reference.
solvers=("chebyshev|--acceleration|chebyshev" "anderson|--acceleration|anderson" "newton|--acceleration|newton"
         "cg|--global-solve|cg" "cg-tolerance|--global-solve|cg|--cg-tolerance|1e-6"
         "tolerance|--tolerance|1e-6" "gradient-tolerance|--gradient-tolerance|1e-3")

# One run: id, then stabint-run's arguments. Prints "<id> <hash>".
one_run() {
  local id=$1 run=$2 dir
  shift 2
  dir=$(mktemp -d -p "$WORK")
  local rc=0
  "$run" "$@" --quiet --csv "$dir/frames.csv" --vtk "$dir/vtk" 2>"$dir/stderr" || rc=$?
  {
    echo "rc=$rc"
    cat "$dir/stderr"
    if [[ -f "$dir/frames.csv" ]]; then
      # Drop the columns whose header ends in _s (timings).
      awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) keep[i] = ($i !~ /_s$/) }
               { line = ""; for (i = 1; i <= NF; ++i) if (keep[i]) line = line (line == "" ? "" : ",") $i; print line }' \
        "$dir/frames.csv"
    fi
    if [[ -d "$dir/vtk" ]]; then
      for f in $(ls "$dir/vtk" | sort); do
        echo "== $f"
        cat "$dir/vtk/$f"
      done
    fi
  } | sha256sum | { read -r hash _; echo "$id $hash"; }
  rm -rf "$dir"
}
export -f one_run
export WORK=$work

{
  for scene in "${scenes[@]}"; do
    name=$(scene_id "$scene")
    for integrator in "${integrators[@]}"; do
      echo "cpu/$name/$integrator/default|--scene|$scene|--integrator|$integrator|--backend|cpu|--frames|$frames"
      echo "cpu/$name/$integrator/none|--scene|$scene|--integrator|$integrator|--backend|cpu|--acceleration|none|--frames|$frames"
      # A refusal by the energy limit (EnergyLimitError) where the integrator gains energy.
      echo "cpu/$name/$integrator/energy-limit|--scene|$scene|--integrator|$integrator|--backend|cpu|--energy-limit|0.05|--frames|$frames"
    done
    for integrator in BE BDF2 IM blend; do
      for solver in "${solvers[@]}"; do
        echo "cpu/$name/$integrator/${solver%%|*}|--scene|$scene|--integrator|$integrator|--backend|cpu|${solver#*|}|--frames|$frames"
      done
    done
  done
  if "$run" --list-devices 2>/dev/null | grep -q '^platform'; then
    for precision in double float; do
      for scene in "${scenes[@]}"; do
        name=$(scene_id "$scene")
        for integrator in "${integrators[@]}"; do
          echo "opencl-$precision/$name/$integrator/default|--scene|$scene|--integrator|$integrator|--backend|opencl|--precision|$precision|--frames|$opencl_frames"
        done
      done
    done
  fi
} | xargs -P "$jobs" -I{} bash -c 'IFS="|" read -r -a a <<< "$1"; one_run "${a[0]}" "$2" "${a[@]:1}"' _ {} "$run" |
  sort
