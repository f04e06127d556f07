#!/usr/bin/python3
"""The soft-body drop of issue 23, from `stabint-study drop`: CGAL's elephant, tetrahedralized by
TetGen (scripts/soft_body_mesh.sh), dropped onto the ground with BE, BDF2 and the blend side by
side at h = 1/30 s and 10 iterations, rendered with POV-Ray (bench/povray_render.py).

Usage: bench/drop.py RESULTS_DIR [--charts DIR] [--every N]

Reads RESULTS_DIR/{drop_surface.csv, drop_energy.csv, drop_<integrator>.bin} and writes into the
charts directory (default RESULTS_DIR/charts):
  drop.gif       the three side by side, one animation frame per N simulation frames
  drop.png       the still: the three at one moment (soft shadows), the energy curves under it
and RESULTS_DIR/drop_table.md, the table it prints: per integrator the energy the ground's
friction took, the energy the integrator lost (H_0 - H_end - friction), the most H rose above
H_0 (during the impacts), the rebound of the centre of mass and the mean kinetic energy over the
last second.
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
from PIL import Image, ImageDraw, ImageFont  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import povray_render as pr  # noqa: E402

INTEGRATORS = ("BE", "BDF2", "blend")
TITLES = {"BE": "backward Euler", "BDF2": "BDF2", "blend": "energy-tracking blend"}
COLOURS = {"BE": "tab:blue", "BDF2": "tab:orange", "blend": "tab:green"}
# Light tints of the curves' colours, so a body and its energy curve go together.
TINTS = {"BE": (0.55, 0.68, 0.85), "BDF2": (0.92, 0.70, 0.48), "blend": (0.58, 0.82, 0.58)}
VIEW = [-0.2, -0.22, -1.0]  # from the eye to the scene: a little from the right and above
STILL_TIME = 4.0 / 3.0      # s: BE and BDF2 lie where they fell; the blend is in the air again
GAP = 0.15                  # m between the three bodies' widest extents


def font(size):
    # matplotlib's own DejaVu Sans (Debian's python3-matplotlib ships it): no system font needed.
    return ImageFont.truetype(os.path.join(matplotlib.get_data_path(), "fonts", "ttf", "DejaVuSans.ttf"), size)


def label_frame(png, titles, centres, caption):
    """Writes the three titles above the bodies and the caption into the rendered frame."""
    img = Image.open(png).convert("RGB")
    draw = ImageDraw.Draw(img)
    small, big = font(max(11, img.height // 18)), font(max(11, img.height // 20))
    for title, cx in zip(titles, centres):
        w = draw.textlength(title, font=small)
        draw.text((cx * img.width - w / 2, 6), title, fill=(30, 30, 30), font=small)
    w = draw.textlength(caption, font=big)
    draw.text((img.width - w - 8, img.height - big.size - 8), caption, fill=(60, 60, 60), font=big)
    return img


def read(results):
    rows = list(csv.DictReader(open(os.path.join(results, "drop_energy.csv"))))
    energy = {}
    for integ in INTEGRATORS:
        rs = [r for r in rows if r["integrator"] == integ]
        energy[integ] = {k: np.array([float(r[k]) for r in rs])
                         for k in ("time", "H", "kinetic", "friction", "com_height", "ms_per_frame")}
        energy[integ]["particles"] = int(rs[0]["particles"])
    triangles = np.loadtxt(os.path.join(results, "drop_surface.csv"), delimiter=",", skiprows=1, dtype=int)
    runs = {}
    for integ in INTEGRATORS:
        n = energy[integ]["particles"]
        runs[integ] = np.fromfile(os.path.join(results, f"drop_{integ}.bin"), dtype="<f4").reshape(-1, n, 3)
    return energy, triangles, runs


def table(energy, frame_step):
    late = int(round(1.0 / frame_step))
    lines = ["| integrator | ms/frame | H_0 [J] | H_end [J] | friction [J] | lost by the integrator [J] | "
             "max H - H_0 [J] | rebound of the centre [m] | mean K, last second [J] |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for integ, e in energy.items():
        h0, h_end, friction = e["H"][0], e["H"][-1], e["friction"][-1]
        com = e["com_height"]
        # The rebound: from the lowest point of the first impact (where the centre first stops
        # falling) to the highest it climbs after it.
        first = int(np.argmax(np.diff(com) > 0))
        rebound = float(com[first:].max() - com[first])
        lines.append(f"| {TITLES[integ]} | {e['ms_per_frame'][-1]:.1f} | {h0:.1f} | {h_end:.1f} | {friction:.1f} | "
                     f"{h0 - h_end - friction:.1f} | {(e['H'] - h0).max():.1f} | {rebound:.2f} | "
                 f"{e['kinetic'][-late:].mean():.3g} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results")
    ap.add_argument("--charts", default=None)
    ap.add_argument("--every", type=int, default=2, help="simulation frames per animation frame")
    args = ap.parse_args()
    charts = args.charts or os.path.join(args.results, "charts")
    os.makedirs(charts, exist_ok=True)
    if not os.path.exists(os.path.join(args.results, "drop_energy.csv")):
        sys.exit(f"drop.py: {args.results}/drop_energy.csv missing (run stabint-study drop)")
    if not pr.available():
        sys.exit(f"drop.py: {pr.POVRAY} missing (Debian package povray; scripts/install-deps.sh)")

    energy, triangles, runs = read(args.results)
    frame_step = float(energy["BE"]["time"][1] - energy["BE"]["time"][0])
    frames = min(len(r) for r in runs.values())
    text = table(energy, frame_step)
    print(text)
    with open(os.path.join(args.results, "drop_table.md"), "w") as f:
        f.write(text + "\n")

    d = np.asarray(VIEW, float) / np.linalg.norm(VIEW)
    right = np.cross(d, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    placed = pr.side_by_side([runs[i].astype(float) for i in INTEGRATORS], right, GAP)
    everything = np.concatenate(placed)
    # Where each title goes: above the body's mean position over the run.
    means = [p.reshape(-1, 3).mean(axis=0) for p in placed]
    surfaces = lambda f: [(p[f], triangles, TINTS[i], None) for p, i in zip(placed, INTEGRATORS)]  # noqa: E731
    titles = [TITLES[i] for i in INTEGRATORS]
    n = energy["BE"]["particles"]
    about = f"{n:,} vertices, {len(triangles):,} surface triangles"

    # --- the still: soft shadows, with the energy curves ----------------------------------------
    still = min(int(round(STILL_TIME / frame_step)), frames - 1)
    with tempfile.TemporaryDirectory(prefix="stabint-drop-") as tmp:
        # Framed on this frame alone (the animation frames every frame): the bodies fill it.
        view = pr.View(VIEW, np.concatenate([p[still][None] for p in placed]), 0.0, 1500, 520, pad=0.12,
                       antialias=0.1, soft_shadows=True)
        centres = [pr.image_x(view, m) for m in means]
        png = os.path.join(tmp, "still.png")
        pr.render(view, [surfaces(still)], [png])
        image = np.asarray(Image.open(png).convert("RGB"))
    fig = plt.figure(figsize=(13.5, 7.0))
    grid = fig.add_gridspec(2, 1, height_ratios=[3.0, 1.3], hspace=0.08)
    ax = fig.add_subplot(grid[0])
    ax.imshow(image, interpolation="lanczos")
    ax.set_axis_off()
    for title, cx in zip(titles, centres):
        ax.text(cx * image.shape[1], 10, title, ha="center", va="top", fontsize=12)
    ax = fig.add_subplot(grid[1])
    for integ, e in energy.items():
        ax.plot(e["time"], e["H"], color=COLOURS[integ], lw=1.6, label=f"{TITLES[integ]}: H")
        ax.plot(e["time"], e["H"] + e["friction"], color=COLOURS[integ], lw=1.0, ls="--",
                label=f"{TITLES[integ]}: H + friction's work")
    ax.axvline(still * frame_step, color="k", lw=0.8, ls=":")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("energy [J]")
    ax.set_ylim(bottom=0.0)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.28), fontsize=8, ncol=3, frameon=False)
    ax.grid(alpha=0.3)
    fig.suptitle(f"TetGen elephant ({about}) dropped on the ground, h = 1/30 s, 10 iterations: "
                 f"t = {still * frame_step:.2f} s", fontsize=12)
    fig.savefig(os.path.join(charts, "drop.png"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    # --- the animation: point light (a third of the tracing), 720 x 250 --------------------------
    picked = list(range(0, frames, args.every))
    with tempfile.TemporaryDirectory(prefix="stabint-drop-") as tmp:
        view = pr.View(VIEW, everything, 0.0, 720, 250, antialias=0.3, soft_shadows=False)
        centres = [pr.image_x(view, m) for m in means]
        pngs = [os.path.join(tmp, f"f{k:04d}.png") for k in range(len(picked))]
        pr.render(view, [surfaces(f) for f in picked], pngs)
        images = [label_frame(p, titles, centres, f"t = {f * frame_step:.2f} s") for p, f in zip(pngs, picked)]
    pr.save_gif(images, os.path.join(charts, "drop.gif"), int(round(1000 * frame_step * args.every)))
    print(f"drop.py: {charts}/drop.gif ({len(picked)} frames), drop.png (t = {still * frame_step:.2f} s), "
          f"{args.results}/drop_table.md")


if __name__ == "__main__":
    main()
