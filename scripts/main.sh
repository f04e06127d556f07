#!/usr/bin/env bash
# The main job (the README's first command): installs missing dependencies, builds the study
# tool and the benchmark suite (Release, into build/, the same build directory as scripts/test.sh),
# runs every experiment of stabint-study (energy and motion tables printed), and draws the charts,
# the summary and the compact motion table (issue 8's targets, printed at the end of the charts
# step). Idempotent; the reference trajectories (the IM h/16 accuracy references and the small-step
# motion references, computed first and two at a time by `stabint-study all`) are cached in
# results/cache/ so a rerun skips them.
# Its run time is in the README, "The main job".
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
elapsed() { echo "$(( $(date +%s) - start )) s"; }

bash scripts/install-deps.sh

# One build for the study tool and the scaling benchmark at the end, so that nothing is built
# after the experiments (STABINT_BUILD_BENCHMARKS is the default; named in case build/ was
# configured without it).
echo "== build (Release, build/, targets stabint-study and stabint_bench)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSTABINT_BUILD_TOOLS=ON -DSTABINT_BUILD_BENCHMARKS=ON
cmake --build build --target stabint-study stabint_bench -j"$(nproc)"
echo "== built in $(elapsed)"

echo "== experiments: build/tools/study/stabint-study all --out results"
build/tools/study/stabint-study all --out results

# The soft body of issue 23: CGAL's elephant (Debian's libcgal-demo) meshed by TetGen, dropped on
# the ground with BE, BDF2 and the blend (about 10 s), rendered with POV-Ray with the teaser.
echo "== soft body: scripts/soft_body_mesh.sh results/mesh; stabint-study drop"
bash scripts/soft_body_mesh.sh results/mesh
build/tools/study/stabint-study drop --mesh results/mesh/elephant.1 --out results

# Self-contact's study scene (issue 49): a 40 x 40 cloth folds onto itself on the ground and is
# dragged over the elephant's surface as a mesh collider, with BE, BDF2 and the blend (about 20 s).
echo "== self-contact: stabint-study fold"
build/tools/study/stabint-study fold --mesh results/mesh/elephant.1 --out results

# The charts and the three pictures are drawn at once, since none of them is timed and each is
# mostly one core's work: matplotlib, and a still that is one single-threaded POV-Ray process
# (POV-Ray's own work threads would change its pixels; separate processes render the same ones).
# The pictures' output is printed after the charts' (which end with the motion table).
echo "== charts; the teaser, the drop and the fold (POV-Ray) beside them"
t_pictures=$(date +%s)
pictures_log=$(mktemp -d)
pictures=()
for picture in teaser drop fold; do
  /usr/bin/python3 "bench/$picture.py" results > "$pictures_log/$picture.log" 2>&1 &
  pictures+=("$!")
done
/usr/bin/python3 bench/study_charts.py results
failed=0
for pid in "${pictures[@]}"; do wait "$pid" || failed=1; done
cat "$pictures_log"/{teaser,drop,fold}.log
rm -rf "$pictures_log"
[ "$failed" = 0 ] || { echo "main.sh: a picture script failed (its output is above)" >&2; exit 1; }
echo "== charts and pictures (POV-Ray) in $(( $(date +%s) - t_pictures )) s"

# Chart 4 (scaling): the benchmark suite's cloth scaling family, 10x10 to 224x224 particles, on
# the CPU reference and OpenCL backends (about a minute). scripts/bench.sh runs the whole suite.
echo "== scaling benchmark: build/bench/stabint_bench --benchmark_filter='^scaling_'"
build/bench/stabint_bench --benchmark_filter='^scaling_' \
  --benchmark_out=results/bench_scaling.json --benchmark_out_format=json
/usr/bin/python3 bench/scaling_chart.py results/bench_scaling.json --charts results/charts \
  --summary results/bench_scaling_summary.md

echo
echo "main.sh: done in $(elapsed)."
echo "  energy table:   results/energy_table.csv (printed above)"
echo "  summary:        results/summary.md"
echo "  motion table:   results/motion.csv (printed above, and in the summary)"
echo "  contact table:  results/contact_table.md (printed above; docs/method.md, \"Contact\")"
echo "  charts:         results/charts/{speed_vs_accuracy,stability_map,energy_over_time,cloth_still,motion,interaction,scaling}.png (and .svg)"
echo "  teaser:         results/charts/teaser.gif (animation), teaser.png (still and energy curves), teaser_energy.png"
echo "  soft-body drop: results/charts/drop.gif (animation), drop.png (still and energy curves);"
echo "                  results/drop_table.md (printed above); the TetGen mesh: results/mesh/elephant.1.{node,ele}"
echo "  self-contact:   results/charts/fold.gif (animation), fold.png (still and energy curves);"
echo "                  results/fold_table.md (printed above)"
echo "  all CSV files:  results/*.csv; cached reference trajectories: results/cache/"
echo "  API reference:  bash scripts/apidocs.sh -> build/apidocs/html/index.html (C++), build/apidocs/python/index.html"
