#!/usr/bin/python3
"""Many scenes at once (issue 11, item 3): one BatchSimulator against one Simulator per scene,
from stabint_bench's JSON output.

    stabint_bench --benchmark_filter='^batch/' --benchmark_repetitions=3 \
        --benchmark_enable_random_interleaving=true --benchmark_format=json --benchmark_out=batch.json
    /usr/bin/python3 bench/batch_chart.py batch.json [--chart docs/images/batch.png]

Takes the fastest repetition of every case batch/<scene>/<integrator>/<backend>/<batch|separate>/scenes:N.
Prints a markdown table per scene, integrator and backend: time per batch step, per scene-step,
and the ratios the goal names (OpenCL separate / OpenCL batch >= 20, CPU separate / OpenCL batch
> 1) with CPU separate / CPU batch. The chart shows the time per scene-step of the batch and of the
separate simulators per case, with the goal's line at 1/20 of each OpenCL backend's separate time.
Use /usr/bin/python3 (Debian's python3-matplotlib).
"""
from collections import defaultdict

from bench_json import chart_main, fastest_repetitions

BACKENDS = ["cpu", "opencl-double", "opencl-float"]
INTEGRATORS = ["BE", "blend"]
GOAL = 20.0  # issue 11 item 3: the OpenCL batch at least 20x one OpenCL Simulator per scene
SCENE_NAMES = {"chain": "chains", "cloth10": "cloths 10 x 10"}


def load(path):
    """{(scene, integrator, backend, count): {variant: (seconds per batch step, entry)}}."""
    cases = defaultdict(dict)
    for (_, scene, integrator, backend, variant, scenes), value in fastest_repetitions(path, "batch", 6).items():
        cases[(scene, integrator, backend, int(scenes.split(":")[1]))][variant] = value
    return cases


def ratio(a, b):
    return f"{a / b:.1f}x" if a and b else "-"


def seconds(cases, key, variant):
    value = cases.get(key, {}).get(variant)
    return value[0] if value else None


def table(cases):
    rows = [
        "| scenes | integrator | backend | batch step | separate step | separate / batch | CPU separate / batch |"
        " IM share (batch, separate) |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    order = lambda k: (k[0], k[3], INTEGRATORS.index(k[1]), BACKENDS.index(k[2]))
    for key in sorted(cases, key=order):
        scene, integrator, backend, count = key
        batch, separate = seconds(cases, key, "batch"), seconds(cases, key, "separate")
        cpu_separate = seconds(cases, (scene, integrator, "cpu", count), "separate")
        fmt = lambda s: f"{s * 1e3:,.1f} ms" if s else "-"
        im = lambda v: f"{cases[key][v][1]['im_fraction']:.2f}" if v in cases[key] and "im_fraction" in cases[key][v][1] else "-"
        rows.append(f"| {count:,} {SCENE_NAMES.get(scene, scene)} | {integrator} | {backend} | {fmt(batch)} | "
                    f"{fmt(separate)} | {ratio(separate, batch)} | {ratio(cpu_separate, batch)} | "
                    f"{im('batch')}, {im('separate')} |")
    return "\n".join(rows)


def chart(cases, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = sorted({(k[0], k[3]) for k in cases if k[2] != "cpu"})
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 4.6), squeeze=False)
    for ax, (scene, count) in zip(axes[0], panels):
        labels, goal_drawn = [], False
        for i, (integrator, backend) in enumerate((i, b) for i in INTEGRATORS for b in BACKENDS):
            key = (scene, integrator, backend, count)
            batch, separate = seconds(cases, key, "batch"), seconds(cases, key, "separate")
            if batch is None and separate is None:
                continue
            x = len(labels)
            for offset, value, color, name in ((-0.2, separate, "tab:gray", "separate"),
                                               (0.2, batch, "tab:blue", "batch")):
                if value:
                    ax.bar(x + offset, value / count * 1e3, 0.4, color=color, label=name if x == 0 else None)
            cpu_separate = seconds(cases, (scene, integrator, "cpu", count), "separate")
            if backend != "cpu" and separate:
                ax.hlines(separate / GOAL / count * 1e3, x - 0.45, x + 0.45, colors="tab:red", linestyles="--",
                          label=None if goal_drawn else f"goal: OpenCL separate / {GOAL:.0f}")
                if cpu_separate:
                    ax.hlines(cpu_separate / count * 1e3, x - 0.45, x + 0.45, colors="tab:green", linestyles=":",
                              label=None if goal_drawn else "goal: CPU separate")
                goal_drawn = True
            labels.append(f"{integrator}\n{backend}")
        ax.set_xticks(range(len(labels)))
        ax.set_xticklabels(labels, fontsize=7)
        ax.set_yscale("log")
        ax.set_ylabel("time per scene-step (ms)")
        ax.set_title(f"{count:,} {SCENE_NAMES.get(scene, scene)}")
        ax.grid(True, axis="y", which="both", alpha=0.3)
    handles, names = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, names, loc="lower center", ncol=len(names), fontsize=8)
    fig.suptitle("one BatchSimulator vs one Simulator per scene (fastest of 3 repetitions)", fontsize=10)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    fig.savefig(path, dpi=110)


def main():
    chart_main(__doc__, "batch.png", load, table, chart)


if __name__ == "__main__":
    main()
