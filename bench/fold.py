#!/usr/bin/python3
"""Self-contact's study scene, from `stabint-study fold`: a cloth that collapses, folds onto itself
on the ground and is dragged over a body given as a triangle mesh, with BE, BDF2 and the blend.

Usage: bench/fold.py RESULTS_DIR [--charts DIR] [--every N]

Reads RESULTS_DIR/{fold_triangles.csv, fold_body.csv, fold_energy.csv, fold_<integrator>.bin} and
writes into the charts directory (default RESULTS_DIR/charts):
  fold.gif         the three side by side, one animation frame per N simulation frames
  fold.png/.svg    the still: the three at one moment, with the energy curves under them
and RESULTS_DIR/fold_table.md, the table it prints: per integrator the frame time, H at the start
and the end, the most H rose above H_0, and the most it ran above the blend's target H* (the drag's
work less the booked losses), as a fraction of the run's largest kinetic energy.

Rendered as the teaser is (bench/povray_render.py, POV-Ray): the cloth a thin shell, blue on the
side its triangles face and ochre on the other, so that its folds show; the body grey. The curves
are H - H_0 and, dashed, the blend's target H* - H_0 (the drag's work less the booked losses).
"""
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
from teaser import BACK, COLOURS, FRONT, TITLES, picture_args, read_energy  # noqa: E402

BODY = (0.62, 0.62, 0.60)   # grey
VIEW = [-0.25, -0.55, -1.0]  # from the eye to the scene: from the front, above
GAP = 0.25                  # m between the three panels' widest extents
STILL_TIME = 4.5            # s: the folded cloth pulled over the body


def read_body(results):
    vertices, triangles = [], []
    for row in csv.DictReader(open(os.path.join(results, "fold_body.csv"))):
        if row["kind"] == "v":
            vertices.append([float(row["a"]), float(row["b"]), float(row["c"])])
        else:
            triangles.append([int(row["a"]), int(row["b"]), int(row["c"])])
    return np.array(vertices), np.array(triangles, dtype=int)


def energy_axes(ax, energy, mark=None):
    """H - H_0 per integrator and the blend's target. The vertical range is BE's and the blend's
    (and the target's): a run that gains far more (BDF2 here) leaves the chart, and a note says
    when and how far it goes."""
    lo, hi = 0.0, 0.0
    for integ in ("BE", "blend"):
        if integ in energy:
            e = energy[integ]
            for curve in (e["H"], e["H_target"]):
                lo, hi = min(lo, float(np.min(curve - e["H"][0]))), max(hi, float(np.max(curve - e["H"][0])))
    pad = 0.15 * max(hi - lo, 1e-9)
    lo, hi = lo - pad, hi + pad
    notes = []
    for integ, e in energy.items():
        rise = e["H"] - e["H"][0]
        ax.plot(e["time"], rise, color=COLOURS[integ], lw=1.6, label=TITLES[integ])
        above = np.nonzero(rise > hi)[0]
        if len(above):
            notes.append(f"{TITLES[integ]} leaves the chart at t = {e['time'][above[0]]:.2f} s "
                         f"and reaches H - H0 = {rise.max():.3g} J")
    if "blend" in energy:
        e = energy["blend"]
        ax.plot(e["time"], e["H_target"] - e["H"][0], color=COLOURS["blend"], lw=1.0, ls="--",
                label="blend's target H*")
    if mark is not None:
        ax.axvline(mark, color="k", lw=0.8, ls="--")
    ax.set_ylim(lo, hi)
    for k, note in enumerate(notes):
        ax.text(0.99, 0.95 - 0.12 * k, note, transform=ax.transAxes, ha="right", va="top", fontsize=9)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("H - H0 [J]")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(alpha=0.3)


def table(energy):
    lines = ["| integrator | ms/frame | H_0 [J] | H_end [J] | max H - H_0 [J] | max (H - H*) / K_max |",
             "|---|---:|---:|---:|---:|---:|"]
    for integ, e in energy.items():
        h0 = e["H"][0]
        excess = (e["H"] - e["H_target"]).max() / e["kinetic"].max()
        lines.append(f"| {TITLES[integ]} | {e['ms_per_frame'][-1]:.1f} | {h0:.3g} | {e['H'][-1]:.3g} | "
                     f"{(e['H'] - h0).max():.3g} | {excess:.3g} |")
    return "\n".join(lines)


def main():
    args, charts = picture_args(__doc__, "fold")
    energy = read_energy(args.results, "fold")
    particles = next(iter(energy.values()))["particles"]
    triangles = np.loadtxt(os.path.join(args.results, "fold_triangles.csv"), delimiter=",", skiprows=1, dtype=int)
    body, body_triangles = read_body(args.results)
    runs = {}
    for integ in energy:
        data = np.fromfile(os.path.join(args.results, f"fold_{integ}.bin"), dtype="<f4")
        runs[integ] = data.reshape(-1, particles, 3).astype(float)
    frames = min(len(r) for r in runs.values())
    text = table(energy)
    print(text)
    with open(os.path.join(args.results, "fold_table.md"), "w") as f:
        f.write(text + "\n")
    frame_step = float(energy["BE"]["time"][1] - energy["BE"]["time"][0])
    d = np.asarray(VIEW, float) / np.linalg.norm(VIEW)
    right = np.cross(d, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    # Each panel is a run's cloth with the body, shifted as one.
    panels = [np.concatenate([runs[i][:frames], np.broadcast_to(body, (frames,) + body.shape)], axis=1) for i in runs]
    # Set side by side and framed on the frames up to the still: a run that flies apart later
    # (BDF2's) then leaves the picture instead of shrinking the others to specks.
    still = min(int(round(STILL_TIME / frame_step)), frames - 1)
    shown = pr.side_by_side([p[: still + 1] for p in panels], right, GAP)
    placed = [p + (q[0, 0] - p[0, 0]) for p, q in zip(panels, shown)]
    everything = np.concatenate(shown)
    ground = 0.0
    means = [p.reshape(-1, 3).mean(axis=0) for p in shown]
    titles = [TITLES[i] for i in runs]

    def surfaces(f):
        out = []
        for p in placed:
            out.append((p[f, :particles], triangles, FRONT, BACK))
            out.append((p[f, particles:], body_triangles, BODY, None))
        return out

    with tempfile.TemporaryDirectory(prefix="stabint-fold-") as tmp:
        view = pr.View(VIEW, np.concatenate([p[still][None] for p in placed]), ground, 1500, 520, pad=0.12,
                       antialias=0.1, soft_shadows=True)
        png = os.path.join(tmp, "still.png")
        pr.render(view, [surfaces(still)], [png])
        image = np.asarray(Image.open(png).convert("RGB"))
        centres = [pr.image_x(view, p[still].mean(axis=0)) for p in placed]
    fig = plt.figure(figsize=(13.5, 7.0))
    grid = fig.add_gridspec(2, 1, height_ratios=[3.0, 1.2], hspace=0.1)
    ax = fig.add_subplot(grid[0])
    ax.imshow(image, interpolation="lanczos")
    ax.set_axis_off()
    for title, cx in zip(titles, centres):
        ax.text(cx * image.shape[1], 10, title, ha="center", va="top", fontsize=12)
    energy_axes(fig.add_subplot(grid[1]), energy, mark=still * frame_step)
    side = int(round(np.sqrt(particles)))
    fig.suptitle(f"{side} x {side} cloth with self-contact, folding on the ground and dragged by the middle of its "
                 f"top edge over a mesh body, h = 1/30 s: t = {still * frame_step:.2f} s", fontsize=12)
    for ext in ("png", "svg"):
        fig.savefig(os.path.join(charts, f"fold.{ext}"), dpi=110, bbox_inches="tight")
    plt.close(fig)

    picked = list(range(0, frames, args.every))
    with tempfile.TemporaryDirectory(prefix="stabint-fold-") as tmp:
        view = pr.View(VIEW, everything, ground, 720, 250, antialias=0.3, soft_shadows=False)
        centres = [pr.image_x(view, m) for m in means]
        pngs = [os.path.join(tmp, f"f{k:04d}.png") for k in range(len(picked))]
        pr.render(view, [surfaces(f) for f in picked], pngs)
        images = [label_frame(p, titles, centres, f"t = {f * frame_step:.2f} s") for p, f in zip(pngs, picked)]
    pr.save_gif(images, os.path.join(charts, "fold.gif"), int(round(1000 * frame_step * args.every)))
    print(f"fold.py: {charts}/fold.gif ({len(picked)} frames), fold.png (t = {still * frame_step:.2f} s)")


if __name__ == "__main__":
    main()
