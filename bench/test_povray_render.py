#!/usr/bin/python3
"""Self-test of bench/povray_render.py (ctest `povray_render`): two unit squares side by side,
tilted 45 degrees to face down towards the camera as a hanging cloth does, the first wound
towards the camera, the second away. With the cloth's two colours the first must show its front
colour (blue) and the second its back colour (ochre), both lit (with the key light overhead, such
a cloth came out black where it faced the camera), and two renders of the same frame must give
the same pixels. Exits non-zero on failure."""
import os
import sys
import tempfile

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import povray_render as pr  # noqa: E402

FRONT, BACK = (0.30, 0.52, 0.75), (0.88, 0.60, 0.30)


def main():
    if not pr.available():
        sys.exit(f"test_povray_render: {pr.POVRAY} missing (scripts/install-deps.sh installs povray)")
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 0.7, 0.7], [0, 0.7, 0.7]], float)
    towards = np.array([[0, 1, 2], [0, 2, 3]])  # normal (0, -1, 1): down, towards an eye on the +z side
    away = towards[:, ::-1]
    right = square + [1.5, 0.0, 0.0]
    view = pr.View([-0.2, -0.3, -1.0], np.concatenate([square, right]), -0.5, 200, 100, antialias=0)
    frame = [(square, towards, FRONT, BACK), (right, away, FRONT, BACK)]
    with tempfile.TemporaryDirectory() as tmp:
        outs = [os.path.join(tmp, f"{k}.png") for k in range(2)]
        pr.render(view, [frame, frame], outs, jobs=2)
        a, b = (np.asarray(Image.open(o).convert("RGB"), float) / 255.0 for o in outs)
    failures = []
    if not np.array_equal(a, b):
        failures.append("two renders of the same frame differ")
    for name, centre, want in (("towards", square.mean(axis=0), "blue"), ("away", right.mean(axis=0), "ochre")):
        col = int(pr.image_x(view, centre) * view.width)
        pixel = a[view.height // 2, col]
        colour = "blue" if pixel[2] > pixel[0] else "ochre"
        if colour != want:
            failures.append(f"square wound {name}: {colour} {pixel.round(2)}, want {want}")
        if pixel.mean() < 0.25:
            failures.append(f"square wound {name}: dark {pixel.round(2)} (lit side shaded black?)")
    for f in failures:
        print("test_povray_render: FAIL:", f)
    if failures:
        sys.exit(1)
    print("test_povray_render: 1 passed, 0 failed")


if __name__ == "__main__":
    main()
