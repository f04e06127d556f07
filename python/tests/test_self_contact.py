"""Self-contact from Python (docs/method.md, "Self-contact"): SimulatorOptions.self_contact_thickness
keeps a cloth dropped onto another above it, where without it the cloth falls through."""
import numpy as np
import pytest

import stabint


def two_cloths():
    """Two 12 x 12 cloths (0.4 m) of one scene: one flat 5 mm above a ground, the other 10 cm above
    it, turned 0.3 rad about the vertical, falling onto it."""
    one = stabint.cloth_grid(nx=12, ny=12, width=0.4, height=0.4)
    n = one.num_particles
    x = np.asarray(one.positions)
    u, w = x[:, 0] - x[:, 0].mean(), x[:, 1] - x[:, 1].mean()
    c, s = np.cos(0.3), np.sin(0.3)
    lower = np.column_stack([u, np.full(n, 0.005), w])
    upper = np.column_stack([c * u - s * w, np.full(n, 0.1), s * u + c * w])
    scene = stabint.Scene()
    scene.positions = scene.rest_positions = np.vstack([lower, upper])
    scene.velocities = np.zeros((2 * n, 3))
    scene.masses = np.concatenate([np.asarray(one.masses)] * 2)
    springs = []
    for offset in (0, n):
        for spring in one.springs:
            copy = stabint.Spring(a=spring.a + offset, b=spring.b + offset, rest_length=spring.rest_length,
                                  stiffness=spring.stiffness)
            springs.append(copy)
    scene.springs = springs
    triangles = np.asarray(one.triangles)
    scene.triangles = np.vstack([triangles, triangles + n])
    scene.colliders = [stabint.Collider(shape=stabint.ColliderShape.Plane, friction=0.5)]
    return scene, n


@pytest.mark.parametrize("thickness", [0.0, 3e-3])
def test_a_cloth_dropped_onto_another_stays_above_it_with_self_contact(thickness):
    scene, n = two_cloths()
    sim = stabint.Simulator(scene, stabint.SimulatorOptions(self_contact_thickness=thickness))
    # Each of the upper cloth's vertices over the lower one's middle against the lower cloth's
    # vertex nearest to it across the ground (2.5 cm apart at most): without self-contact the upper
    # one ends below it somewhere (both on the ground), with it always above.
    lowest_gap = np.inf
    for _ in range(30):
        sim.step()
        x = sim.positions
        lower, upper = x[:n], x[n:]
        inside = upper[(np.abs(upper[:, 0]) < 0.15) & (np.abs(upper[:, 2]) < 0.15)]
        across = np.linalg.norm(inside[:, None, [0, 2]] - lower[None, :, [0, 2]], axis=2)
        nearest = lower[across.argmin(axis=1)]
        lowest_gap = min(lowest_gap, (inside[:, 1] - nearest[:, 1]).min())
    if thickness == 0.0:
        assert lowest_gap < 0.0
    else:
        assert lowest_gap > 0.0


def test_a_negative_thickness_is_refused_naming_the_option():
    with pytest.raises(stabint.InvalidInputError, match="self_contact_thickness"):
        stabint.Simulator(stabint.builtin_scene("cloth"), stabint.SimulatorOptions(self_contact_thickness=-1.0))


def test_a_start_that_crosses_itself_is_refused_and_so_is_such_a_state():
    scene, n = two_cloths()
    x = np.asarray(scene.positions).copy()
    # The upper cloth stood on its edge through the lower one: they cross along a line.
    upper = x[n:].copy()
    x[n:] = np.column_stack([upper[:, 0], 0.005 + upper[:, 2], np.full(n, 0.0137)])
    crossing, _ = two_cloths()
    crossing.positions = crossing.rest_positions = x
    options = stabint.SimulatorOptions(self_contact_thickness=3e-3)
    with pytest.raises(stabint.InvalidInputError, match=r"self-contact: surface triangle \d+ \(particles"):
        stabint.Simulator(crossing, options)
    sim = stabint.Simulator(scene, options)
    before = np.array(sim.positions)
    with pytest.raises(stabint.InvalidInputError, match="cross"):
        sim.set_state(x, np.zeros_like(x))
    assert np.array_equal(np.asarray(sim.positions), before)
