#!/usr/bin/python3
"""Charts and a summary from stabint-study's CSV files.

usage: /usr/bin/python3 bench/study_charts.py [RESULTS_DIR]   (default: results)

Reads RESULTS_DIR/{sweep,stability,energy_tetbar,energy_cloth,accuracy,energy_table,reference,
backend_check}.csv and cloth_still_<integrator>.csv, writes PNG and SVG charts into
RESULTS_DIR/charts/ and RESULTS_DIR/summary.md. A missing CSV skips its chart with a note.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

INTEGRATORS = ["FE", "SE", "BE", "BDF2", "IM", "blend"]
COLORS = {"FE": "#8c564b", "SE": "#9467bd", "BE": "#1f77b4", "BDF2": "#2ca02c", "IM": "#d62728",
          "blend": "#ff7f0e"}
MARKERS = {"FE": "v", "SE": "^", "BE": "s", "BDF2": "D", "IM": "o", "blend": "*"}
VERDICTS = ["stable", "over-damped", "exploded"]
VERDICT_COLORS = ["#4daf4a", "#377eb8", "#e41a1c"]
SCENE_TITLES = {"cloth": "cloth 20x20 (pinned corners)", "tetbar": "tet bar 8x2x2 (pinned at x = 0)",
                "chain": "stiff chain pendulum"}


def read_csv(results, name):
    path = os.path.join(results, name)
    if not os.path.exists(path):
        print(f"study_charts: {path} missing, skipping what needs it")
        return None
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError):
        return float("nan")


def save(fig, charts, name):
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(charts, f"{name}.{ext}"), dpi=130 if ext == "png" else None,
                    bbox_inches="tight")
    plt.close(fig)
    print(f"study_charts: wrote {os.path.join(charts, name)}.png/.svg")


def pareto(points):
    """Non-dominated (time, value) points: nothing else is both faster and more accurate."""
    front = []
    for p in sorted(points):
        if not front or p[1] < front[-1][1]:
            front.append(p)
    return front


def chart_speed_vs_accuracy(results, charts):
    rows = read_csv(results, "sweep.csv")
    if not rows:
        return
    scenes = [s for s in ("cloth", "tetbar") if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(len(scenes), 2, figsize=(13, 5.2 * len(scenes)), squeeze=False)
    backend = rows[0].get("backend", "cpu")
    ref_error = {r["scene"]: num(r, "self_error_m") for r in (read_csv(results, "reference.csv") or [])}
    for si, scene in enumerate(scenes):
        for ci, (key, label) in enumerate((("position_error_m", "position error vs reference, RMS [m]"),
                                           ("drift_rel", "|energy drift| over 2 s [E_avail]"))):
            ax = axes[si][ci]
            everything = []
            exploded = {}
            for integ in INTEGRATORS:
                pts = []
                for r in rows:
                    if r["scene"] != scene or r["integrator"] != integ:
                        continue
                    t, v = num(r, "ms_per_frame"), abs(num(r, key))
                    if r["verdict"] == "exploded" or not math.isfinite(v):
                        exploded[integ] = exploded.get(integ, 0) + 1
                        continue
                    v = max(v, 1e-7)
                    knob = f"k={r['substeps']}" if integ in ("FE", "SE") else f"{r['iterations']} it"
                    gain = num(r, "drift_rel") > 0
                    order = num(r, "substeps") if integ in ("FE", "SE") else num(r, "iterations")
                    pts.append((t, v, knob, gain, order))
                if not pts:
                    continue
                pts.sort(key=lambda p: p[4])  # along the knob: iterations or substeps
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=COLORS[integ], lw=1.4, alpha=0.8)
                for t, v, knob, gain, _ in pts:
                    filled = (key != "drift_rel") or gain
                    ax.plot(t, v, MARKERS[integ], color=COLORS[integ], ms=9 if integ == "blend" else 6,
                            mfc=COLORS[integ] if filled else "white")
                    everything.append((t, v))
                # Label the ends of each line with their knob (iterations or substeps).
                for t, v, knob, _, _ in (pts[0], pts[-1]) if len(pts) > 1 else (pts[0],):
                    ax.annotate(knob, (t, v), textcoords="offset points", xytext=(4, 4), fontsize=7,
                                color=COLORS[integ])
                ax.plot([], [], "-" + MARKERS[integ], color=COLORS[integ], label=integ)
            front = pareto(everything)
            if front:
                ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="black", lw=1.0,
                        ls="--", alpha=0.6)
                ax.plot([p[0] for p in front], [p[1] for p in front], "o", ms=13, mfc="none", mec="black",
                        mew=1.0, alpha=0.7, label="Pareto front")
            if ci == 0 and scene in ref_error:
                ax.axhline(ref_error[scene], color="gray", lw=0.8, ls=":")
                ax.text(0.99, ref_error[scene], "reference: h/16 vs h/8 difference", color="gray", fontsize=7,
                        ha="right", va="bottom", transform=ax.get_yaxis_transform())
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(f"time per frame [ms], {backend} backend")
            ax.set_ylabel(label)
            title = f"{SCENE_TITLES.get(scene, scene)}: {'position error' if ci == 0 else 'energy drift'}"
            ax.set_title(title, fontsize=10)
            ax.grid(True, which="both", alpha=0.25)
            note = ", ".join(f"{k} {n}" for k, n in exploded.items())
            if note:
                ax.text(0.01, 0.01, f"exploded runs not shown: {note}", transform=ax.transAxes, fontsize=7,
                        color="#e41a1c", va="bottom")
            if ci == 1:
                ax.text(0.99, 0.01, "filled = energy gained, hollow = lost", transform=ax.transAxes, fontsize=7,
                        ha="right", va="bottom")
            ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("Speed versus accuracy (h = 1/30 s, 60 frames; implicit: 1-32 iterations, explicit: "
                 "k substeps of h/k)", fontsize=11)
    save(fig, charts, "speed_vs_accuracy")


def chart_stability_map(results, charts):
    rows = read_csv(results, "stability.csv")
    if not rows:
        return
    scenes = [s for s in ("chain", "tetbar") if any(r["scene"] == s for r in rows)]
    cmap = ListedColormap(VERDICT_COLORS)
    fig, axes = plt.subplots(len(scenes), len(INTEGRATORS), figsize=(2.6 * len(INTEGRATORS), 3.1 * len(scenes)),
                             squeeze=False)
    for si, scene in enumerate(scenes):
        srows = [r for r in rows if r["scene"] == scene]
        ks = sorted({num(r, "stiffness") for r in srows})
        hs = sorted({num(r, "h") for r in srows})
        unit = "N/m" if scene == "chain" else "Pa"
        for ii, integ in enumerate(INTEGRATORS):
            ax = axes[si][ii]
            grid = [[float("nan")] * len(hs) for _ in ks]
            text = [[""] * len(hs) for _ in ks]
            for r in srows:
                if r["integrator"] != integ:
                    continue
                ki, hi = ks.index(num(r, "stiffness")), hs.index(num(r, "h"))
                grid[ki][hi] = VERDICTS.index(r["verdict"])
                if r["verdict"] != "exploded":
                    # Energy lost (+) or gained (-) over the run, in % of E_avail.
                    text[ki][hi] = f"{100 * num(r, 'damping_rel'):.0f}%"
            ax.imshow(grid, cmap=cmap, vmin=-0.5, vmax=2.5, origin="lower", aspect="auto")
            for ki in range(len(ks)):
                for hi in range(len(hs)):
                    if text[ki][hi]:
                        ax.text(hi, ki, text[ki][hi], ha="center", va="center", fontsize=7, color="white")
            ax.set_xticks(range(len(hs)))
            ax.set_xticklabels([f"1/{round(1 / h)}" for h in hs], fontsize=7)
            ax.set_yticks(range(len(ks)))
            ax.set_yticklabels([f"{k:.0e}" for k in ks] if ii == 0 else [], fontsize=7)
            if ii == 0:
                ax.set_ylabel(f"{scene}: stiffness [{unit}]", fontsize=8)
            if si == len(scenes) - 1:
                ax.set_xlabel("step h [s]", fontsize=8)
            ax.set_title(f"{integ} ({scene})", fontsize=9)
    steps = rows[0].get("steps", "?")
    fig.legend(handles=[Patch(color=c, label=v) for v, c in zip(VERDICTS, VERDICT_COLORS)], loc="lower center",
               ncol=3, fontsize=9, bbox_to_anchor=(0.5, -0.02))
    fig.suptitle(f"Stability over {steps} steps, 10 iterations (cell text: energy lost, % of E_avail; "
                 "exploded: |H - H0| > 10 E_avail or non-finite; over-damped: lost > 50 %)\n"
                 "stiffness k of the springs (chain) or tets (bar); pins scale with it (chain: k, bar: k times "
                 "the cell size)", fontsize=10)
    fig.tight_layout(rect=(0, 0.03, 1, 0.95))
    save(fig, charts, "stability_map")


def chart_energy_over_time(results, charts):
    bar = read_csv(results, "energy_tetbar.csv")
    cloth = read_csv(results, "energy_cloth.csv")
    if not bar and not cloth:
        return
    fig, axes = plt.subplots(1, 3, figsize=(17, 4.8))
    shown = ["BE", "BDF2", "IM", "blend"]

    def series(rows, integ, key):
        rs = [r for r in rows if r["integrator"] == integ]
        return [num(r, "time") for r in rs], [num(r, key) for r in rs], rs

    if bar:
        for integ in shown:
            t, y, _ = series(bar, integ, "free_end_y")
            if t:
                axes[0].plot(t, y, color=COLORS[integ], lw=1.2, label=integ)
        axes[0].set_title("tet bar: height of the free end", fontsize=10)
        axes[0].set_ylabel("free end y [m] (start 0.125)")
        for integ in shown:
            t, h, rs = series(bar, integ, "H")
            if t:
                h0, ea = h[0], num(rs[0], "E_avail")
                axes[1].plot(t, [(v - h0) / ea for v in h], color=COLORS[integ], lw=1.2, label=integ)
        axes[1].set_title("tet bar: energy H - H0 (H* = H0: no forcing, no damping)", fontsize=10)
        axes[1].set_ylabel("(H - H0) / E_avail")
    if cloth:
        for integ in shown:
            t, h, rs = series(cloth, integ, "H")
            if not t:
                continue
            h0, ea = h[0], num(rs[0], "E_avail")
            axes[2].plot(t, [(v - h0) / ea for v in h], color=COLORS[integ], lw=1.0 if integ == "blend" else 1.2,
                         label=integ, alpha=0.85)
        # IM's energy grows by orders of magnitude: linear within +-1, logarithmic beyond.
        axes[2].set_yscale("symlog", linthresh=1.0)
        axes[2].axhline(0.0, color="black", lw=0.6)
        axes[2].set_title("cloth: energy H - H0 (H* = H0; symmetric log scale beyond +-1)", fontsize=10)
        axes[2].set_ylabel("(H - H0) / E_avail")
    for ax in axes:
        ax.set_xlabel("time [s]  (h = 1/30 s, 10 iterations)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Energy over time (E_avail: energy the scene can turn into motion, H0 minus the static "
                 "equilibrium's potential)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    save(fig, charts, "energy_over_time")


def chart_cloth_still(results, charts):
    stills = []
    for integ in ("BE", "blend"):
        rows = read_csv(results, f"cloth_still_{integ}.csv")
        if rows:
            stills.append((integ, rows))
    if not stills:
        return
    fig = plt.figure(figsize=(6.2 * len(stills), 5.6))
    all_pts = [(num(r, "x"), num(r, "y"), num(r, "z")) for _, rows in stills for r in rows]
    lims = [(min(p[a] for p in all_pts), max(p[a] for p in all_pts)) for a in range(3)]
    for n, (integ, rows) in enumerate(stills):
        nx, ny = int(rows[0]["nx"]), int(rows[0]["ny"])
        frame = rows[0]["frame"]
        grid = {(int(r["i"]), int(r["j"])): r for r in rows}
        # Plot with the simulation's y (up) as the chart's vertical axis.
        X = [[num(grid[(i, j)], "x") for i in range(nx)] for j in range(ny)]
        Y = [[num(grid[(i, j)], "z") for i in range(nx)] for j in range(ny)]
        Z = [[num(grid[(i, j)], "y") for i in range(nx)] for j in range(ny)]
        ax = fig.add_subplot(1, len(stills), n + 1, projection="3d")
        import numpy as np  # matplotlib depends on numpy

        X, Y, Z = np.array(X), np.array(Y), np.array(Z)
        ax.plot_surface(X, Y, Z, cmap="viridis", edgecolor="#333333", linewidth=0.3, antialiased=True,
                        rstride=1, cstride=1, alpha=0.95)
        ax.set_xlim(*lims[0])
        ax.set_ylim(*lims[2])
        ax.set_zlim(*lims[1])
        ax.set_box_aspect((lims[0][1] - lims[0][0], lims[2][1] - lims[2][0], lims[1][1] - lims[1][0]))
        ax.view_init(elev=18, azim=-60)
        ax.set_xlabel("x [m]", fontsize=8)
        ax.set_ylabel("z [m]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(f"{integ}, frame {frame} (t = {int(frame) / 30:.1f} s); vertical axis: y (up) [m]",
                     fontsize=10)
    fig.suptitle("Cloth released 30 degrees below the horizontal, pinned at two corners (h = 1/30 s, "
                 "10 iterations)", fontsize=10)
    save(fig, charts, "cloth_still")


def fmt(v, digits=3):
    if not math.isfinite(v):
        return "inf" if v > 0 else "nan"
    return f"{v:.{digits}g}"


def write_summary(results):
    out = []
    out.append("# stabint study: summary\n")
    out.append("Generated by `bench/study_charts.py` from the CSV files of `stabint-study all`. Energies are "
               "relative to **E_avail** = H0 minus the potential energy of the static equilibrium (the energy "
               "the scene can turn into motion). Verdict: *exploded* = non-finite or max |H - H0| > 10 E_avail; "
               "*over-damped* = lost more than 50 % of E_avail; else *stable*. Timings are wall clock on the "
               "machine that ran the study (shared, so noisy).\n")
    acc = read_csv(results, "accuracy.csv")
    if acc:
        out.append("## Real-time setting: h = 1/30 s, 10 iterations, 60 frames (2 s) against the reference\n")
        out.append(f"Backend: {acc[0].get('backend', 'cpu')}.\n")
        out.append("| scene | integrator | ms/frame | position error [m] | energy drift [E_avail] | "
                   "energy lost (damping) [E_avail] | verdict |")
        out.append("|---|---|---:|---:|---:|---:|---|")
        for r in acc:
            out.append(f"| {r['scene']} | {r['integrator']} | {fmt(num(r, 'ms_per_frame'))} | "
                       f"{fmt(num(r, 'position_error_m'))} | {fmt(num(r, 'drift_rel'))} | "
                       f"{fmt(num(r, 'damping_rel'))} | {r['verdict']} |")
        out.append("")
    table = read_csv(results, "energy_table.csv")
    if table:
        out.append("## Energy behaviour over 300 frames (10 s), h = 1/30 s, 10 iterations\n")
        out.append("| scene | integrator | ms/frame | drift [E_avail] | max abs(H - H*) [E_avail] | H min .. max | "
                   "blew up at | blend IM/BE/FE | verdict |")
        out.append("|---|---|---:|---:|---:|---|---:|---|---|")
        for r in table:
            blow = r["blew_up_frame"] if r["blew_up_frame"] != "-1" else "-"
            branches = (f"{r['branch_IM']}/{r['branch_BE']}/{r['branch_FE']}"
                        if r["integrator"].startswith("blend") else "-")
            out.append(f"| {r['scene']} | {r['integrator']} | {fmt(num(r, 'ms_per_frame'))} | "
                       f"{fmt(num(r, 'drift_rel'))} | {fmt(num(r, 'max_dev_target_rel'))} | "
                       f"{fmt(num(r, 'H_min'))} .. {fmt(num(r, 'H_max'))} | {blow} | {branches} | {r['verdict']} |")
        out.append("")
    sweep = read_csv(results, "sweep.csv")
    if sweep:
        out.append("## Speed versus accuracy: cheapest non-exploded setting per integrator and its most accurate one\n")
        out.append("| scene | integrator | cheapest non-exploded setting | ms/frame | error [m] | most accurate setting | "
                   "ms/frame | error [m] |")
        out.append("|---|---|---|---:|---:|---|---:|---:|")
        for scene in ("cloth", "tetbar"):
            for integ in INTEGRATORS:
                rs = [r for r in sweep if r["scene"] == scene and r["integrator"] == integ
                      and r["verdict"] != "exploded" and math.isfinite(num(r, "position_error_m"))]
                if not rs:
                    out.append(f"| {scene} | {integ} | exploded at every setting tried | | | | | |")
                    continue
                knob = (lambda r: f"{r['substeps']} substeps") if integ in ("FE", "SE") else \
                    (lambda r: f"{r['iterations']} iteration{'s' if r['iterations'] != '1' else ''}")
                cheap = min(rs, key=lambda r: num(r, "ms_per_frame"))
                best = min(rs, key=lambda r: num(r, "position_error_m"))
                out.append(f"| {scene} | {integ} | {knob(cheap)} | {fmt(num(cheap, 'ms_per_frame'))} | "
                           f"{fmt(num(cheap, 'position_error_m'))} | {knob(best)} | "
                           f"{fmt(num(best, 'ms_per_frame'))} | {fmt(num(best, 'position_error_m'))} |")
        out.append("")
    stab = read_csv(results, "stability.csv")
    if stab:
        out.append("## Stability grid (stable / over-damped / exploded cells of stiffness x step size)\n")
        out.append("| scene | " + " | ".join(INTEGRATORS) + " |")
        out.append("|---|" + "---|" * len(INTEGRATORS))
        for scene in ("chain", "tetbar"):
            cells = []
            for integ in INTEGRATORS:
                rs = [r for r in stab if r["scene"] == scene and r["integrator"] == integ]
                cells.append("/".join(str(sum(r["verdict"] == v for r in rs)) for v in VERDICTS))
            out.append(f"| {scene} | " + " | ".join(cells) + " |")
        out.append("")
    ref = read_csv(results, "reference.csv")
    if ref:
        out.append("## Reference trajectories\n")
        for r in ref:
            out.append(f"- {r['scene']}: implicit midpoint with h/{r['substeps']}, local/global iterations to a "
                       f"1e-10 relative objective change, {r['frames']} frames; finite; max |H - H0| = "
                       f"{fmt(100 * num(r, 'max_energy_dev_rel'))} % of E_avail; difference to the same run with "
                       f"h/{int(r['substeps']) // 2}: {fmt(num(r, 'self_error_m'))} m RMS.")
        out.append("")
    chk = read_csv(results, "backend_check.csv")
    if chk:
        out.append("## OpenCL backend against the CPU reference\n")
        if chk[0]["status"] == "skipped":
            out.append("Skipped: no OpenCL device.\n")
        else:
            implicit = [r for r in chk if r["integrator"] not in ("FE", "SE")]
            dx = max(num(r, "max_position_diff_m") for r in implicit)
            rel = max(num(r, "max_relative_position_diff") for r in chk)
            out.append(f"Device: {chk[0]['opencl_device']}. Implicit integrators and the blend, "
                       f"{chk[0]['frames']} frames on chain, cloth and tet bar: max position difference "
                       f"{fmt(dx)} m; all integrators, relative to the state's size: {fmt(rel)}. The CPU "
                       "numbers above stand for both backends.\n")
    charts = os.path.join(results, "charts")
    out.append("## Charts\n")
    for name, what in (("speed_vs_accuracy", "time per frame against position error and energy drift, Pareto "
                        "front circled"),
                       ("stability_map", "verdict per stiffness and step size, per integrator"),
                       ("energy_over_time", "tet bar free-end height and energy; cloth energy"),
                       ("cloth_still", "the cloth at the same frame with BE and the blend")):
        if os.path.exists(os.path.join(charts, name + ".png")):
            out.append(f"- `charts/{name}.png` (and .svg): {what}")
    path = os.path.join(results, "summary.md")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"study_charts: wrote {path}")


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else "results"
    charts = os.path.join(results, "charts")
    os.makedirs(charts, exist_ok=True)
    chart_speed_vs_accuracy(results, charts)
    chart_stability_map(results, charts)
    chart_energy_over_time(results, charts)
    chart_cloth_still(results, charts)
    write_summary(results)


if __name__ == "__main__":
    main()
