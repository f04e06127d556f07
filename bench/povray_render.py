"""Shaded renders of triangle surfaces with POV-Ray (Debian's `povray`), for the teaser and the
soft-body drop (issue 23): smooth vertex normals, a key light with soft shadows, a fill light, a
ground plane that takes the shadow, and a white sky. POV-Ray is a CPU ray tracer, so it runs
headless on a machine without a GPU, and it renders the same pixels on every run (antialiasing
and the area light are not jittered), so the pictures are deterministic.

Only numpy, Pillow (the GIF; Debian's python3-pil) and /usr/bin/povray are used; nothing is
downloaded.
"""
import os
import shutil
import subprocess
import tempfile

import numpy as np

POVRAY = "/usr/bin/povray"


def available():
    return os.access(POVRAY, os.X_OK)


def vertex_normals(x, triangles):
    """Area-weighted vertex normals (the sum of the adjacent faces' cross products), unit length."""
    p = x[triangles]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n = np.zeros_like(x)
    for k in range(3):
        np.add.at(n, triangles[:, k], face)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.maximum(length, 1e-12)


class View:
    """A fixed orthographic camera for a set of frames: looks along `direction` (from the eye to
    the scene, y up) and frames every point of `points` (all frames of all runs, so the panels
    and the animation frames share one scale), with the ground at `ground` (y)."""

    def __init__(self, direction, points, ground, width, height, pad=0.06, antialias=0.1, soft_shadows=True):
        d = np.asarray(direction, float)
        self.view = d / np.linalg.norm(d)
        right = np.cross(self.view, [0.0, 1.0, 0.0])
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.right, self.view)
        pts = np.asarray(points, float).reshape(-1, 3)
        u, v = pts @ self.right, pts @ self.up
        self.centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        half_u = 0.5 * (u.max() - u.min()) + pad
        half_v = 0.5 * (v.max() - v.min()) + pad
        # Widen one extent so the image's aspect ratio holds without stretching.
        aspect = width / height
        if half_u / half_v < aspect:
            half_u = half_v * aspect
        else:
            half_v = half_u / aspect
        cu, cv = 0.5 * (u.max() + u.min()), 0.5 * (v.max() + v.min())
        depth = float(self.centre @ self.view)
        self.look_at = cu * self.right + cv * self.up + depth * self.view
        self.extent = (2.0 * half_u, 2.0 * half_v)
        self.distance = 4.0 * float(np.ptp(pts, axis=0).max() + 1.0)
        self.ground = ground
        self.width, self.height = width, height
        self.antialias = antialias  # POV-Ray's +A threshold (0: off)
        # The key light as an area light: soft shadows at about three times the tracing cost
        # (animation frames use a point light).
        self.soft_shadows = soft_shadows


def image_x(view, point):
    """Where `point` lies across the image of `view`: 0 at the left edge, 1 at the right."""
    return float((np.asarray(point, float) - view.look_at) @ view.right / view.extent[0] + 0.5)


def _vec(v):
    # POV-Ray is left-handed: its z is our -z. Mirroring z maps our right-handed scene to it
    # without changing what the camera sees.
    return f"<{v[0]:.6f},{v[1]:.6f},{-v[2]:.6f}>"


def _mesh2_one(x, n, triangles, colour):
    finish = "finish { ambient 0.0 emission 0.0 diffuse 0.78 specular 0.18 roughness 0.03 }"
    return "\n".join([
        "mesh2 {",
        f"vertex_vectors {{ {len(x)},", ",".join(_vec(p) for p in x), "}",
        f"normal_vectors {{ {len(n)},", ",".join(_vec(p) for p in n), "}",
        # Wound the other way: mirroring z (see _vec) reverses each triangle's winding, so this
        # keeps the winding's normal on the side of the given vertex normals.
        f"face_indices {{ {len(triangles)},", ",".join(f"<{a},{c},{b}>" for a, b, c in triangles), "}",
        f"texture {{ pigment {{ rgb <{colour[0]:.4f},{colour[1]:.4f},{colour[2]:.4f}> }} {finish} }}",
        "}",
    ])


# Half the thickness of the shell an open surface is drawn as (m): far below what a frame shows.
SHELL = 0.001


def _mesh2(x, triangles, colour, back_colour):
    """A closed surface as one smooth mesh; an open one (the cloth, `back_colour` given) as a thin
    shell: the surface moved SHELL along its normals in `colour` and SHELL against them, wound the
    other way, in `back_colour`. Each side then faces its own normals, so each is lit and
    coloured as its own side, and folds that turn the cloth over read."""
    n = vertex_normals(x, triangles)
    if back_colour is None:
        return _mesh2_one(x, n, triangles, colour)
    return _mesh2_one(x + SHELL * n, n, triangles, colour) + "\n" + _mesh2_one(
        x - SHELL * n, -n, triangles[:, ::-1], back_colour)


def scene_header(view):
    """Camera, lights, sky and ground of `view`: everything but the surface."""
    eye = view.look_at - view.distance * view.view
    y = np.array([0.0, 1.0, 0.0])
    # Key light: from the front left, about 40 degrees up, so that surfaces facing the camera (a hanging
    # cloth, which faces down towards it) are lit and the shadow falls behind the body onto the
    # ground; an area light (4 x 4 samples, not jittered) for a soft shadow. A fill light from the
    # front right, level, a third as bright and without shadow; faint shadowless lights from
    # above (the sky) and from below in front (the ground's bounce), so no side goes black.
    key_dir = -0.6 * view.right + 0.7 * y - 1.0 * view.view
    key_dir /= np.linalg.norm(key_dir)
    fill_dir = 1.0 * view.right - 1.0 * view.view
    fill_dir /= np.linalg.norm(fill_dir)
    bounce_dir = -1.0 * y - 0.6 * view.view
    bounce_dir /= np.linalg.norm(bounce_dir)
    size = view.distance
    key = view.look_at + size * key_dir
    fill = view.look_at + size * fill_dir
    a1 = np.cross(key_dir, view.right)
    a1 *= 0.12 * size / np.linalg.norm(a1)
    a2 = np.cross(a1, key_dir)
    a2 *= 0.12 * size / np.linalg.norm(a2)
    return "\n".join([
        "#version 3.7;",
        "global_settings { assumed_gamma 1.0 ambient_light rgb 0 }",
        # The mirrored z (see _vec) makes this left-handed camera show the right-handed scene.
        f"camera {{ orthographic location {_vec(eye)} look_at {_vec(view.look_at)} "
        f"right x*{view.extent[0]:.6f} up y*{view.extent[1]:.6f} }}",
        f"light_source {{ {_vec(key)} rgb 1.0 "
        + (f"area_light {_vec(a1)}, {_vec(a2)}, 4, 4 adaptive 1 circular orient" if view.soft_shadows else "") + " }",
        f"light_source {{ {_vec(fill)} rgb 0.35 shadowless }}",
        f"light_source {{ {_vec(view.look_at + size * y)} rgb 0.2 shadowless }}",
        f"light_source {{ {_vec(view.look_at + size * bounce_dir)} rgb 0.18 shadowless }}",
        "background { rgb <0.97,0.97,0.98> }",
        f"plane {{ y, {view.ground:.6f} texture {{ pigment {{ checker rgb <0.97,0.97,0.96> rgb <0.88,0.88,0.87> "
        "scale 0.25 } finish { ambient 0.0 diffuse 1.0 } } }",
    ])


def side_by_side(runs, right, gap):
    """Offsets along `right` that set the runs (each an array frames x n x 3) side by side with
    `gap` metres between their widest extents over all frames; returns the shifted runs."""
    right = np.asarray(right, float)
    widths = [(r.reshape(-1, 3) @ right) for r in runs]
    out, edge = [], 0.0
    for r, w in zip(runs, widths):
        shift = edge - w.min()
        out.append(r + shift * right)
        edge += (w.max() - w.min()) + gap
    return out


def _render_chunk(view, frames, tmp, first):
    """Writes the scene and one include per frame into `tmp`, starts POV-Ray on them as an
    animation and returns the process (frames first+1 .. first+len(frames))."""
    for k, surfaces in enumerate(frames):
        with open(os.path.join(tmp, f"frame{first + k + 1}.inc"), "w") as f:
            for x, triangles, colour, back in surfaces:
                f.write(_mesh2(np.asarray(x, float), triangles, colour, back) + "\n")
    pov = os.path.join(tmp, "scene.pov")
    with open(pov, "w") as f:
        # A one-frame chunk is no animation to POV-Ray (frame_number stays 0): it names the frame
        # by a declared F instead, and writes out.png (renamed by render()).
        f.write(scene_header(view) + '\n#ifndef (F) #declare F = frame_number; #end\n'
                '#include concat("frame", str(F, 0, 0), ".inc")\n')
    args = [POVRAY, f"+I{pov}", f"+O{os.path.join(tmp, 'out.png')}", f"+W{view.width}", f"+H{view.height}",
            "+FN", "-D", "-V", "-GA", "Work_Threads=1"]
    if len(frames) == 1:
        args.append(f"Declare=F={first + 1}")
    else:
        args += [f"+KFI{first + 1}", f"+KFF{first + len(frames)}", f"+KI{first + 1}", f"+KF{first + len(frames)}"]
    if view.antialias:
        args += [f"+A{view.antialias}", "+AM2", "+R2", "-J"]  # adaptive, not jittered: the same pixels every run
    return subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=tmp)


def render(view, frames, out_pngs, jobs=None):
    """Renders each frame of `frames` (a list of surfaces: tuples x, triangles, colour,
    back_colour or None) to the matching path of `out_pngs` (view.width x view.height).
    POV-Ray runs as an animation over a chunk of frames, `jobs` runs at once (default: the CPU
    count plus one): each frame costs about 0.6 s of POV-Ray's own idle wall clock besides the
    tracing, which the parallel runs overlap."""
    if not frames:
        return
    jobs = max(1, min(jobs or (os.cpu_count() or 1) + 1, len(frames)))
    bounds = np.linspace(0, len(frames), jobs + 1).round().astype(int)
    with tempfile.TemporaryDirectory(prefix="stabint-pov-") as tmp:
        running = []
        for j in range(jobs):
            sub = os.path.join(tmp, str(j))
            os.makedirs(sub)
            running.append((sub, _render_chunk(view, frames[bounds[j]:bounds[j + 1]], sub, int(bounds[j]))))
        for sub, proc in running:
            _, err = proc.communicate()
            if proc.returncode != 0:
                raise RuntimeError(f"povray failed ({proc.returncode}): {err.decode(errors='replace')[-2000:]}")
        written = []
        for j, (sub, _) in enumerate(running):
            if os.path.exists(os.path.join(sub, "out.png")):
                os.rename(os.path.join(sub, "out.png"), os.path.join(sub, f"out{bounds[j] + 1}.png"))
            written += [os.path.join(sub, f) for f in os.listdir(sub) if f.startswith("out") and f.endswith(".png")]
        # POV-Ray numbers the frames out<frame>.png with the frame number zero-padded.
        written.sort(key=lambda f: int(os.path.basename(f)[3:-4]))
        if len(written) != len(frames):
            raise RuntimeError(f"povray wrote {len(written)} frames for {len(frames)}")
        for src, out in zip(written, out_pngs):
            shutil.move(src, out)


def save_gif(images, path, frame_ms):
    """Writes the RGB `images` as a looping GIF with one palette for all frames (so colours do
    not flicker between frames), taken from eight frames spread over the animation side by
    side, without dithering (dithered frames compress to twice the size). Deterministic."""
    from PIL import Image

    pick = [images[k] for k in np.linspace(0, len(images) - 1, min(8, len(images))).round().astype(int)]
    sample = Image.new("RGB", (sum(im.width for im in pick), max(im.height for im in pick)))
    x = 0
    for im in pick:
        sample.paste(im, (x, 0))
        x += im.width
    palette = sample.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=frame_ms, loop=0, optimize=False)
