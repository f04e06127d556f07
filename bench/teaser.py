#!/usr/bin/python3
"""The teaser of the paper, from `stabint-study teaser`: a 40 x 40 cloth of triangle strain and
bending hinges, pinned at two corners, stepped with BE, BDF2 and the blend from the same start.

Usage: bench/teaser.py RESULTS_DIR [--charts DIR] [--every N]

Reads RESULTS_DIR/{teaser_triangles.csv, teaser_energy.csv, teaser_<integrator>.bin} and writes
into the charts directory (default RESULTS_DIR/charts):
  teaser.gif         the three side by side, one animation frame per N simulation frames
  teaser.png/.svg    the still: the three at one moment, with the energy curves under them
  teaser_energy.png  the energy curves alone (H / E_avail over time)

The surface is drawn with a fixed orthographic camera, triangles depth-sorted (painter's
algorithm) and flat-shaded; the two sides of the cloth get different colours so folds show.
Only matplotlib (and Pillow, through matplotlib's GIF writer) is used; nothing is downloaded.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import animation  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

INTEGRATORS = ("BE", "BDF2", "blend")
TITLES = {"BE": "backward Euler", "BDF2": "BDF2", "blend": "energy-tracking blend"}
COLOURS = {"BE": "tab:blue", "BDF2": "tab:orange", "blend": "tab:green"}
FRONT = np.array([0.27, 0.51, 0.71])  # steel blue
BACK = np.array([0.85, 0.55, 0.25])   # ochre
STILL_TIME = 2.0  # s: the cloth has swung through the bottom; BE's folds are gone, the blend's are not


def read_energy(results):
    rows = list(csv.DictReader(open(os.path.join(results, "teaser_energy.csv"))))
    out = {}
    for integ in INTEGRATORS:
        rs = [r for r in rows if r["integrator"] == integ]
        if rs:
            out[integ] = {k: np.array([float(r[k]) for r in rs]) for k in ("time", "H", "H_target", "kinetic")}
            out[integ]["particles"] = int(rs[0]["particles"])
    return out


def read_positions(results, integ, particles):
    data = np.fromfile(os.path.join(results, f"teaser_{integ}.bin"), dtype="<f4")
    return data.reshape(-1, particles, 3)


class Camera:
    """Orthographic view along `direction` (from the eye towards the scene), y up."""

    def __init__(self, direction):
        d = np.asarray(direction, float)
        self.view = d / np.linalg.norm(d)
        right = np.cross(self.view, [0.0, 1.0, 0.0])
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.right, self.view)
        light = np.array([0.4, 0.8, -0.45])
        self.light = light / np.linalg.norm(light)

    def draw(self, ax, x, triangles):
        p = x[triangles]                       # T x 3 x 3
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        facing = n @ self.view < 0.0           # the front side faces the eye
        shade = 0.35 + 0.65 * np.abs(n @ self.light)
        colours = np.where(facing[:, None], FRONT, BACK) * shade[:, None]
        depth = (p.mean(axis=1) @ self.view)
        order = np.argsort(-depth)             # far first
        xy = np.stack([p @ self.right, p @ self.up], axis=-1)[order]
        ax.add_collection(PolyCollection(xy, facecolors=np.clip(colours[order], 0, 1), edgecolors="none",
                                         antialiaseds=False))


def frame_limits(camera, runs):
    pts = np.concatenate([r.reshape(-1, 3) for r in runs])
    u, v = pts @ camera.right, pts @ camera.up
    pad = 0.05
    return (u.min() - pad, u.max() + pad), (v.min() - pad, v.max() + pad)


def setup_panel(ax, limits, title):
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for side in ax.spines.values():
        side.set_visible(False)
    ax.set_title(title, fontsize=11)


def energy_axes(ax, energy, mark=None):
    lowest = 0.0
    for integ, e in energy.items():
        ax.plot(e["time"], e["H"] - e["H"][0], color=COLOURS[integ], lw=1.6, label=TITLES[integ])
        lowest = min(lowest, float(np.min(e["H"] - e["H"][0])))
    ax.axhline(0.0, color="gray", lw=0.8, ls=":")
    if mark is not None:
        ax.axvline(mark, color="k", lw=0.8, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("H - H0 [J]")
    ax.set_ylim(1.08 * lowest, -0.15 * lowest)
    ax.legend(loc="lower left", fontsize=8)
    ax.grid(alpha=0.3)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results")
    ap.add_argument("--charts", default=None)
    ap.add_argument("--every", type=int, default=2, help="simulation frames per animation frame")
    args = ap.parse_args()
    charts = args.charts or os.path.join(args.results, "charts")
    os.makedirs(charts, exist_ok=True)
    if not os.path.exists(os.path.join(args.results, "teaser_energy.csv")):
        sys.exit(f"teaser.py: {args.results}/teaser_energy.csv missing (run stabint-study teaser)")

    energy = read_energy(args.results)
    particles = next(iter(energy.values()))["particles"]
    triangles = np.loadtxt(os.path.join(args.results, "teaser_triangles.csv"), delimiter=",", skiprows=1, dtype=int)
    runs = {integ: read_positions(args.results, integ, particles) for integ in energy}
    frame_step = float(energy["BE"]["time"][1] - energy["BE"]["time"][0])
    camera = Camera([-0.35, -0.3, -1.0])
    limits = frame_limits(camera, list(runs.values()))

    # --- the still, with the energy curves ---------------------------------------------------------
    still = min(int(round(STILL_TIME / frame_step)), min(len(r) for r in runs.values()) - 1)
    fig = plt.figure(figsize=(13.5, 6.4))
    grid = fig.add_gridspec(2, 3, height_ratios=[3.0, 1.2], hspace=0.12, wspace=0.02)
    for c, integ in enumerate(runs):
        ax = fig.add_subplot(grid[0, c])
        setup_panel(ax, limits, TITLES[integ])
        camera.draw(ax, runs[integ][still], triangles)
    energy_axes(fig.add_subplot(grid[1, :]), energy, mark=still * frame_step)
    fig.suptitle(f"{int(np.sqrt(particles))} x {int(np.sqrt(particles))} cloth of triangle strain and bending hinges, "
                 f"pinned at two corners, h = 1/30 s, 10 iterations: t = {still * frame_step:.2f} s", fontsize=12)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(charts, f"teaser.{ext}"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    energy_axes(ax, energy)
    ax.set_title("Teaser cloth: total energy H relative to the start")
    fig.savefig(os.path.join(charts, "teaser_energy.png"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    # --- the animation ---------------------------------------------------------------------------
    frames = range(0, min(len(r) for r in runs.values()), args.every)
    fig, axes = plt.subplots(1, len(runs), figsize=(10.5, 4.2))
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.02, top=0.86, wspace=0.02)
    label = fig.suptitle("")

    def draw(f):
        for ax, integ in zip(axes, runs):
            ax.clear()
            setup_panel(ax, limits, TITLES[integ])
            camera.draw(ax, runs[integ][f], triangles)
        label.set_text(f"triangle strain + bending hinges, pinned at two corners: t = {f * frame_step:.2f} s")
        return []

    anim = animation.FuncAnimation(fig, draw, frames=frames, blit=False)
    anim.save(os.path.join(charts, "teaser.gif"), writer=animation.PillowWriter(fps=round(1.0 / (frame_step * args.every))),
              dpi=70)
    plt.close(fig)
    print(f"teaser.py: {charts}/teaser.gif ({len(frames)} frames), teaser.png (t = {still * frame_step:.2f} s), "
          "teaser_energy.png")


if __name__ == "__main__":
    main()
