"""Reading stabint_bench's JSON output (--benchmark_out=... --benchmark_out_format=json or
--benchmark_format=json), shared by the chart scripts."""
import argparse
import json

UNIT_S = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def fastest_repetitions(path, family, parts_count):
    """{name parts as a tuple: (fastest seconds per iteration, the JSON entry)} over the
    repetitions of every case whose name starts with `family` and has `parts_count` parts
    separated by '/' (after dropping the trailing iterations:N, real_time, manual_time). Cases that failed or were
    skipped, and the aggregates (mean, median, stddev, cv), are left out."""
    with open(path) as f:
        data = json.load(f)
    best = {}
    for entry in data["benchmarks"]:
        if entry.get("run_type") != "iteration" or entry.get("error_occurred"):
            continue
        parts = entry["run_name"].split("/")
        while parts and (parts[-1] in ("real_time", "manual_time") or parts[-1].startswith("iterations:")):
            parts = parts[:-1]
        if len(parts) != parts_count or not parts[0].startswith(family):
            continue
        seconds = entry["real_time"] * UNIT_S[entry.get("time_unit", "ns")]
        key = tuple(parts)
        if key not in best or seconds < best[key][0]:
            best[key] = (seconds, entry)
    return best


def chart_main(doc, default_chart, load, table, chart):
    """The chart scripts' command line: `<script> JSON [--chart PNG]` prints table(load(JSON)) and
    draws chart(cases, PNG)."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("json")
    parser.add_argument("--chart", default=default_chart)
    args = parser.parse_args()
    cases = load(args.json)
    print(table(cases))
    chart(cases, args.chart)
