#!/usr/bin/python3
"""Charts and a summary from stabint-study's CSV files.

usage: /usr/bin/python3 bench/study_charts.py [RESULTS_DIR]   (default: results)

Reads RESULTS_DIR/{sweep,stability,energy_tetbar,energy_cloth,accuracy,energy_table,reference,
backend_check,motion,motion_series,motion_reference,moving_pin}.csv and cloth_still_<integrator>.csv,
writes PNG and SVG charts into RESULTS_DIR/charts/ and RESULTS_DIR/summary.md, and prints the motion
table (issue 8's targets). A missing CSV skips its chart with a note.
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
# Series with another solver than the default (L-BFGS): plain iterations ("<integrator>+PD"),
# Anderson ("+AA"), Newton-CG ("+NT").
ACCELERATED = ["BE+PD", "blend+PD", "BE+AA", "blend+AA", "BE+NT", "blend+NT"]
COLORS = {"FE": "#8c564b", "SE": "#9467bd", "BE": "#1f77b4", "BDF2": "#2ca02c", "IM": "#d62728",
          "blend": "#ff7f0e", "BE+AA": "#17becf", "blend+AA": "#e377c2",
          "BE+PD": "#7f7f7f", "blend+PD": "#bcbd22", "BE+NT": "#e7ba52", "blend+NT": "#393b79"}
MARKERS = {"FE": "v", "SE": "^", "BE": "s", "BDF2": "D", "IM": "o", "blend": "*", "BE+AA": "P", "blend+AA": "X", "BE+PD": "p",
           "blend+PD": "h", "BE+NT": "<", "blend+NT": ">"}
VERDICTS = ["stable", "over-damped", "exploded"]
VERDICT_COLORS = ["#4daf4a", "#377eb8", "#e41a1c"]
SCENE_TITLES = {"cloth": "cloth 20x20 (pinned corners)", "tetbar": "tet bar 8x2x2 (pinned at x = 0)",
                "chain": "stiff chain pendulum",
                "cloth_triangles": "cloth 20x20 of triangle strain + bending hinges"}


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


def chart_speed_vs_accuracy_full(results, charts):
    """The appendix: every series of the sweep on every panel (error, energy drift, error over
    0-1 s) for every scene."""
    rows = read_csv(results, "sweep.csv")
    if not rows:
        return
    scenes = [s for s in ("cloth", "cloth_triangles", "tetbar") if any(r["scene"] == s for r in rows)]
    # Panels: error against the IM h/16 reference over 2 s, energy drift, and (when the sweep has
    # it) the RMS error over 0-1 s against the small-step motion reference (issue 8).
    panels = [("position_error_m", "position error vs reference, RMS [m]", "position error"),
              ("drift_rel", "|energy drift| over 2 s [E_avail]", "energy drift")]
    if "rms_0_1s_m" in rows[0]:
        panels.append(("rms_0_1s_m", "RMS error over 0-1 s vs small-step reference [m]",
                       "error over 0-1 s vs small-step reference"))
    fig, axes = plt.subplots(len(scenes), len(panels), figsize=(6.5 * len(panels), 5.2 * len(scenes)),
                             squeeze=False)
    backend = rows[0].get("backend", "cpu")
    # The median frame time when the sweep has it: robust to stalls on a shared machine.
    time_key = "ms_per_frame_median" if "ms_per_frame_median" in rows[0] else "ms_per_frame"
    ref_error = {r["scene"]: num(r, "self_error_m") for r in (read_csv(results, "reference.csv") or [])}
    motion_ref = {r["scene"]: r for r in (read_csv(results, "motion_reference.csv") or [])}
    for si, scene in enumerate(scenes):
        for ci, (key, label, what) in enumerate(panels):
            ax = axes[si][ci]
            everything = []
            exploded = {}
            for integ in INTEGRATORS + ACCELERATED:
                pts = []
                for r in rows:
                    if r["scene"] != scene or r["integrator"] != integ:
                        continue
                    t, v = num(r, time_key), abs(num(r, key))
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
            if key == "rms_0_1s_m" and scene in motion_ref:
                m = motion_ref[scene]
                ax.axhline(num(m, "self_rms_0_1s_m"), color="gray", lw=0.8, ls=":")
                ax.text(0.99, num(m, "self_rms_0_1s_m"), f"reference {m['method']}: difference to half the steps",
                        color="gray", fontsize=7, ha="right", va="bottom", transform=ax.get_yaxis_transform())
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(f"{'median ' if time_key.endswith('median') else ''}time per frame [ms], {backend} backend")
            ax.set_ylabel(label)
            title = f"{SCENE_TITLES.get(scene, scene)}: {what}"
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
    save(fig, charts, "speed_vs_accuracy_full")


# The readable figure's series: the integrators with the default solver, plain local/global
# iterations of the blend (the paper's solver) and symplectic Euler's substeps (the explicit
# alternative); the other solvers are in the appendix figure.
FRONT_SERIES = ["SE", "BE", "BDF2", "IM", "blend+PD", "blend"]


def chart_speed_vs_accuracy(results, charts):
    """One question, one figure: per scene, which method gives the least error for the time. Each
    series is drawn along its own Pareto front (the budgets no other budget of it beats in both
    time and error), the front of all of them dashed, and the default (the blend, L-BFGS, 10
    iterations) ringed."""
    rows = read_csv(results, "sweep.csv")
    if not rows:
        return
    scenes = [s for s in ("cloth", "cloth_triangles", "tetbar") if any(r["scene"] == s for r in rows)]
    key = "rms_0_1s_m" if "rms_0_1s_m" in rows[0] else "position_error_m"
    label = ("RMS error over 0-1 s vs a small-step reference [m]" if key == "rms_0_1s_m"
             else "RMS position error vs reference [m]")
    time_key = "ms_per_frame_median" if "ms_per_frame_median" in rows[0] else "ms_per_frame"
    fig, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 4.6), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        everything, default = [], None
        for series in FRONT_SERIES:
            pts = []
            for r in rows:
                if r["scene"] != scene or r["integrator"] != series or r["verdict"] == "exploded":
                    continue
                t, v = num(r, time_key), abs(num(r, key))
                if math.isfinite(t) and math.isfinite(v):
                    pts.append((t, max(v, 1e-7)))
                    if series == "blend" and r.get("iterations") == "10":
                        default = (t, max(v, 1e-7))
            front = pareto(pts)
            if not front:
                continue
            everything += pts
            ax.plot([p[0] for p in front], [p[1] for p in front], "-" + MARKERS[series], color=COLORS[series],
                    ms=8 if series == "blend" else 5, lw=1.6 if series == "blend" else 1.1,
                    label=series if series != "blend" else "blend (default solver)")
        overall = pareto(everything)
        if overall:
            ax.step([p[0] for p in overall], [p[1] for p in overall], where="post", color="black", lw=0.9, ls="--",
                    alpha=0.6, label="best of all")
        if default:
            ax.plot(*default, "o", ms=16, mfc="none", mec="black", mew=1.6)
            ax.annotate("default", default, textcoords="offset points", xytext=(10, -14), fontsize=9)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(f"{'median ' if time_key.endswith('median') else ''}ms per frame")
        ax.set_title(SCENE_TITLES.get(scene, scene), fontsize=10)
        ax.grid(True, which="both", alpha=0.25)
    axes[0][0].set_ylabel(label)
    axes[0][-1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Least error for the time (h = 1/30 s; each method along its own best budgets; "
                 "full grid: speed_vs_accuracy_full.png)", fontsize=10)
    fig.tight_layout()
    save(fig, charts, "speed_vs_accuracy")


def chart_stability_map(results, charts):
    rows = read_csv(results, "stability.csv")
    if not rows:
        return
    scenes = [s for s in ("chain", "cloth_triangles", "tetbar") if any(r["scene"] == s for r in rows)]
    cmap = ListedColormap(VERDICT_COLORS)
    fig, axes = plt.subplots(len(scenes), len(INTEGRATORS), figsize=(2.6 * len(INTEGRATORS), 3.1 * len(scenes)),
                             squeeze=False)
    for si, scene in enumerate(scenes):
        srows = [r for r in rows if r["scene"] == scene]
        ks = sorted({num(r, "stiffness") for r in srows})
        hs = sorted({num(r, "h") for r in srows})
        unit = "Pa" if scene == "tetbar" else "N/m"
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
                 "stiffness k of the springs (chain), triangle strain (cloth) or tets (bar); pins scale with it "
                 "(chain and cloth: k, bar: k times the cell size)", fontsize=10)
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


def energy_books(ax, rs, title, series):
    """One integrator's energy terms over time: H and H* relative to H(0), the others as they are,
    each (key, label, sign, style) drawn with the sign it enters H* with."""
    t = [num(r, "time") for r in rs]
    h0 = num(rs[0], "H")
    for key, label, sign, style in series:
        base = h0 if key in ("H", "H_target") else 0.0
        ax.plot(t, [sign * (num(r, key) - base) for r in rs], label=label, **style)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("time [s]  (h = 1/30 s, 10 iterations)")
    ax.set_ylabel("energy relative to H(0) [J]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)


def chart_interaction(results, charts):
    rows = read_csv(results, "interaction.csv")
    if not rows:
        return
    bounce = read_csv(results, "bounce.csv")
    shown = [i for i in ("BE", "BDF2", "blend") if any(r["integrator"] == i for r in rows)]
    n_rows = 2 if bounce else 1
    fig, grid = plt.subplots(n_rows, len(shown) + 1, figsize=(5.2 * (len(shown) + 1), 4.6 * n_rows), squeeze=False)
    axes = grid[0]
    for ax, integ in zip(axes, shown):
        rs = [r for r in rows if r["integrator"] == integ]
        energy_books(ax, rs, f"{integ}: energy books of a grab-drag-release",
                     (("H", "H", 1.0, dict(color=COLORS[integ], lw=1.4)),
                      ("H_target", "H* (target)", 1.0, dict(color="black", lw=1.0, ls="--")),
                      ("work", "hand's work (cumulative)", 1.0, dict(color="#7f7f7f", lw=1.0)),
                      ("kinetic", "K", 1.0, dict(color="#9467bd", lw=0.9))))
        held = [num(r, "time") for r in rs if r["held"] == "1"]
        if held:
            ax.axvspan(min(held), max(held), color="#ffdd88", alpha=0.35, lw=0, label="corner held")
            ax.legend(fontsize=7)
    ax = axes[-1]
    for integ in shown:
        rs = [r for r in rows if r["integrator"] == integ]
        ax.plot([num(r, "time") for r in rs], [num(r, "kinetic") for r in rs], color=COLORS[integ], lw=1.2,
                label=integ)
    ax.set_yscale("log")
    ax.set_title("kinetic energy: does the cloth keep swinging after the release?", fontsize=10)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("K [J]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    title = ("Interaction (stabint-study interaction). Top: a hand grabs the free corner of a 20 x 20 cloth at "
             "0.5 s, drags it for 1 s, lets go at 2 s.")
    if bounce:
        axes = grid[1]
        for ax, integ in zip(axes, shown):
            rs = [r for r in bounce if r["integrator"] == integ]
            # H* = H0 - friction + projection: both terms drawn with the sign they enter H* with.
            energy_books(ax, rs, f"{integ}: energy books of a bounce on the ground",
                         (("H", "H", 1.0, dict(color=COLORS[integ], lw=1.4)),
                          ("H_target", "H* (target)", 1.0, dict(color="black", lw=1.0, ls="--")),
                          ("friction", "- friction (cumulative)", -1.0, dict(color="#7f7f7f", lw=1.0)),
                          ("projection", "final projection (cumulative)", 1.0,
                           dict(color="#d62728", lw=0.9, ls=":")),
                          ("kinetic", "K", 1.0, dict(color="#9467bd", lw=0.9))))
        ax = axes[-1]
        for integ in shown:
            rs = [r for r in bounce if r["integrator"] == integ]
            ax.plot([num(r, "time") for r in rs], [num(r, "height") for r in rs], color=COLORS[integ], lw=1.2,
                    label=integ)
        ax.axhline(0.5, color="black", lw=0.6, ls="--", label="drop height")
        ax.set_title("bar centre above its resting height", fontsize=10)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("height [m]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        title += ("\nBottom: a free tet bar (62.5 kg) dropped from 0.5 m onto the ground (the default contact, "
                  "friction 0.3).")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.95 if bounce else 0.93))
    save(fig, charts, "interaction")


def chart_cloth_still(results, charts):
    """The main job's cloth at the same frame with BE and the blend, rendered with POV-Ray
    (bench/povray_render.py, as the teaser): smooth normals, key and fill light, the shadow on
    a ground plane, the cloth's two sides in two colours."""
    import tempfile

    import numpy as np  # matplotlib depends on numpy
    from PIL import Image

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import povray_render as pr

    stills = []
    for integ in ("BE", "blend"):
        rows = read_csv(results, f"cloth_still_{integ}.csv")
        if rows:
            stills.append((integ, rows))
    if not stills:
        return
    if not pr.available():
        print(f"study_charts: cloth_still skipped: {pr.POVRAY} missing (scripts/install-deps.sh)")
        return
    nx, ny = int(stills[0][1][0]["nx"]), int(stills[0][1][0]["ny"])
    frame = stills[0][1][0]["frame"]
    # The grid's particles in row-major order j*nx + i, two triangles per cell, wound as the
    # teaser's cloth, so the side facing the camera is blue in both pictures.
    ij = np.array([(j, i) for j in range(ny - 1) for i in range(nx - 1)])
    c = ij[:, 0] * nx + ij[:, 1]
    triangles = np.concatenate([np.stack([c, c + nx + 1, c + 1], 1), np.stack([c, c + nx, c + nx + 1], 1)])
    xs = []
    for _, rows in stills:
        x = np.zeros((nx * ny, 3))
        for r in rows:
            x[int(r["j"]) * nx + int(r["i"])] = (num(r, "x"), num(r, "y"), num(r, "z"))
        xs.append(x[None])
    direction = np.array([-0.35, -0.3, -1.0])
    right = np.cross(direction / np.linalg.norm(direction), [0.0, 1.0, 0.0])
    placed = pr.side_by_side(xs, right / np.linalg.norm(right), 0.15)
    everything = np.concatenate(placed)
    view = pr.View(direction, everything, float(everything[..., 1].min()) - 0.08, 1300, 560, antialias=0.1)
    with tempfile.TemporaryDirectory(prefix="stabint-cloth-") as tmp:
        png = os.path.join(tmp, "still.png")
        pr.render(view, [[(p[0], triangles, (0.30, 0.52, 0.75), (0.88, 0.60, 0.30)) for p in placed]], [png])
        image = np.asarray(Image.open(png).convert("RGB"))
    fig, ax = plt.subplots(figsize=(12.0, 5.6))
    ax.imshow(image, interpolation="lanczos")
    ax.set_axis_off()
    names = {"BE": "backward Euler", "blend": "energy-tracking blend"}
    for (integ, _), p in zip(stills, placed):
        ax.text(pr.image_x(view, p[0].mean(axis=0)) * image.shape[1], 10, names[integ], ha="center", va="top",
                fontsize=12)
    ax.set_title(f"Cloth released 30 degrees below the horizontal, pinned at two corners (h = 1/30 s, "
                 f"10 iterations): frame {frame} (t = {int(frame) / 30:.1f} s)", fontsize=10)
    save(fig, charts, "cloth_still")


MOTION_SHOWN = ["BE", "BDF2", "IM", "blend"]


def chart_motion(results, charts):
    """Motion against the small-step reference: the cloth's centre-of-mass path and kinetic energy,
    every run's mean K against its flicker (the frozen and jittery regions shaded), and the stiff
    cloth's fall."""
    series = read_csv(results, "motion_series.csv")
    motion = read_csv(results, "motion.csv")
    if not series and not motion:
        return
    fig, axes = plt.subplots(2, 2, figsize=(14, 9.5))

    exploded_at = {(r["scene"], r["integrator"]): num(r, "exploded_at_s") for r in (motion or [])
                   if "exploded_at_s" in r}

    def lines(ax, scene, key, log=False):
        for integ in ["reference"] + MOTION_SHOWN:
            # A run is drawn until it explodes (IM on the cloth at about 3 s): after that its
            # curve only sets the axis range.
            end = exploded_at.get((scene, integ), math.inf)
            end = end if math.isfinite(end) else math.inf
            rs = [r for r in series if r["scene"] == scene and r["integrator"] == integ and num(r, "time") <= end]
            if not rs:
                continue
            if math.isfinite(end):
                ax.annotate(f"{integ} exploded", (num(rs[-1], "time"), num(rs[-1], key)), fontsize=7,
                            color=COLORS[integ], textcoords="offset points", xytext=(3, 3))
            t = [num(r, "time") for r in rs]
            y = [max(num(r, key), 1e-12) if log else num(r, key) for r in rs]
            ax.plot(t, y, color="black" if integ == "reference" else COLORS[integ],
                    lw=1.8 if integ == "reference" else 1.0, alpha=0.9, label=integ)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        if log:
            ax.set_yscale("log")

    if series:
        method = {r["scene"]: r["method"] for r in (read_csv(results, "motion_reference.csv") or [])}
        lines(axes[0][0], "cloth", "com_y")
        axes[0][0].set_title(f"cloth: centre of mass height (reference: {method.get('cloth', '?')})", fontsize=10)
        axes[0][0].set_ylabel("y of the centre of mass [m]")
        lines(axes[0][1], "cloth", "kinetic", log=True)
        axes[0][1].set_title("cloth: kinetic energy per frame (log scale)", fontsize=10)
        axes[0][1].set_ylabel("K [J]")
        axes[0][1].set_ylim(bottom=1e-5)  # frame 0 is the release from rest (K = 0)
        lines(axes[1][1], "cloth_stiff", "com_y")
        axes[1][1].set_xlim(0.0, 1.0)  # the reference covers 1 s; the runs go on for 10
        axes[1][1].set_title(f"stiff cloth (springs 1e6 N/m, h = 1/15 s): centre of mass height "
                             f"(reference {method.get('cloth_stiff', '?')}, 1 s)", fontsize=10)
        axes[1][1].set_ylabel("y of the centre of mass [m]")
        for ax in (axes[0][0], axes[0][1], axes[1][1]):
            ax.set_xlabel("time [s]  (10 iterations)")
    ax = axes[1][0]
    if motion:
        pts = [r for r in motion if r["integrator"] in INTEGRATORS and r["energy_verdict"] != "exploded"
               and math.isfinite(num(r, "mean_K_ratio")) and math.isfinite(num(r, "flicker"))]
        # Axes clipped to where the verdicts are decided; a point beyond shows on the edge with
        # its value.
        ycap = 30.0
        xs = [max(num(r, "mean_K_ratio"), 1e-4) for r in pts]
        ys = [min(max(num(r, "flicker"), 1.0), ycap) for r in pts]
        xmax, ymax = max(xs + [10.0]) * 1.5, ycap * 1.2
        for r, x in zip(pts, xs):
            if num(r, "flicker") > ycap:
                ax.annotate(f"flicker {fmt(num(r, 'flicker'), 2)}", (x, ycap), textcoords="offset points",
                            xytext=(4, -10), fontsize=7, color=COLORS[r["integrator"]])
        ax.axvspan(1e-4, 0.3, color="#377eb8", alpha=0.12, label="frozen (mean K < 0.3 x reference)")
        ax.axhspan(1.5, ymax, color="#e41a1c", alpha=0.10, label="jittery (flicker > 1.5)")
        for r, x, y in zip(pts, xs, ys):
            ax.plot(x, y, MARKERS[r["integrator"]], color=COLORS[r["integrator"]], ms=9)
            ax.annotate(r["scene"], (x, y), textcoords="offset points", xytext=(4, 3), fontsize=7)
        for integ in INTEGRATORS:
            if any(r["integrator"] == integ for r in pts):
                ax.plot([], [], MARKERS[integ], color=COLORS[integ], label=integ)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(1e-4, xmax)
        ax.set_ylim(0.9, ymax)
        ax.axvline(1.0, color="gray", lw=0.8, ls=":")
        ax.set_xlabel("mean K over the K window / reference's (5-10 s; stiff cloth 0.5-1 s)")
        ax.set_ylabel("flicker: median of max(K_i+1/K_i, K_i/K_i+1)")
        ax.set_title("every non-exploded run: motion kept against flicker", fontsize=10)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=7, loc="center right")
    fig.suptitle("Motion against the small-step reference (h = 1/30 s unless said, 10 iterations)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    save(fig, charts, "motion")


def interpolate_at_time(points, t):
    """log-log interpolation of (ms per frame, error) points at time t; None outside their range."""
    pts = sorted((p for p in points if p[0] > 0 and math.isfinite(p[1]) and p[1] > 0), key=lambda p: p[0])
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if t0 <= t <= t1:
            w = 0.0 if t1 == t0 else (math.log(t) - math.log(t0)) / (math.log(t1) - math.log(t0))
            return math.exp((1 - w) * math.log(e0) + w * math.log(e1))
    return None


def equal_time_errors(sweep, scene="cloth", budget="10"):
    """RMS error over 0-1 s of each implicit integrator at the blend's time per frame at `budget`
    iterations, read off each integrator's iteration-budget curve of the same sweep."""
    if not sweep or "rms_0_1s_m" not in sweep[0]:
        return {}, None
    blend = [r for r in sweep if r["scene"] == scene and r["integrator"] == "blend" and r["iterations"] == budget]
    if not blend:
        return {}, None
    time_key = "ms_per_frame_median" if "ms_per_frame_median" in sweep[0] else "ms_per_frame"
    t = num(blend[0], time_key)
    out = {}
    for integ in ("BE", "BDF2", "IM", "blend"):
        pts = [(num(r, time_key), num(r, "rms_0_1s_m")) for r in sweep
               if r["scene"] == scene and r["integrator"] == integ and r["verdict"] != "exploded"]
        out[integ] = num(blend[0], "rms_0_1s_m") if integ == "blend" else interpolate_at_time(pts, t)
    return out, t


def motion_table(results):
    """The compact motion table of issue 8's targets, as markdown lines (integrators as columns)."""
    motion = read_csv(results, "motion.csv")
    if not motion:
        return []
    cols = INTEGRATORS + [c for c in ("blend+PD", "blend+AA", "blend+NT") if any(r["integrator"] == c for r in motion)] + ["reference"]
    rows = {(r["scene"], r["integrator"]): r for r in motion}

    def line(label, scene, key, digits=3, scale=1.0, until=math.inf):
        """One measure per integrator; `until`: the end of the measure's window [s]. A run that
        exploded before it shows "exploded": its numbers say only how fast it blew up."""
        cells = []
        for c in cols:
            r = rows.get((scene, c))
            if r is None:
                cells.append("")
                continue
            v = num(r, key) * scale
            exploded_at = num(r, "exploded_at_s") if "exploded_at_s" in r else math.inf
            if r["energy_verdict"] == "exploded" and not exploded_at > until and not key.startswith("ms_per"):
                cells.append("exploded")
            else:
                cells.append(fmt(v, digits) if math.isfinite(v) else "-")
        return f"| {label} | " + " | ".join(cells) + " |"

    def verdicts(label, scene):
        return f"| {label} | " + " | ".join(rows[(scene, c)]["verdict"] if (scene, c) in rows and c != "reference"
                                            else "" for c in cols) + " |"

    out = ["| scene: measure | " + " | ".join(cols) + " |", "|---|" + "---:|" * len(cols)]
    out.append(line("cloth: RMS error 0-0.5 s [m]", "cloth", "rms_0_0.5s_m", until=0.5))
    out.append(line("cloth: RMS error 0-1 s [m]", "cloth", "rms_0_1s_m", until=1.0))
    equal, t = equal_time_errors(read_csv(results, "sweep.csv"))
    if equal:
        cells = [fmt(equal[c]) if equal.get(c) is not None else ("" if c not in equal else "out of range")
                 for c in cols]
        out.append(f"| cloth: RMS error 0-1 s at the blend's median {fmt(t)} ms/frame (sweep, interpolated) [m] | " + " | ".join(cells)
                   + " |")
    if "swing_period_s" in motion[0]:
        out.append(line("cloth: swing period of the centre of mass [s]", "cloth", "swing_period_s"))
    out.append(line("cloth: mean K 5-10 s [J]", "cloth", "mean_K_J"))
    out.append(line("cloth: mean K 5-10 s / reference's", "cloth", "mean_K_ratio"))
    out.append(line("cloth: flicker of K", "cloth", "flicker"))
    out.append(line("cloth: max abs(H - H*) / E_avail", "cloth", "max_dev_target_rel"))
    time_key = "ms_per_frame_median" if "ms_per_frame_median" in motion[0] else "ms_per_frame"
    out.append(line("cloth: ms/frame (median)", "cloth", time_key))
    be = rows.get(("cloth", "BE"))
    if be:
        out.append("| cloth: time per frame / BE's | " + " | ".join(
            fmt(num(rows[("cloth", c)], time_key) / num(be, time_key)) if ("cloth", c) in rows and c != "reference"
            else "" for c in cols) + " |")
    out.append(verdicts("cloth: verdict", "cloth"))
    out.append(line("chain: max abs(H - H*) / E_avail", "chain", "max_dev_target_rel"))
    out.append(line("chain: mean K 5-10 s / reference's", "chain", "mean_K_ratio"))
    out.append(line("chain: flicker of K", "chain", "flicker"))
    if "swing_period_s" in motion[0]:
        out.append(line("chain: swing period of the centre of mass [s]", "chain", "swing_period_s"))
    out.append(verdicts("chain: verdict", "chain"))
    out.append(line("spinning bar (y axis): L kept after 10 s [%]", "spinbar", "L_kept", 4, 100.0))
    out.append(line("spinning bar (general axis, 20 % stretch): L kept [%]", "spinbar_general", "L_kept", 4, 100.0))
    r = rows.get(("handle", "blend"))
    if r:
        frac = num(r, "partner_whole_steps") / max(num(r, "steps"), 1.0)
        out.append("| handle cloth: steps with the partner taken whole [%] | " + " | ".join(
            fmt(100 * frac) if c == "blend" else "" for c in cols) + " |")
    out.append(line("handle cloth: mean K 5-10 s / reference's", "handle", "mean_K_ratio"))
    out.append(line("handle cloth: flicker of K", "handle", "flicker"))
    out.append(line("stiff cloth dragged by a hand: mean K 5-10 s / reference's", "stiff_drag", "mean_K_ratio"))
    out.append(line("stiff cloth dragged by a hand: flicker of K", "stiff_drag", "flicker"))
    out.append(line("stiff cloth (h = 1/15): drop of the centre of mass within 1 s [m]", "cloth_stiff",
                    "com_drop_1s_m", until=1.0))
    out.append(line("stiff cloth: flicker of K over 10 s", "cloth_stiff", "flicker"))
    pin = read_csv(results, "moving_pin.csv")
    if pin:
        out.append("| particle on a moving pin, IM: max abs(H* - H_IM) [J] for k = "
                   + ", ".join(f"{num(r, 'stiffness'):.0e}" for r in pin) + " | " + " | ".join(
                       ", ".join(fmt(num(r, "max_abs_target_minus_H_IM_J")) for r in pin) if c == "IM" else ""
                       for c in cols) + " |")
    return out


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
               "*over-damped* = lost more than 50 % of E_avail; else *stable*; where a run is also judged against a "
               "small-step reference, the motion flags *frozen* and *jittery* are added (see the motion section). "
               "Timings are wall clock on the "
               "machine that ran the study (shared, so noisy).\n")
    acc = read_csv(results, "accuracy.csv")
    if acc:
        out.append("## Real-time setting: h = 1/30 s, 10 iterations, 60 frames (2 s) against the reference\n")
        out.append(f"Backend: {acc[0].get('backend', 'cpu')}.\n")
        out.append("| scene | integrator | ms/frame | position error [m] | RMS error 0-1 s vs small-step reference [m] "
                   "| energy drift [E_avail] | energy lost (damping) [E_avail] | verdict (energy) |")
        out.append("|---|---|---:|---:|---:|---:|---:|---|")
        for r in acc:
            out.append(f"| {r['scene']} | {r['integrator']} | {fmt(num(r, 'ms_per_frame'))} | "
                       f"{fmt(num(r, 'position_error_m'))} | {fmt(num(r, 'rms_0_1s_m'))} | "
                       f"{fmt(num(r, 'drift_rel'))} | {fmt(num(r, 'damping_rel'))} | {r['verdict']} |")
        out.append("")
    table = read_csv(results, "energy_table.csv")
    if table:
        out.append("## Energy behaviour over 300 frames (10 s), h = 1/30 s, 10 iterations\n")
        out.append("Verdict: energy verdict, then the motion flags against the small-step reference (frozen, "
                   "jittery; see the motion section).\n")
        out.append("| scene | integrator | ms/frame | drift [E_avail] | max abs(H - H*) [E_avail] | H min .. max | "
                   "blew up at | blend branches | verdict |")
        out.append("|---|---|---:|---:|---:|---|---:|---|---|")
        for r in table:
            blow = r["blew_up_frame"] if r["blew_up_frame"] != "-1" else "-"
            branches = r.get("branches", "-").replace(";", " ") if r["integrator"].startswith("blend") else "-"
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
        for scene in ("cloth", "cloth_triangles", "tetbar"):
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
        for scene in ("chain", "cloth_triangles", "tetbar"):
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
    table = motion_table(results)
    if table:
        out.append("## Motion against a small-step reference (issue 8)\n")
        out.append("Every run judged on motion, not only on energy: **RMS error** = sqrt of the mean over frames "
                   "1..N (0-0.5 s, 0-1 s) and particles of abs(x - x_ref)^2; **mean K** over 5-10 s relative to the "
                   "reference's (stiff cloth: over the second half of its 1 s reference); **flicker** = median over "
                   "consecutive frames (from frame 1) of max(K_i+1/K_i, K_i/K_i+1), with 1e-9 E_avail added to "
                   "both; **L kept** = L(10 s).L0/abs(L0)^2 about the centre of mass; **drop** = largest drop of the "
                   "centre of mass within 1 s. Verdicts: *exploded* as above; otherwise the flags that apply of "
                   "*over-damped*, **frozen** (mean K < 0.3 x the reference's) and **jittery** (flicker > 1.5); "
                   "else *stable*. The stability map's cells are judged on energy only (no small-step reference "
                   "per stiffness and step size). h = 1/30 s and 10 iterations unless said; `stabint-study motion` "
                   f"(backend {read_csv(results, 'motion.csv')[0]['backend']}). Times are medians of per-frame "
                   "wall clock on the machine that ran the study; on a shared machine they still vary by up to 2x "
                   "between runs, and so does the equal-time row (read off the sweep's iteration-budget curves).\n")
        out.extend(table)
        out.append("")
        refs = read_csv(results, "motion_reference.csv")
        if refs:
            out.append("References (CPU backend; the check run has half the steps per frame):\n")
            columns = [("scene", "scene", None), ("method", "method", None), ("horizon [s]", "horizon_s", 3),
                       ("energy error max abs(H - H*) / E_avail", "energy_error_rel", 2),
                       ("check: RMS 0-1 s [m]", "self_rms_0_1s_m", 2), ("check: mean K ratio", "self_mean_K_ratio", 4),
                       ("computed in [s]", "compute_s", 3)]
            out.append("| " + " | ".join(c[0] for c in columns) + " |")
            out.append("|" + "".join("---|" if c[2] is None else "---:|" for c in columns))
            out.extend("| " + " | ".join(r[key] if digits is None else fmt(num(r, key), digits)
                                         for _, key, digits in columns) + " |" for r in refs)
            out.append("")
        handle = read_csv(results, "handle_convergence.csv")
        if handle:
            out.append("Handle cloth, blend, by how far its solves converge (docs/method.md, \"Which solver is the "
                       "default\"): H* gained over 10 s (booked work minus damping) against the reference's energy "
                       f"gain of {fmt(num(handle[0], 'reference_gain_J'))} J.\n")
            out.append("| solver | iterations | tolerance | mean K 5-10 s / reference's | H* gained [J] |")
            out.append("|---|---:|---:|---:|---:|")
            out.extend(f"| {r['solver']} | {r['iterations'] if int(r['iterations']) > 0 else '-'} | "
                       f"{fmt(num(r, 'tolerance')) if num(r, 'tolerance') > 0 else '-'} | "
                       f"{fmt(num(r, 'mean_K_ratio'))} | {fmt(num(r, 'target_gain_J'))} |" for r in handle)
            out.append("")
    bounce = read_csv(results, "bounce.csv")
    if bounce:
        drop = 0.5  # cmd_interaction.cpp: the bar's bottom starts 0.5 m above the ground, at rest
        out.append("## Bounce on the ground (`stabint-study interaction`, bounce.csv)\n")
        out.append("A free tet bar (62.5 kg) dropped from 0.5 m onto the ground (the default contact, friction "
                   "0.3), h = 1/30 s, 10 iterations, 4 s. Lands: when the bar's centre first "
                   "reaches its resting height (free fall: 0.32 s). Rebound: the highest the centre gets after that, "
                   "as a fraction of the drop. Friction and final projection: the energy they took out of H* over "
                   "the run.\n")
        out.append("| integrator | lands at [s] | rebound [drop] | friction [J] | final projection [J] | "
                   "max abs(H - H*) [E_scale] |")
        out.append("|---|---:|---:|---:|---:|---:|")
        for integ in ("BE", "BDF2", "blend"):
            rs = [r for r in bounce if r["integrator"] == integ]
            if not rs:
                continue
            landed = next((i for i, r in enumerate(rs) if num(r, "height") <= 0.0), None)
            rebound = max(num(r, "height") for r in rs[landed:]) / drop if landed is not None else float("nan")
            gap = max(abs(num(r, "H") - num(r, "H_target")) / num(r, "E_scale") for r in rs)
            out.append(f"| {integ} | {fmt(num(rs[landed], 'time')) if landed is not None else 'never'} | "
                       f"{fmt(rebound, 2)} | {fmt(num(rs[-1], 'friction'))} | "
                       f"{fmt(0.0 - num(rs[-1], 'projection') + 0.0)} | {fmt(gap)} |")
        out.append("")
    charts = os.path.join(results, "charts")
    out.append("## Charts\n")
    for name, what in (("speed_vs_accuracy", "per scene, the least error for the time: each method along its "
                        "own Pareto front, the default ringed"),
                       ("speed_vs_accuracy_full", "the appendix: every series against position error, energy "
                        "drift and the error over 0-1 s"),
                       ("stability_map", "verdict per stiffness and step size, per integrator"),
                       ("energy_over_time", "tet bar free-end height and energy; cloth energy"),
                       ("cloth_still", "the cloth at the same frame with BE and the blend"),
                       ("motion", "centre-of-mass path and kinetic energy of the cloth against the small-step "
                        "reference, mean K against flicker for every run, the stiff cloth's fall"),
                       ("interaction", "energy books of a grab-drag-release of a cloth corner (H, H*, the hand's "
                        "work, K) and of a tet bar bouncing on the ground (H, H*, friction, final projection, K, "
                        "height) with BE, BDF2 and the blend")):
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
    chart_speed_vs_accuracy_full(results, charts)
    chart_stability_map(results, charts)
    chart_energy_over_time(results, charts)
    chart_cloth_still(results, charts)
    chart_motion(results, charts)
    chart_interaction(results, charts)
    write_summary(results)
    table = motion_table(results)
    if table:
        print("\nMotion table (issue 8; definitions in summary.md):")
        print("\n".join(table))


if __name__ == "__main__":
    main()
