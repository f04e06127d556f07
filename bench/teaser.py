#!/usr/bin/python3
"""The teaser of the paper, from `stabint-study teaser`: a 40 x 40 cloth of triangle strain and
bending hinges, pinned at two corners, stepped with BE, BDF2 and the blend from the same start.

Usage: bench/teaser.py RESULTS_DIR [--charts DIR] [--every N]

Reads RESULTS_DIR/{teaser_triangles.csv, teaser_energy.csv, teaser_<integrator>.bin} and writes
into the charts directory (default RESULTS_DIR/charts):
  teaser.gif         the three side by side, one animation frame per N simulation frames
  teaser.png/.svg    the still: the three at one moment, with the energy curves under them
  teaser_energy.png  the energy curves alone (H / E_avail over time)

The cloths are rendered with POV-Ray (Debian's povray, bench/povray_render.py): a fixed
orthographic camera, smooth vertex normals, a key light with soft shadows (the still) and a fill
light, a ground plane under the lowest point the cloths reach; the two sides of the cloth get
different colours so folds show. matplotlib draws the energy curves, Pillow writes the GIF;
nothing is downloaded.
"""
import argparse
import csv
import os
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import povray_render as pr  # noqa: E402
from drop import label_frame  # noqa: E402

INTEGRATORS = ("BE", "BDF2", "blend")
TITLES = {"BE": "backward Euler", "BDF2": "BDF2", "blend": "energy-tracking blend"}
COLOURS = {"BE": "tab:blue", "BDF2": "tab:orange", "blend": "tab:green"}
FRONT = (0.30, 0.52, 0.75)  # steel blue
BACK = (0.88, 0.60, 0.30)   # ochre
VIEW = [-0.35, -0.3, -1.0]  # from the eye to the scene
GAP = 0.12                  # m between the three cloths' widest extents
STILL_TIME = 5.0  # s: BE and BDF2 hang still in their folds; the blend is at the top of its swing


def read_energy(results, name="teaser"):
    """Every frame's energies per integrator from RESULTS/<name>_energy.csv (a study command's)."""
    rows = list(csv.DictReader(open(os.path.join(results, f"{name}_energy.csv"))))
    out = {}
    for integ in INTEGRATORS:
        rs = [r for r in rows if r["integrator"] == integ]
        if rs:
            out[integ] = {k: np.array([float(r[k]) for r in rs])
                          for k in ("time", "H", "H_target", "kinetic", "ms_per_frame") if k in rs[0]}
            out[integ]["particles"] = int(rs[0]["particles"])
    return out


def read_positions(results, integ, particles):
    data = np.fromfile(os.path.join(results, f"teaser_{integ}.bin"), dtype="<f4")
    return data.reshape(-1, particles, 3)


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


def picture_args(doc, name):
    """The command line of a picture script for `stabint-study <name>`'s results: the parsed
    arguments and the charts directory (made); exits when the results or POV-Ray are missing."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("results")
    ap.add_argument("--charts", default=None)
    ap.add_argument("--every", type=int, default=3, help="simulation frames per animation frame")
    args = ap.parse_args()
    charts = args.charts or os.path.join(args.results, "charts")
    os.makedirs(charts, exist_ok=True)
    if not os.path.exists(os.path.join(args.results, f"{name}_energy.csv")):
        sys.exit(f"{name}.py: {args.results}/{name}_energy.csv missing (run stabint-study {name})")
    if not pr.available():
        sys.exit(f"{name}.py: {pr.POVRAY} missing (Debian package povray; scripts/install-deps.sh)")
    return args, charts


def main():
    args, charts = picture_args(__doc__, "teaser")

    energy = read_energy(args.results)
    particles = next(iter(energy.values()))["particles"]
    triangles = np.loadtxt(os.path.join(args.results, "teaser_triangles.csv"), delimiter=",", skiprows=1, dtype=int)
    runs = {integ: read_positions(args.results, integ, particles) for integ in energy}
    frame_step = float(energy["BE"]["time"][1] - energy["BE"]["time"][0])
    frames = min(len(r) for r in runs.values())
    d = np.asarray(VIEW, float) / np.linalg.norm(VIEW)
    right = np.cross(d, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    placed = pr.side_by_side([runs[i].astype(float) for i in runs], right, GAP)
    everything = np.concatenate(placed)
    # The ground: a little under the lowest point any cloth reaches, so it takes their shadows.
    ground = float(everything[..., 1].min()) - 0.08
    means = [p.reshape(-1, 3).mean(axis=0) for p in placed]
    titles = [TITLES[i] for i in runs]
    surfaces = lambda f: [(p[f], triangles, FRONT, BACK) for p in placed]  # noqa: E731
    side = int(np.sqrt(particles))

    # --- the still, with the energy curves ---------------------------------------------------------
    still = min(int(round(STILL_TIME / frame_step)), frames - 1)
    with tempfile.TemporaryDirectory(prefix="stabint-teaser-") as tmp:
        view = pr.View(VIEW, everything, ground, 1500, 560, antialias=0.1, soft_shadows=True)
        png = os.path.join(tmp, "still.png")
        pr.render(view, [surfaces(still)], [png])
        image = np.asarray(Image.open(png).convert("RGB"))
        centres = [pr.image_x(view, m) for m in means]
    fig = plt.figure(figsize=(13.5, 7.0))
    grid = fig.add_gridspec(2, 1, height_ratios=[3.0, 1.2], hspace=0.1)
    ax = fig.add_subplot(grid[0])
    ax.imshow(image, interpolation="lanczos")
    ax.set_axis_off()
    for title, cx in zip(titles, centres):
        ax.text(cx * image.shape[1], 10, title, ha="center", va="top", fontsize=12)
    energy_axes(fig.add_subplot(grid[1]), energy, mark=still * frame_step)
    fig.suptitle(f"{side} x {side} cloth of triangle strain and bending hinges, "
                 f"pinned at two corners, h = 1/30 s, 10 iterations: t = {still * frame_step:.2f} s", fontsize=12)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(charts, f"teaser.{ext}"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    energy_axes(ax, energy)
    ax.set_title("Teaser cloth: total energy H relative to the start")
    fig.savefig(os.path.join(charts, "teaser_energy.png"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    # --- the animation: point light (a third of the tracing), 720 x 270 ----------------------------
    picked = list(range(0, frames, args.every))
    with tempfile.TemporaryDirectory(prefix="stabint-teaser-") as tmp:
        view = pr.View(VIEW, everything, ground, 720, 270, antialias=0.3, soft_shadows=False)
        centres = [pr.image_x(view, m) for m in means]
        pngs = [os.path.join(tmp, f"f{k:04d}.png") for k in range(len(picked))]
        pr.render(view, [surfaces(f) for f in picked], pngs)
        images = [label_frame(p, titles, centres, f"t = {f * frame_step:.2f} s") for p, f in zip(pngs, picked)]
    pr.save_gif(images, os.path.join(charts, "teaser.gif"), int(round(1000 * frame_step * args.every)))
    print(f"teaser.py: {charts}/teaser.gif ({len(picked)} frames), teaser.png (t = {still * frame_step:.2f} s), "
          "teaser_energy.png")


if __name__ == "__main__":
    main()
