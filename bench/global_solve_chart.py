#!/usr/bin/python3
"""Speed against accuracy of the global step: the CHOLMOD factor against the conjugate-gradient
global solve (GlobalSolve::ConjugateGradient), from stabint_bench's JSON output.

    stabint_bench --benchmark_filter='^global_step' --benchmark_repetitions=3 \
        --benchmark_enable_random_interleaving=true --benchmark_out=global_step.json
    /usr/bin/python3 bench/global_solve_chart.py global_step.json [--chart docs/images/global_solve.png]

Takes the fastest repetition of every case. Left panels (global_step/<scene>/<solver>/<backend>):
time of one local/global iteration against the counter position_error (after one frame's BE
solve of 10 iterations, the largest distance from the CPU factor's result over the body's size).
Right panel (global_step_scaling/<tetbar>/...): time per iteration against particles. Prints a
markdown table with the ratio CG / factor per scene and backend.
Use /usr/bin/python3 (Debian's python3-matplotlib).
"""
from collections import defaultdict

from bench_json import chart_main, fastest_repetitions

BACKENDS = ["cpu", "opencl-double", "opencl-float"]
MARKERS = {"cpu": "o", "opencl-double": "s", "opencl-float": "^"}
ERROR_FLOOR = 1e-17  # the CPU factor's own error is 0: drawn at the floor


def load(path):
    """{(kind, scene, solver, backend): (fastest seconds, counters)} over the repetitions."""
    return fastest_repetitions(path, "global_step", 4)


def particles(entry):
    return entry.get("particles", 0.0)


def table(best):
    rows = ["| scene | backend | solver | time / iteration | CG / factor | position error |", "|---|---|---|---:|---:|---:|"]
    groups = defaultdict(dict)
    for (kind, scene, solver, backend), value in best.items():
        groups[(kind, scene, backend)][solver] = value
    order = lambda k: (k[0], particles(next(iter(groups[k].values()))[1]), k[1], BACKENDS.index(k[2]))
    for key in sorted(groups, key=order):
        kind, scene, backend = key
        solvers = groups[key]
        factor = solvers.get("factor")
        for solver in sorted(solvers, key=lambda s: (s != "factor", int(s[2:]) if s.startswith("cg") else 0)):
            seconds, entry = solvers[solver]
            ratio = f"{seconds / factor[0]:.2f}" if factor and solver != "factor" else "-"
            error = entry.get("position_error", float("nan"))
            rows.append(f"| {scene} | {backend} | {solver} | {seconds * 1e3:.3f} ms | {ratio} | {error:.1e} |")
    return "\n".join(rows)


def chart(best, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = sorted({k[1] for k in best if k[0] == "global_step"})
    fig, axes = plt.subplots(1, len(scenes) + 1, figsize=(5.2 * (len(scenes) + 1), 4.4))
    for ax, scene in zip(axes, scenes):
        for backend in BACKENDS:
            points = [(v[0], max(v[1].get("position_error", 0.0), ERROR_FLOOR), k[2])
                      for k, v in best.items() if k[0] == "global_step" and k[1] == scene and k[3] == backend]
            if not points:
                continue
            points.sort(key=lambda p: (p[2] != "factor", int(p[2][2:]) if p[2].startswith("cg") else 0))
            ax.plot([p[0] * 1e3 for p in points], [p[1] for p in points], marker=MARKERS[backend], label=backend)
            for t, e, solver in points:
                ax.annotate(solver, (t * 1e3, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("one local/global iteration (ms)")
        ax.set_ylabel("position error after a BE frame / size")
        ax.set_title(scene)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax = axes[-1]
    for backend in BACKENDS:
        for solver, style in (("factor", "-"), ("cg10", "--")):
            points = sorted((particles(v[1]), v[0]) for k, v in best.items()
                            if k[0] == "global_step_scaling" and k[2] == solver and k[3] == backend)
            if points:
                ax.plot([p[0] for p in points], [p[1] * 1e3 for p in points], style, marker=MARKERS[backend],
                        label=f"{solver} {backend}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("particles (tet bars)")
    ax.set_ylabel("one local/global iteration (ms)")
    ax.set_title("tet bar scaling: factor vs 10 CG iterations")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    chart_main(__doc__, "global_solve.png", load, table, chart)


if __name__ == "__main__":
    main()
