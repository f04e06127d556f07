"""The markdown report of scripts/gpu_report.sh: the machine, the selected OpenCL device, the OpenCL
tests' outcome and, per benchmark stage (bench-<stage>.json), each case on the CPU reference and
the OpenCL device side by side, with the sizes from which the device beats the CPU reference (the
data for BackendKind::Auto's threshold, host/backend/device_profiles.cpp).

    python3 bench/gpu_report.py RESULTS_DIR [--quick 0|1] > RESULTS_DIR/report.md
"""
import argparse
import glob
import json
import os
import platform
import re
import subprocess

UNIT_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
BACKENDS = ("cpu", "opencl-double", "opencl-float")
STAGES = ("bench-frame", "bench-cg", "bench-scaling", "bench-auto", "bench-blend", "bench-solver", "bench-batch")


def load_json(path):
    """A Google Benchmark JSON file, also when the run was cut short (its finished cases); None
    when it is missing or holds no finished case."""
    text = read(path)
    if not text:
        return None
    try:
        return json.loads(text)
    except ValueError:
        end = text.rfind("\n    }")
        if end < 0:
            return None
        try:
            return json.loads(text[: end + len("\n    }")] + "\n  ]\n}\n")
        except ValueError:
            return None


def read(path, default=""):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return default


def case_key(name):
    """(name with the backend part as '*', backend) or None for a case without backend."""
    parts = [p for p in name.split("/") if p not in ("real_time", "manual_time") and not p.startswith("iterations:")]
    for i, p in enumerate(parts):
        if p in BACKENDS:
            return "/".join(parts[:i] + ["*"] + parts[i + 1 :]), p
    return None


def fmt_ms(ms):
    if ms is None:
        return "-"
    if ms >= 100:
        return "%.0f ms" % ms
    if ms >= 1:
        return "%.2f ms" % ms
    return "%.0f us" % (ms * 1e3)


def fmt_ratio(a, b):
    return "-" if a is None or b is None or b == 0 else "%.2f" % (a / b)


def machine_lines(results):
    cpu = ""
    for line in read("/proc/cpuinfo").splitlines():
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
        branch = subprocess.run(["git", "rev-parse", "--abbrev-ref", "HEAD"], capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = branch = "?"
    gpu = ""
    smi = read(os.path.join(results, "nvidia-smi.txt"))
    m = re.search(r"Driver Version: *([0-9.]+)", smi)
    if m:
        gpu = "NVIDIA driver " + m.group(1)
    lines = [
        "- commit: %s (%s)" % (commit, branch),
        "- host: %s, %d hardware threads, %s" % (platform.node(), os.cpu_count() or 0, cpu or "?"),
    ]
    if gpu:
        lines.append("- " + gpu + " (nvidia-smi.txt)")
    device = read(os.path.join(results, "device.txt")).strip().splitlines()
    lines.append("- selected OpenCL device: " + (device[0] if device else "? (no test or bench stage ran)"))
    for d in read(os.path.join(results, "devices.txt")).strip().splitlines():
        lines.append("  - listed: " + d)
    return lines


def gtest_lines(log):
    """The test stage without ctest (STABINT_NO_CTEST): each executable's GoogleTest summary."""
    runs = re.split(r"^== ", log, flags=re.M)[1:]
    passed = sum(int(n) for n in re.findall(r"^\[  PASSED  \] (\d+) tests?", log, re.M))
    failed = sorted(set(re.findall(r"^\[  FAILED  \] ([^\s,]+)(?: \(|, where|$)", log, re.M)))
    unfinished = [r.split()[0] for r in runs if not re.search(r"^\[==========\] \d+ tests? from .* ran", r, re.M)]
    lines = ["%d test cases passed, %d failed, in %d executables (GoogleTest one by one, ctest.log)"
             % (passed, len(failed), len(runs))]
    if failed:
        lines += ["", "Failed:", "```"] + failed[:40] + ["```"]
    if unfinished:
        lines += ["", "No GoogleTest summary (crashed or cut short): " + ", ".join(unfinished)]
    return lines


def tests_lines(results):
    log = read(os.path.join(results, "ctest.log"))
    if not log:
        return ["Not run (stage `test`)."]
    lines = []
    m = re.search(r"^\d+% tests passed.*$", log, re.M)
    if m:
        lines.append(m.group(0) + " (`ctest -L opencl`, ctest.log)")
    elif re.search(r"^== .*--gtest_filter=", log, re.M):
        lines += gtest_lines(log)
    else:
        lines.append("no summary line in ctest.log (cut short?) (`ctest -L opencl`, ctest.log)")
    failed = log.split("The following tests FAILED:", 1)
    if len(failed) == 2:
        lines += ["", "Failed:", "```"] + [l for l in failed[1].strip().splitlines() if l.strip()][:40] + ["```"]
    skipped = len(re.findall(r"\*\*\*Skipped|Not Run|SKIPPED", log))
    if skipped:
        lines.append("Skipped: %d" % skipped)
    return lines


def stage_tables(results, stage, quick):
    data = load_json(os.path.join(results, stage + ".json"))
    if data is None:
        return ["### %s" % stage, "", "Not run, or no finished case (%s.json)." % stage, ""], {}
    cases, labels, errors = {}, {}, []
    for b in data.get("benchmarks", []):
        if b.get("run_type", "iteration") != "iteration":
            continue
        key = case_key(b["name"])
        if key is None:
            continue
        if b.get("error_occurred"):
            errors.append("%s: %s" % (b["name"], b.get("error_message", "")))
            continue
        ms = b["real_time"] * UNIT_MS[b.get("time_unit", "ns")]
        entry = cases.setdefault(key[0], {"particles": b.get("particles")})
        if key[1] not in entry or ms < entry[key[1]]:
            entry[key[1]] = ms
        if key[1] != "cpu" and b.get("label", "").startswith("OpenCL: "):
            labels[key[1]] = b["label"]
    lines = ["### %s" % stage, ""]
    for backend in ("opencl-double", "opencl-float"):
        if backend in labels:
            lines.append("- %s: %s" % (backend, labels[backend]))
    lines += [
        "",
        "| case | particles | cpu | opencl-double | opencl-float | double / cpu | float / cpu |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, e in cases.items():
        particles = "%d" % e["particles"] if e.get("particles") else ""
        lines.append(
            "| %s | %s | %s | %s | %s | %s | %s |"
            % (
                name,
                particles,
                fmt_ms(e.get("cpu")),
                fmt_ms(e.get("opencl-double")),
                fmt_ms(e.get("opencl-float")),
                fmt_ratio(e.get("opencl-double"), e.get("cpu")),
                fmt_ratio(e.get("opencl-float"), e.get("cpu")),
            )
        )
    if errors:
        lines += ["", "Errors or skips (%d):" % len(errors), ""] + ["- " + e for e in errors[:20]]
    lines.append("")
    return lines, cases


def rows_lines(results):
    """bench-rows-<row>.json: the same OpenCL cases with each row's launch sizes."""
    paths = sorted(glob.glob(os.path.join(results, "bench-rows-*.json")))
    if not paths:
        return ["Not run (stage `bench-rows`)."]
    rows, times = [], {}
    for path in paths:
        row = os.path.basename(path)[len("bench-rows-") : -len(".json")]
        rows.append(row)
        data = load_json(path) or {}
        for b in data.get("benchmarks", []):
            if b.get("run_type", "iteration") != "iteration" or b.get("error_occurred"):
                continue
            name = "/".join(p for p in b["name"].split("/") if p != "real_time" and not p.startswith("iterations:"))
            ms = b["real_time"] * UNIT_MS[b.get("time_unit", "ns")]
            cell = times.setdefault(name, {})
            cell[row] = min(ms, cell.get(row, ms))
    lines = ["| case | " + " | ".join(rows) + " |", "|---|" + "---:|" * len(rows)]
    for name in sorted(times):
        lines.append("| %s | %s |" % (name, " | ".join(fmt_ms(times[name].get(r)) for r in rows)))
    return lines


def family(name):
    """The case name without its size: scaling_step/cloth/BE/*/side:50 -> scaling_step/cloth/BE/*."""
    parts = name.split("/")
    if parts[-1].startswith("side:"):
        return "/".join(parts[:-1])
    if parts[0] == "auto_iteration":  # auto_iteration/springs50x50/BE/* -> auto_iteration/springs/BE/*
        return "/".join([parts[0], re.sub(r"[0-9x]+$", "", parts[1])] + parts[2:])
    return None


def crossing_lines(all_cases):
    """Per size family: the smallest size from which OpenCL is faster than the CPU reference at
    that size and every larger one (Auto's threshold on this device)."""
    families = {}
    for name, e in all_cases.items():
        f = family(name)
        if f and e.get("particles") and e.get("cpu"):
            families.setdefault(f, []).append(e)
    if not families:
        return ["No scaling or auto_iteration cases ran."]
    lines = [
        "| family | sizes (particles) | opencl-double faster from | opencl-float faster from |",
        "|---|---|---|---|",
    ]
    for f, entries in sorted(families.items()):
        entries.sort(key=lambda e: e["particles"])
        row = [f, ", ".join("%d" % e["particles"] for e in entries)]
        for backend in ("opencl-double", "opencl-float"):
            crossing = None
            for e in reversed(entries):
                if e.get(backend) is not None and e[backend] < e["cpu"]:
                    crossing = e["particles"]
                else:
                    break
            if all(e.get(backend) is None for e in entries):
                row.append("-")
            else:
                row.append("%d particles" % crossing if crossing else "never (up to the largest)")
        lines.append("| " + " | ".join(row) + " |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results")
    parser.add_argument("--quick", default="0")
    args = parser.parse_args()
    quick = args.quick == "1"
    out = ["# GPU report", ""]
    if quick:
        out += ["Quick mode (`--quick`): a check of the script, not a measurement.", ""]
    out += machine_lines(args.results) + ["", "## OpenCL tests", ""] + tests_lines(args.results)
    out += ["", "## Benchmarks", "", "Fastest repetition per case, wall time per benchmark iteration; ratios above 1: "
            "OpenCL slower than the CPU reference on this machine.", ""]
    all_cases = {}
    extra = sorted(
        set(os.path.basename(p)[:-5] for p in glob.glob(os.path.join(args.results, "bench-*.json")))
        - set(STAGES)
        - set(os.path.basename(p)[:-5] for p in glob.glob(os.path.join(args.results, "bench-rows-*.json")))
    )
    for stage in list(STAGES) + extra:
        lines, cases = stage_tables(args.results, stage, quick)
        out += lines
        all_cases.update(cases)
    out += ["## Where the device overtakes the CPU reference", "",
            "The data for BackendKind::Auto's costs (DeviceProfile::auto_*, "
            "host/backend/device_profiles.cpp).", ""]
    out += crossing_lines(all_cases)
    out += ["", "## Rows of launch sizes on this device", "",
            "The same OpenCL cases with each row's work-group sizes and reduction grid "
            "(STABINT_OPENCL_PROFILE=<row>; host/backend/device_profiles.cpp).", ""]
    out += rows_lines(args.results)
    print("\n".join(out))


if __name__ == "__main__":
    main()
