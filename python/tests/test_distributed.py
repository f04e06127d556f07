"""stabint.distributed: sweeps on a local Dask cluster of worker processes (loopback only, no
network) against the same BatchSimulator stepped in this process, bit for bit, and its errors."""

import functools
import logging
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import stabint

distributed = pytest.importorskip("distributed")  # the [distributed] extra; requirements.txt pins it

from stabint.distributed import BuiltinScene, Cell, grid, plan, sweep  # noqa: E402

FRAMES = 30
# The blend, so that the reports carry decisions (branch, alpha) as well as energies.
OPTIONS = {"integrator": "EnergyBlend", "iterations": 10}


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None,
                                       silence_logs=logging.CRITICAL)
    with cluster, distributed.Client(cluster) as c:
        yield c


def mixed_scenes():
    """One scene of each kind of description a sweep takes: built-in by name, a Scene (sent as
    its JSON text), a factory (functools.partial of a builder: picklable), and a triangle cloth."""
    return [
        BuiltinScene("cloth", {"nx": 6, "ny": 6, "pinned": [0], "stretch_stiffness": 1e2}),
        stabint.cloth_grid(nx=5, ny=7, pinned=[0], stretch_stiffness=1e4),
        functools.partial(stabint.chain_pendulum, stiffness=1e3),
        BuiltinScene("tetbar", {"nx": 3, "ny": 1, "nz": 1}),
        BuiltinScene("cloth", {"nx": 5, "ny": 5, "pinned": [0], "model": "triangles"}),
    ]


def built(description):
    if isinstance(description, BuiltinScene):
        return description.build()
    return stabint.Scene(description) if isinstance(description, stabint.Scene) else description()


def local_batch(scenes, frames):
    """What a worker should compute: one BatchSimulator of `scenes` stepped here, every frame's
    positions and each step's report."""
    batch = stabint.BatchSimulator(scenes, stabint.SimulatorOptions(integrator=stabint.Integrator.EnergyBlend,
                                                                    iterations=10))
    positions = [[batch.positions(s)] for s in range(len(scenes))]
    reports = [[] for _ in scenes]
    for _ in range(frames):
        step = batch.step()
        for s in range(len(scenes)):
            positions[s].append(batch.positions(s))
            reports[s].append((step.scenes[s], step.refusals[s]))
    return [np.array(p) for p in positions], reports


def test_sweep_on_two_workers_equals_the_same_batches_stepped_here_bit_for_bit(client):
    scenes = mixed_scenes()
    with distributed.get_task_stream(client) as tasks:
        results = sweep(scenes, OPTIONS, FRAMES, batch_size=2, client=client)
    # Three batches, three tasks, run in the worker processes (not in this one).
    assert len(tasks.data) == 3
    workers = client.run(os.getpid)
    assert {t["worker"] for t in tasks.data} <= set(workers) and os.getpid() not in workers.values()
    batches = plan(scenes, OPTIONS, batch_size=2)
    assert batches == [[0, 1], [2, 3], [4]]  # one options group, cut into runs of 2
    assert [r.index for r in results] == list(range(len(scenes)))
    assert {r.batch for r in results} == {0, 1, 2}
    for indices in batches:
        positions, reports = local_batch([built(scenes[i]) for i in indices], FRAMES)
        for s, i in enumerate(indices):
            r = results[i]
            # The CPU reference is deterministic (docs/batch_design.md; its threads too,
            # tests/test_cpu_threads.cpp): the same batch in a worker process gives the same bits.
            assert r.positions.shape == positions[s].shape
            assert np.array_equal(r.positions, positions[s])
            assert np.array_equal(r.frames, np.arange(FRAMES + 1))
            own = [rep for rep, _ in reports[s]]
            assert np.array_equal(r.reports["total"][1:], [rep.energy.total for rep in own])
            assert np.array_equal(r.reports["kinetic"][1:], [rep.energy.kinetic for rep in own])
            assert np.array_equal(r.reports["target"][1:], [rep.target for rep in own])
            assert np.array_equal(r.reports["alpha"][1:], [rep.alpha for rep in own])
            assert np.array_equal(r.reports["iterations"][1:], [rep.iterations for rep in own])
            assert list(r.reports["branch"][1:]) == [stabint.blend_branch_name(rep.branch) for rep in own]
            assert np.array_equal(r.times, [0.0] + [rep.time for rep in own])
            assert r.refusal == "" and r.refused_at == -1
            assert all(refusal == "" for _, refusal in reports[s])
    # The blend decided more than one way across the sweep: the comparison covered decisions.
    assert len({b for r in results for b in r.reports["branch"][1:]}) >= 2


def test_another_batch_size_agrees_to_round_off(client):
    scenes = mixed_scenes()
    pairs = sweep(scenes, OPTIONS, FRAMES, batch_size=2, client=client)
    whole = sweep(scenes, OPTIONS, FRAMES, batch_size=len(scenes), client=client)
    assert {r.batch for r in whole} == {0}
    for a, b in zip(pairs, whole):
        # Another batch is another block-diagonal matrix: its fill-reducing ordering may order a
        # scene's block differently, so the library promises agreement to round-off only
        # (docs/batch_design.md, README "Many scenes at once"). 1e-9 m is ~1e5 ulps of these
        # O(1 m) positions after 30 steps: round-off, far below any difference of dynamics.
        np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=1e-9)
        np.testing.assert_allclose(a.reports["total"], b.reports["total"], rtol=1e-9)


def test_grid_groups_cells_by_options_and_keeps_input_order(client):
    cells = grid(BuiltinScene("chain", {"particles": 4}), stiffness=[1e2, 1e3, 1e4], time_step=[1 / 30, 1 / 60])
    assert [c.key for c in cells[:2]] == [{"stiffness": 1e2, "time_step": 1 / 30},
                                          {"stiffness": 1e2, "time_step": 1 / 60}]
    # One options group per time step (a BatchSimulator has one h), in order of first appearance.
    assert plan(cells, batch_size=8) == [[0, 2, 4], [1, 3, 5]]
    results = sweep(cells, None, 12, stride=5, velocities=False, client=client)
    assert [r.key for r in results] == [c.key for c in cells]
    assert np.array_equal(results[0].frames, [0, 5, 10, 12])  # every 5th, and always the last
    assert results[0].velocities is None
    for r in results:
        assert r.options["time_step"] == r.key["time_step"]
        assert r.times[-1] == pytest.approx(12 * r.key["time_step"], rel=1e-12)
        # Each cell is the scene its key describes, stepped alone: the sweep changed nothing.
        sim = stabint.Simulator(stabint.chain_pendulum(particles=4, stiffness=r.key["stiffness"]),
                                stabint.SimulatorOptions(time_step=r.key["time_step"]))
        for _ in range(12):
            sim.step()
        np.testing.assert_allclose(r.positions[-1], sim.positions, rtol=0, atol=1e-9)


def test_a_refused_scene_is_reported_and_the_others_step_on():
    # Symplectic Euler at h = 1/60 s on 3 particles of 1/30 kg: stable below k = (2/h)^2 m =
    # 480 N/m; the 1e8 N/m chain is far past that, and the energy limit refuses the step that
    # leaves H* (its own Simulator raises EnergyLimitError); the 10 N/m chain swings on.
    options = {"integrator": "SymplecticEuler", "time_step": 1 / 60, "energy_limit": 1.0}
    soft, stiff = (stabint.chain_pendulum(particles=3, stiffness=k, pin_stiffness=k) for k in (10.0, 1e8))
    results = sweep([soft, stiff], options, 20, client=None)  # no client: in this process
    assert results[0].refusal == "" and results[0].refused_at == -1
    assert results[1].refused_at > 0 and "energy" in results[1].refusal.lower()
    frozen = results[1].positions[results[1].refused_at:]
    assert (frozen == frozen[0]).all()  # the refused scene keeps its last accepted state
    sim = stabint.Simulator(stiff, stabint.SimulatorOptions(integrator=stabint.Integrator.SymplecticEuler,
                                                            time_step=1 / 60, energy_limit=1.0))
    with pytest.raises(stabint.EnergyLimitError) as raised:
        for _ in range(20):
            sim.step()
    assert raised.value.step + 1 == results[1].refused_at  # the same step its own Simulator refuses


def test_batches_of_one_are_their_simulators():
    # With batch_size 1 each scene is its own Simulator, bit for bit, CG included.
    options = {"integrator": "BackwardEuler", "global_solve": "ConjugateGradient"}
    results = sweep([BuiltinScene("chain"), BuiltinScene("chain", {"stiffness": 1e3})], options, 5, batch_size=1,
                    client=None)
    sim = stabint.Simulator(stabint.chain_pendulum(), stabint.SimulatorOptions(
        integrator=stabint.Integrator.BackwardEuler, global_solve=stabint.GlobalSolve.ConjugateGradient))
    for _ in range(5):
        sim.step()
    assert (results[0].positions[-1] == sim.positions).all()


def test_bad_input_is_an_invalid_input_error_naming_the_problem(client):
    with pytest.raises(stabint.InvalidInputError, match="non-empty list"):
        sweep([], OPTIONS, 10, client=client)
    with pytest.raises(stabint.InvalidInputError, match="scene 1: expected a stabint.Scene"):
        sweep([BuiltinScene("chain"), "chain"], OPTIONS, 10, client=client)
    with pytest.raises(stabint.InvalidInputError, match="scene 0: options: unknown SimulatorOptions field 'h'"):
        sweep([Cell(BuiltinScene("chain"), {"h": 0.01})], OPTIONS, 10, client=client)
    with pytest.raises(stabint.InvalidInputError, match="batch_size must be an integer >= 1"):
        sweep([BuiltinScene("chain")], OPTIONS, 10, batch_size=0, client=client)
    # Option values the library refuses, before any task.
    with pytest.raises(stabint.InvalidInputError, match="scene 0: simulator options: time_step"):
        sweep([BuiltinScene("chain")], {"time_step": -1.0}, 10, client=client)
    # Scenes of one options group must share gravity: the worker's BatchSimulator says which
    # batch, and the error reaches the caller with its class.
    upside_down = stabint.chain_pendulum()
    upside_down.gravity = np.array([0.0, 9.81, 0.0])
    with pytest.raises(stabint.InvalidInputError, match=r"the batch of scenes \[0, 1\].*gravity"):
        sweep([BuiltinScene("chain"), upside_down], OPTIONS, 10, client=client)
    # A scene that does not validate is named by its place in the sweep.
    broken = stabint.chain_pendulum()
    broken.masses = -broken.masses
    with pytest.raises(stabint.InvalidInputError, match="sweep: scene 1: "):
        sweep([BuiltinScene("chain"), broken], OPTIONS, 10, client=client)
    # A builder's unknown parameter is the builder's own FileFormatError, with the scene's index.
    with pytest.raises(stabint.FileFormatError, match="sweep: scene 0: .*unknown field 'stiffnes'"):
        sweep([BuiltinScene("chain", {"stiffnes": 1.0})], OPTIONS, 10, client=client)


def test_the_sweep_example_prints_its_table():
    example = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python" / "sweep_stiffness_step.py"
    result = subprocess.run([sys.executable, str(example), "--nx", "6", "--time", "0.5"], capture_output=True,
                            text=True, check=True, timeout=120, env={**os.environ})
    rows = [line.split() for line in result.stdout.splitlines()[2:]]
    assert len(rows) == 9  # 3 stiffnesses x 3 steps
    be, blend = np.array([[float(r[2]), float(r[3])] for r in rows]).T
    # Nothing does work on the swinging cloth: backward Euler's numerical damping loses energy
    # in every cell, and the blend keeps H within 1 % of H(0) (the bound of the cloth_energy
    # example's test; measured here: below 0.3 %).
    assert (be < -1e-3).all()
    assert (np.abs(blend) < 0.01).all()


def test_the_core_package_imports_neither_dask_nor_meshio():
    # Both are optional extras: `import stabint` must work without them, and the submodules
    # load on first use (stabint.distributed, stabint.io).
    code = ("import sys, stabint; assert not {'dask', 'distributed', 'meshio'} & set(sys.modules), sys.modules.keys(); "
            "assert callable(stabint.distributed.sweep) and callable(stabint.io.read_mesh)")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
