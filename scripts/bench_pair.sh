#!/usr/bin/env bash
# Paired timing of two stabint_bench binaries (before / after a change) on a shared, noisy
# machine: the two alternate `rounds` times, each run with 3 repetitions of every case matching
# the filter; prints per case the median and the fastest of each binary's repetitions and their
# ratios (after / before). The JSON of every run stays in the output folder.
#   bash scripts/bench_pair.sh OLD_BENCH NEW_BENCH FILTER [ROUNDS=5] [OUT=bench-pair]
# e.g. an old build from `git worktree add /tmp/old REV` configured with -DSTABINT_BUILD_TESTS=OFF
# -DSTABINT_BUILD_BENCHMARKS=ON and built with `--target stabint_bench`.
set -euo pipefail
old=$1 new=$2 filter=$3 rounds=${4:-5} out=${5:-bench-pair}
mkdir -p "$out"
for r in $(seq 1 "$rounds"); do
  for v in old new; do
    bin=$old
    [[ $v == new ]] && bin=$new
    "$bin" --benchmark_filter="$filter" --benchmark_repetitions=3 --benchmark_format=json \
      --benchmark_out="$out/${v}_$r.json" > /dev/null
  done
done
/usr/bin/python3 - "$out" "$rounds" <<'PY'
import json, statistics, sys
out, rounds = sys.argv[1], int(sys.argv[2])
times = {}
for v in ("old", "new"):
    for r in range(1, rounds + 1):
        with open(f"{out}/{v}_{r}.json") as f:
            for b in json.load(f)["benchmarks"]:
                if b.get("run_type") == "iteration" and not b.get("error_occurred"):
                    times.setdefault(b["run_name"], {}).setdefault(v, []).append(b["real_time"])
for name, t in times.items():
    if "old" not in t or "new" not in t:
        continue
    o, n = statistics.median(t["old"]), statistics.median(t["new"])
    print(f"{name}: before {o:.4g} (fastest {min(t['old']):.4g}), after {n:.4g} (fastest {min(t['new']):.4g}), "
          f"after/before {n / o:.2f} (fastest {min(t['new']) / min(t['old']):.2f})")
PY
