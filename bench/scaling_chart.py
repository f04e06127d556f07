#!/usr/bin/python3
"""Charts and a markdown summary from stabint_bench's JSON output.

    /usr/bin/python3 bench/scaling_chart.py results/bench.json \
        [--charts results/charts] [--summary results/bench_summary.md]

Writes <charts>/scaling.png and .svg (log-log: one BE local/global iteration, total and per
phase, and BE/blend steps, against the number of particles of the cloth scaling family) and the
summary: tables per scene/backend/integrator of step and iteration times with their phase
breakdown, and the two performance goals (docs/method.md section 3 and the issue):
  - one BE iteration on the 50x50 cloth under 0.6 ms on PoCL (OpenCL backend);
  - a blend step at most 30 % slower than a BE step with the same main iteration count (aim, issue 11:
    at most 10 %).
The global solve variants (global_solve/*) are listed with their memory bound and time/bound.
Use /usr/bin/python3 (Debian's python3-matplotlib); `python3` on PATH may lack matplotlib.
"""
import argparse
import json
import os
import sys
from collections import defaultdict

ITERATION_GOAL_S = 0.6e-3
BLEND_OVERHEAD_MAX = 0.30
BLEND_OVERHEAD_AIM = 0.10  # issue 11, item 2
PHASES = ["local", "gather", "transfer", "global", "energy", "bookkeeping"]
ITERATION_PHASES = ["local", "gather", "transfer", "global"]
BACKENDS = ["cpu", "opencl-double", "opencl-float"]
INTEGRATORS = ["FE", "SE", "BE", "BDF2", "IM", "blend"]
UNIT_S = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


class Case:
    """One benchmark result: its name parts, wall time per iteration (s) and counters."""

    def __init__(self, entry):
        parts = entry["run_name"].split("/")
        if parts and parts[-1] in ("real_time", "manual_time"):
            parts = parts[:-1]
        self.parts = parts
        self.kind = parts[0]
        self.time = entry["real_time"] * UNIT_S[entry.get("time_unit", "ns")]
        self.cpu_time = entry.get("cpu_time", 0.0) * UNIT_S[entry.get("time_unit", "ns")]
        self.counters = {k: v for k, v in entry.items() if isinstance(v, (int, float))}
        self.counters["iterations_run"] = entry.get("iterations", 1)
        self.label = entry.get("label", "")
        self.side = None
        for p in parts:
            if p.startswith("side:"):
                self.side = int(p.split(":", 1)[1])

    def get(self, name, default=0.0):
        return self.counters.get(name, default)


def load(path):
    """Cases by run name; errors (skipped cases) kept apart. With repetitions, the fastest
    repetition is used (the least disturbed by other load on a shared machine), except for the
    paired blend_vs_be cases, whose step times are pooled over all repetitions. When the JSON holds
    only aggregates, the median is used."""
    with open(path) as f:
        data = json.load(f)
    runs, medians, errors = defaultdict(list), {}, {}
    for entry in data.get("benchmarks", []):
        name = entry.get("run_name", entry["name"])
        if entry.get("error_occurred"):
            errors[name] = entry.get("error_message", "error")
            continue
        if entry.get("run_type") == "aggregate":
            if entry.get("aggregate_name") == "median":
                medians[name] = Case(entry)
        else:
            runs[name].append(Case(entry))
    chosen = dict(medians)
    for name, reps in runs.items():
        if reps[0].kind == "blend_vs_be":
            pooled = reps[0]
            n = sum(r.get("iterations_run", 1) for r in reps)
            for key in ("be_step", "blend_step"):
                pooled.counters[key] = sum(r.get(key) * r.get("iterations_run", 1) for r in reps) / n
            if pooled.get("be_step") > 0:
                pooled.counters["overhead"] = pooled.get("blend_step") / pooled.get("be_step") - 1.0
            chosen[name] = pooled
        else:
            chosen[name] = min(reps, key=lambda r: r.time)
    return data.get("context", {}), list(chosen.values()), errors, max(len(r) for r in runs.values()) if runs else 1


def index(cases):
    by = defaultdict(dict)
    for c in cases:
        p = c.parts
        if c.kind in ("step", "iteration") and len(p) >= 4:
            by[c.kind][(p[1], p[2], p[3])] = c  # (scene, integrator, backend)
        elif c.kind in ("scaling_step", "scaling_iteration") and len(p) >= 5 and c.side:
            by[c.kind][(p[2], p[3], c.side)] = c  # (integrator, backend, side)
        elif c.kind == "blend_vs_be" and len(p) >= 3:
            by[c.kind][(p[1], p[2])] = c  # (scene, backend)
        elif c.kind == "global_solve" and len(p) >= 3:
            by[c.kind][(p[1], p[2])] = c  # (scene, variant)
    return by


def fmt_time(seconds):
    if seconds is None:
        return "-"
    if seconds >= 1.0:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.2f} ms"
    if seconds >= 1e-5:
        return f"{seconds * 1e6:.0f} us"
    return f"{seconds * 1e6:.1f} us"


def fmt_pct(x):
    return "-" if x is None else f"{x * 100:+.1f} %"


# ---- charts ------------------------------------------------------------------------------------

def draw_charts(by, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = {"cpu": "tab:blue", "opencl-double": "tab:red", "opencl-float": "tab:orange"}
    phase_styles = {"local": "o--", "gather": "s--", "transfer": "^--", "global": "D--"}
    it = by.get("scaling_iteration", {})
    st = by.get("scaling_step", {})
    if not it and not st:
        print("scaling_chart: no scaling cases in the JSON; no chart written", file=sys.stderr)
        return []

    def series(table, integrator, backend, value):
        pts = sorted((c.get("particles"), value(c)) for (i, b, _), c in table.items()
                     if i == integrator and b == backend)
        pts = [(n, v) for n, v in pts if n and v and v > 0]
        return [n for n, _ in pts], [v for _, v in pts]

    def legend(ax, **kw):
        if ax.get_legend_handles_labels()[0]:
            ax.legend(**kw)

    fig, axes = plt.subplots(2, 2, figsize=(13, 10))
    ax = axes[0][0]
    for b in BACKENDS:
        n, t = series(it, "BE", b, lambda c: c.time)
        if n:
            ax.plot(n, t, "o-", color=colors[b], label=b)
    ax.axhline(ITERATION_GOAL_S, color="gray", ls=":", lw=1)
    ax.axvline(2500, color="gray", ls=":", lw=1)
    ax.annotate("goal: 0.6 ms at 50x50 (PoCL)", (2500, ITERATION_GOAL_S), textcoords="offset points",
                xytext=(5, 5), fontsize=8, color="gray")
    ax.set_title("one BE local/global iteration (cloth), wall time")
    legend(ax)

    for ax, backend in ((axes[0][1], "cpu"), (axes[1][0], "opencl-double")):
        n, t = series(it, "BE", backend, lambda c: c.time)
        if n:
            ax.plot(n, t, "k-", lw=2, label="total")
        for ph in ITERATION_PHASES:
            n, t = series(it, "BE", backend, lambda c, ph=ph: c.get(ph))
            if n:
                ax.plot(n, t, phase_styles[ph], label=ph, ms=4)
        ax.set_title(f"BE iteration by phase: {backend}")
        legend(ax)

    ax = axes[1][1]
    for b in BACKENDS:
        for integ, style in (("BE", "s--"), ("blend", "o-")):
            n, t = series(st, integ, b, lambda c: c.time)
            if n:
                ax.plot(n, t, style, color=colors[b], label=f"{integ} step, {b}", ms=4)
    ax.set_title("one step (10 iterations; blend: IM + BE partner)")
    legend(ax, fontsize=8)

    for row in axes:
        for a in row:
            a.set_xscale("log")
            a.set_yscale("log")
            a.set_xlabel("particles")
            a.set_ylabel("seconds")
            a.grid(True, which="both", alpha=0.3)
    fig.suptitle("stabint: time against cloth size (10x10 to 224x224 particles)")
    fig.tight_layout()
    os.makedirs(out_dir, exist_ok=True)
    written = []
    for ext in ("png", "svg"):
        path = os.path.join(out_dir, f"scaling.{ext}")
        fig.savefig(path, dpi=110)
        written.append(path)
    plt.close(fig)
    return written


# ---- summary -----------------------------------------------------------------------------------

def goal_checks(by):
    lines = []
    its = by.get("iteration", {})
    lines.append("### Goal 1: one BE iteration on the 50x50 cloth under 0.6 ms on PoCL\n")
    lines.append("| backend | iteration | local | gather | transfer | global | verdict |")
    lines.append("|---|---|---|---|---|---|---|")
    found = False
    for b in BACKENDS:
        c = its.get(("cloth50x50", "BE", b))
        if not c:
            continue
        found = True
        check = "-" if b == "cpu" else ("PASS" if c.time < ITERATION_GOAL_S else "MISS")
        lines.append(f"| {b} | {fmt_time(c.time)} | " +
                     " | ".join(fmt_time(c.get(p)) for p in ITERATION_PHASES) + f" | {check} |")
    if not found:
        lines.append("| (no iteration/cloth50x50/BE case in the JSON) | | | | | | |")
    lines.append("")

    lines.append("### Goal 2: blend step at most 30 % (aim, issue 11: 10 %) slower than a BE step\n")
    lines.append("Both with the same main iteration count (10); the blend adds its BE partner "
                 "(be_iterations) when IM has too much energy, the FE partner when too little, and "
                 "energy evaluations for the root find.\n")
    pairs = by.get("blend_vs_be", {})
    if pairs:
        lines.append("Paired cases (blend_vs_be): one BE step and one blend step alternated from the same "
                     "start, so other load hits both alike.\n")
        lines.append("| scene | backend | BE step | blend step | overhead | blend iterations/step | "
                     "blend energy evals/step | branch IM/BE/FE | verdict |")
        lines.append("|---|---|---|---|---|---|---|---|---|")
        for (scene, b), c in sorted(pairs.items()):
            over = c.get("overhead")
            branches = "/".join(f"{c.get('branch_' + x) * 100:.0f}%" for x in ("IM", "BE", "FE"))
            lines.append(f"| {scene} | {b} | {fmt_time(c.get('be_step'))} | {fmt_time(c.get('blend_step'))} | "
                         f"{fmt_pct(over)} | {c.get('blend_iterations'):.1f} | "
                         f"{c.get('blend_energy_evaluations'):.2f} | {branches} | {verdict(over)} |")
        lines.append("")
    steps = by.get("step", {})
    rows = []
    for scene in sorted({k[0] for k in steps}):
        for b in BACKENDS:
            be, bl = steps.get((scene, "BE", b)), steps.get((scene, "blend", b))
            if not be or not bl:
                continue
            over = bl.time / be.time - 1.0
            branches = "/".join(f"{bl.get('branch_' + x) * 100:.0f}%" for x in ("IM", "BE", "FE"))
            rows.append(f"| {scene} | {b} | {fmt_time(be.time)} | {fmt_time(bl.time)} | {fmt_pct(over)} | "
                        f"{bl.get('iterations'):.1f} | {bl.get('energy_evaluations'):.2f} | {branches} | "
                        f"{verdict(over)} |")
    if rows:
        lines.append("From the separate step cases (each simulator at its own point of the motion):\n")
        lines.append("| scene | backend | BE step | blend step | overhead | blend iterations/step | "
                     "blend energy evals/step | branch IM/BE/FE | verdict |")
        lines.append("|---|---|---|---|---|---|---|---|---|")
        lines += rows
    lines.append("")
    return lines


def verdict(over):
    if over is None:
        return "-"
    return ("PASS (aim met)" if over <= BLEND_OVERHEAD_AIM else
            "PASS" if over <= BLEND_OVERHEAD_MAX else "MISS")


def step_tables(by):
    lines = ["## Steps (Simulator::step, per step)\n",
             "Phase columns are wall time per step from StepReport::times; `iter` is the time of one "
             "local/global iteration inside the step (local+gather+transfer+global per iteration).\n"]
    steps = by.get("step", {})
    for scene in sorted({k[0] for k in steps}):
        c0 = next(c for k, c in steps.items() if k[0] == scene)
        lines.append(f"### {scene} ({c0.get('particles'):.0f} particles, {c0.get('elements'):.0f} elements)\n")
        lines.append("| integrator | backend | step | iterations | iter | " + " | ".join(PHASES) + " |")
        lines.append("|---|---|---|---|---|" + "---|" * len(PHASES))
        for integ in INTEGRATORS:
            for b in BACKENDS:
                c = steps.get((scene, integ, b))
                if not c:
                    continue
                iter_t = c.counters.get("iteration_time")
                lines.append(f"| {integ} | {b} | {fmt_time(c.time)} | {c.get('iterations'):.1f} | "
                             f"{fmt_time(iter_t) if iter_t else '-'} | " +
                             " | ".join(fmt_time(c.get(p)) for p in PHASES) + " |")
        lines.append("")
    return lines


def iteration_tables(by):
    lines = ["## One local/global iteration (LocalGlobalSolver, 1 iteration)\n",
             "`other` is the wall time not booked to a phase (launch/queue overhead outside the "
             "timers, the write-back of x is booked as transfer).\n"]
    its = by.get("iteration", {})
    lines.append("| scene | integrator (c) | backend | iteration | " + " | ".join(ITERATION_PHASES) + " | other |")
    lines.append("|---|---|---|---|" + "---|" * len(ITERATION_PHASES) + "---|")
    for (scene, integ, b), c in sorted(its.items(), key=lambda kv: (kv[0][0], INTEGRATORS.index(kv[0][1])
                                                                   if kv[0][1] in INTEGRATORS else 9,
                                                                   BACKENDS.index(kv[0][2])
                                                                   if kv[0][2] in BACKENDS else 9)):
        other = c.time - sum(c.get(p) for p in ITERATION_PHASES)
        lines.append(f"| {scene} | {integ} | {b} | {fmt_time(c.time)} | " +
                     " | ".join(fmt_time(c.get(p)) for p in ITERATION_PHASES) + f" | {fmt_time(max(other, 0.0))} |")
    lines.append("")
    return lines


def scaling_table(by):
    it, st = by.get("scaling_iteration", {}), by.get("scaling_step", {})
    if not it and not st:
        return []
    sides = sorted({k[2] for k in it} | {k[2] for k in st})
    lines = ["## Cloth scaling\n",
             "| cloth | particles | backend | BE iteration | local | gather | transfer | global | "
             "BE step | blend step | blend overhead |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for side in sides:
        for b in BACKENDS:
            i = it.get(("BE", b, side))
            be, bl = st.get(("BE", b, side)), st.get(("blend", b, side))
            if not (i or be or bl):
                continue
            n = (i or be or bl).get("particles")
            over = bl.time / be.time - 1.0 if be and bl else None
            phases = " | ".join(fmt_time(i.get(p)) if i else "-" for p in ITERATION_PHASES)
            lines.append(f"| {side}x{side} | {n:.0f} | {b} | {fmt_time(i.time) if i else '-'} | {phases} | "
                         f"{fmt_time(be.time) if be else '-'} | {fmt_time(bl.time) if bl else '-'} | {fmt_pct(over)} |")
    lines.append("")
    return lines


def solver_table(by):
    """global_solve/<scene>/<variant>: each variant's time against its memory bound (bench_solver.cpp:
    2 factor_bytes / one thread's streaming bandwidth over a buffer of that size, measured in the
    same case), and against the library's time."""
    gs = by.get("global_solve", {})
    if not gs:
        return []
    lines = ["## Global solve against its bound (K_c x = rhs, 3 columns)\n",
             "bound: the factor's bytes (8 bytes of value and 4 of row index per entry, column pointers and "
             "lengths; supernodal: its dense blocks and indices) read twice, forward and backward, at the "
             "streaming bandwidth of one thread over a buffer of that size, measured in each case of the "
             "scene (the fastest of those measurements for that factor). "
             "All three columns in those two passes: a solve per column reads the factor three times "
             "as often (passes).\n",
             "`cpu`: the solving thread's CPU time per solve, which other load on a shared machine inflates "
             "less than the wall time (one-thread variants only).\n",
             "| scene | particles | factor entries | factor MB | bandwidth | variant | passes | solve | bound | "
             "solve/bound | cpu/bound | vs library |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]

    def order(scene):
        digits = [int(x) for x in "".join(ch if ch.isdigit() else " " for ch in scene).split()]
        return (0 if scene.startswith("cloth") else 1, digits[0] if digits else 0, scene)

    # One bound per scene and factor (the simplicial variants share theirs): the fastest of the
    # streaming measurements over a buffer of that size, one per case, so that a case whose
    # measurement other load disturbed does not get a lenient bound.
    best_bound = {}
    for (scene, _), c in gs.items():
        key = (scene, c.get("factor_bytes"))
        if c.get("bound") > 0:
            best_bound[key] = min(best_bound.get(key, float("inf")), c.get("bound"))
    for scene in sorted({k[0] for k in gs}, key=order):
        lib = gs.get((scene, "library"))
        for (s, variant), c in sorted(gs.items(), key=lambda kv: kv[0][1] != "library"):
            if s != scene:
                continue
            rel = f"{c.time / lib.time:.2f}x" if lib else "-"
            bound = best_bound.get((scene, c.get("factor_bytes")), 0.0)
            ratio = f"{c.time / bound:.2f}" if bound else "-"
            one_thread = not variant.endswith("-2t")
            cpu = f"{c.cpu_time / bound:.2f}" if bound and one_thread and c.cpu_time > 0 else "-"
            bandwidth = 2.0 * c.get("factor_bytes") / bound if bound else 0.0
            lines.append(f"| {scene} | {c.get('particles'):.0f} | {c.get('factor_entries'):.0f} | "
                         f"{c.get('factor_bytes') / 1e6:.2f} | {bandwidth / 1e9:.0f} GB/s | {variant} | "
                         f"{c.get('passes'):.0f} | {fmt_time(c.time)} | {fmt_time(bound) if bound else '-'} | "
                         f"{ratio} | {cpu} | {rel} |")
    lines.append("")
    return lines


def summary(context, by, errors, repetitions):
    lines = ["# stabint benchmark summary\n"]
    host = context.get("host_name", "?")
    lines.append(f"Run {context.get('date', '?')} on {host}: {context.get('num_cpus', '?')} CPUs at "
                 f"{context.get('mhz_per_cpu', '?')} MHz; OpenCL: {context.get('opencl_devices', '?')}; "
                 f"quick mode: {context.get('quick_mode', '?')}. Times are wall-clock per benchmark "
                 f"iteration" + (f", fastest of {repetitions} repetitions" if repetitions > 1 else "") +
                 ".\n")
    lines.append("## Goals\n")
    lines += goal_checks(by)
    lines += iteration_tables(by)
    lines += step_tables(by)
    lines += scaling_table(by)
    lines += solver_table(by)
    if errors:
        skipped = sorted({msg for msg in errors.values()})
        lines.append(f"## Not run\n\n{len(errors)} cases: " + "; ".join(skipped) + "\n")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json", help="benchmark output (--benchmark_out_format=json)")
    ap.add_argument("--charts", default="results/charts", help="directory for scaling.png/.svg")
    ap.add_argument("--summary", default="results/bench_summary.md", help="markdown summary to write")
    args = ap.parse_args()

    context, cases, errors, repetitions = load(args.json)
    by = index(cases)
    for path in draw_charts(by, args.charts):
        print(f"scaling_chart: wrote {path}")
    os.makedirs(os.path.dirname(os.path.abspath(args.summary)), exist_ok=True)
    with open(args.summary, "w") as f:
        f.write(summary(context, by, errors, repetitions))
    print(f"scaling_chart: wrote {args.summary}")


if __name__ == "__main__":
    main()
