"""stabint.distributed keeps finished work (issue 46, item 4): scene parameters are checked in
the caller before any task is sent (a typo, a NaN), a batch that fails in its worker gives its
scenes an error naming the scene and the cause while every other batch's results come back, and
errors="raise" still raises at once, naming the scene."""

import functools
import logging

import numpy as np
import pytest

import stabint
import stabint.distributed as distributed_module
from stabint.distributed import BuiltinScene, Cell, SceneParameterError, grid, plan, sweep

FRAMES = 6


@pytest.fixture
def local(monkeypatch):
    """Runs sweeps in this process even when another test module left a default Dask client."""
    monkeypatch.setattr(distributed_module, "_default_client", lambda: None)


@pytest.fixture
def counted(monkeypatch):
    """Counts the batches that start running (locally: _run is what a worker runs)."""
    calls = []
    run = distributed_module._run

    def counting(batch, *args, **kwargs):
        calls.append(batch.indices)
        return run(batch, *args, **kwargs)

    monkeypatch.setattr(distributed_module, "_run", counting)
    return calls


FACTORY_CALLS = []


def counting_factory():
    FACTORY_CALLS.append(1)
    return stabint.chain_pendulum()


def failing_factory():
    raise ValueError("the mesh server is down")


LOST = []


def losing_run(batch, *args):
    if batch.number == 1:
        raise RuntimeError("worker lost")
    return LOST[0](batch, *args)


def good_scenes():
    return [BuiltinScene("chain"), BuiltinScene("chain", {"stiffness": 1e3}), BuiltinScene("chain", {"particles": 3}),
            BuiltinScene("chain", {"stiffness": 1e4}), BuiltinScene("cloth", {"nx": 4, "ny": 4, "pinned": [0]})]


def assert_same_result(a, b):
    assert a.index == b.index and a.key == b.key and a.batch == b.batch and a.error == b.error == ""
    assert np.array_equal(a.frames, b.frames) and np.array_equal(a.times, b.times)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.velocities, b.velocities)
    assert a.reports.keys() == b.reports.keys()
    for name in a.reports:
        assert np.array_equal(a.reports[name], b.reports[name]), name
    assert a.refusal == b.refusal and a.refused_at == b.refused_at


# --- checked before any task is sent ----------------------------------------------------------

def test_a_parameter_typo_is_refused_before_any_task_runs(local, counted):
    FACTORY_CALLS.clear()
    scenes = [counting_factory, BuiltinScene("chain"), BuiltinScene("cloth", {"nxx": 8})]
    typo = (r"sweep: scene 2: BuiltinScene\('cloth', \{'nxx': 8\}\): cloth: params: unknown field 'nxx' "
            r"\(did you mean 'nx'\?")
    with pytest.raises(stabint.InvalidInputError, match=typo) as e:
        sweep(scenes, None, FRAMES, batch_size=1)
    # The builder's own class too (a FileFormatError naming the builder), so either except works.
    assert isinstance(e.value, SceneParameterError) and isinstance(e.value, stabint.FileFormatError)
    assert (e.value.file, e.value.line) == ("cloth", 0)
    assert counted == [] and FACTORY_CALLS == []  # nothing ran: no batch, not even the factory
    with pytest.raises(stabint.InvalidInputError, match="scene 2: .*unknown field 'nxx'"):
        plan(scenes, batch_size=1)
    # An unknown builder, and a value the builder refuses, are found here as well.
    with pytest.raises(SceneParameterError, match=r"scene 1: .*unknown built-in scene 'clth' \(did you mean 'cloth'\?"):
        sweep([BuiltinScene("chain"), BuiltinScene("clth")], None, FRAMES)
    with pytest.raises(SceneParameterError, match="scene 0: .*nx = 1 must be >= 2"):
        sweep([BuiltinScene("cloth", {"nx": 1})], None, FRAMES)
    assert counted == []


def test_a_grid_axis_with_an_unknown_name_is_refused_at_once(local, counted):
    with pytest.raises(SceneParameterError, match=r"grid: axis 'stretch_stifness' is neither a parameter of the cloth "
                                                  r"builder nor a SimulatorOptions field \(did you mean "
                                                  r"'stretch_stiffness'\?"):
        grid("cloth", stretch_stifness=[1e2, 1e3])
    with pytest.raises(SceneParameterError, match="did you mean 'time_step'"):
        grid("cloth", time_stepp=[1 / 30, 1 / 60])
    # A cell made by hand with a typo in its parameters: the sweep and the plan refuse it.
    cells = grid("chain", stiffness=[1e2, 1e3]) + [Cell(BuiltinScene("chain", {"stifness": 1e4}), key={"k": 3})]
    with pytest.raises(stabint.InvalidInputError, match=r"sweep: scene 2: .*\(key \{'k': 3\}\): .*"
                                                        r"unknown field 'stifness' \(did you mean 'stiffness'\?"):
        plan(cells)
    with pytest.raises(stabint.InvalidInputError, match="sweep: scene 2: "):
        sweep(cells, None, FRAMES)
    assert counted == []


@pytest.mark.parametrize("value, said", [(float("nan"), "is NaN"), (float("inf"), r"is infinite \(inf\)"),
                                         (-np.inf, r"is infinite \(-inf\)")])
def test_a_non_finite_parameter_is_named_as_such_not_malformed_json(local, counted, value, said):
    scenes = [BuiltinScene("chain"), BuiltinScene("chain"), BuiltinScene("cloth", {"stretch_stiffness": value})]
    with pytest.raises(stabint.InvalidInputError, match=rf"sweep: scene 2: .*cloth: params.stretch_stiffness {said}; "
                                                        "a parameter must be a finite number") as e:
        sweep(scenes, None, FRAMES)
    assert "malformed JSON" not in str(e.value)
    # Inside a list parameter, and from a grid axis: the element and the cell are named.
    with pytest.raises(SceneParameterError, match=rf"scene 0: .*params.gravity\[1\] {said}"):
        sweep([BuiltinScene("chain", {"gravity": [0.0, value, 0.0]})], None, FRAMES)
    with pytest.raises(SceneParameterError, match=rf"scene 1: .*params.stiffness {said}"):
        plan(grid("chain", stiffness=[1e3, value]))
    # BuiltinScene.build says the same outside a sweep.
    with pytest.raises(SceneParameterError, match=rf"params.stretch_stiffness {said}"):
        BuiltinScene("cloth", {"stretch_stiffness": value}).build()
    assert counted == []


def test_numpy_values_in_a_grid_are_parameters_like_python_numbers(local):
    # A grid over np.arange / np.array values (numpy scalars) builds the same scenes as Python numbers.
    from_numpy = sweep(grid("chain", particles=np.arange(3, 5), stiffness=np.array([1e2])), None, FRAMES)
    from_python = sweep(grid("chain", particles=[3, 4], stiffness=[1e2]), None, FRAMES)
    for a, b in zip(from_numpy, from_python):
        assert np.array_equal(a.positions, b.positions) and a.error == ""


# --- a failing batch keeps the others' results ------------------------------------------------

def check_failed_batch(results, clean):
    """Batches [0, 1], [2, 3], [4]: scene 2 is a factory that raised; batch 1 is reported, the
    others equal the same batches without the failure, bit for bit."""
    assert [r.index for r in results] == [0, 1, 2, 3, 4]
    for i in (0, 1, 4):
        assert_same_result(results[i], clean[i])
    failed, neighbour = results[2], results[3]
    assert failed.error == ("sweep: scene 2: factory test_sweep_failures.failing_factory: the factory raised "
                            "ValueError: the mesh server is down")
    assert neighbour.error.startswith("sweep: scene 3: BuiltinScene('chain', {'stiffness': 10000.0}): its batch 1 "
                                      "(scenes [2, 3]) failed: sweep: scene 2: factory ")
    assert "ValueError: the mesh server is down" in neighbour.error
    for r in (failed, neighbour):
        assert r.batch == 1 and r.refusal == r.error and r.refused_at == 0  # refused before its first step
        assert r.frames.shape == (0,) and r.times.shape == (0,) and r.positions.shape[0] == 0
        assert r.velocities.shape[0] == 0 and all(len(v) == 0 for v in r.reports.values())


def test_a_factory_raising_in_one_batch_keeps_the_other_batches_locally(local, counted):
    scenes = good_scenes()
    clean = sweep(scenes, None, FRAMES, batch_size=2)
    scenes[2] = failing_factory
    counted.clear()
    results = sweep(scenes, None, FRAMES, batch_size=2)
    assert counted == [(0, 1), (2, 3), (4,)]  # the batch after the failure ran too
    check_failed_batch(results, clean)


def test_a_factory_raising_in_one_batch_keeps_the_other_batches_on_dask():
    distributed = pytest.importorskip("distributed")
    scenes = good_scenes()
    with distributed.LocalCluster(n_workers=1, processes=False, threads_per_worker=2, dashboard_address=None,
                                  silence_logs=logging.CRITICAL) as cluster, distributed.Client(cluster) as client:
        clean = sweep(scenes, None, FRAMES, batch_size=2, client=client)
        scenes[2] = failing_factory
        results = sweep(scenes, None, FRAMES, batch_size=2, client=client)
        check_failed_batch(results, clean)
        # The raising option: the first failure reaches the caller, naming the scene.
        with pytest.raises(stabint.InvalidInputError, match=r"sweep: scene 2: factory .*failing_factory: the factory "
                                                            r"raised ValueError: the mesh server is down"):
            sweep(scenes, None, FRAMES, batch_size=2, client=client, errors="raise")
        # A task that fails outside the batch runner (a lost worker, a task that cannot be
        # unpickled) is reported as well.
        scenes[2] = BuiltinScene("chain", {"particles": 3})
        LOST.clear()
        LOST.append(distributed_module._run)
        try:
            distributed_module._run = losing_run
            results = sweep(scenes, None, FRAMES, batch_size=2, client=client)
        finally:
            distributed_module._run = LOST[0]
        for i in (0, 1, 4):
            assert_same_result(results[i], clean[i])
        for i in (2, 3):
            assert results[i].error.startswith(f"sweep: scene {i}: BuiltinScene('chain', ")
            assert results[i].error.endswith("its batch 1 (scenes [2, 3]) failed: RuntimeError: worker lost")
            assert results[i].frames.shape == (0,) and results[i].refused_at == 0


def test_the_error_names_the_scene_and_keeps_the_librarys_class(local):
    # A factory whose loader refuses: FileFormatError kept, with the scene's index and description.
    bad = functools.partial(stabint.chain_pendulum, stiffnes=3.0)
    results = sweep([BuiltinScene("chain"), bad], None, FRAMES, batch_size=1)
    assert results[0].error == "" and results[0].positions.shape == (FRAMES + 1, 10, 3)
    assert results[1].error.startswith("sweep: scene 1: factory partial(stabint.chain_pendulum, stiffnes=3.0): the "
                                       "factory raised FileFormatError: chain: params: unknown field 'stiffnes'")
    with pytest.raises(stabint.FileFormatError, match=r"sweep: scene 1: factory partial\(stabint.chain_pendulum"):
        sweep([BuiltinScene("chain"), bad], None, FRAMES, batch_size=1, errors="raise")
    # A factory returning something else.
    results = sweep([lambda: "a scene", BuiltinScene("chain")], None, FRAMES, batch_size=1)
    assert results[0].error.startswith("sweep: scene 0: factory ")
    assert "the factory returned str, not a stabint.Scene" in results[0].error
    assert results[1].error == ""


def test_a_batch_the_batch_simulator_refuses_is_reported_and_the_others_run(local):
    # A factory's gravity is known only where it runs: the BatchSimulator refuses its batch there.
    def upside_down():
        scene = stabint.chain_pendulum()
        scene.gravity = np.array([0.0, 9.81, 0.0])
        return scene

    clean = sweep([BuiltinScene("chain")] * 2, None, FRAMES, batch_size=2)
    results = sweep([BuiltinScene("chain"), BuiltinScene("chain"), BuiltinScene("chain"), upside_down], None, FRAMES,
                    batch_size=2)
    for i in (0, 1):
        assert_same_result(results[i], clean[i])
    # Both scenes of the refused batch are named, and the cause says which scene's gravity differs.
    assert results[2].error.startswith("sweep: scene 2: BuiltinScene('chain', {}): its batch 1 (scenes [2, 3]) "
                                       "failed: ")
    assert results[3].error.startswith("sweep: scene 3: factory test_sweep_failures.test_a_batch_the_batch_simulator_"
                                       "refuses_is_reported_and_the_others_run.<locals>.upside_down: its batch 1 ")
    for r in results[2:]:
        assert r.error.endswith("failed: sweep: the batch of scenes [2, 3]: scene 1: gravity differs from scene 0's; "
                                "the scenes of a batch share one gravity (the batch's scene 1 is scene 3)")
        assert r.frames.shape == (0,) and r.refused_at == 0 and r.refusal == r.error
    # Known gravities are checked before any task is sent.
    flipped = upside_down()
    with pytest.raises(stabint.InvalidInputError, match=r"the batch of scenes \[0, 1\]: scene 1: Scene 'chain': "
                                                        r"gravity \[0.0, 9.81, 0.0\] differs from scene 0's"):
        plan([BuiltinScene("chain"), flipped])


class FlakyBatch:
    """A BatchSimulator whose fourth step raises (a device lost mid-run)."""

    def __init__(self, *args):
        self._sim = stabint.BatchSimulator(*args)
        self._steps = 0

    def step(self):
        self._steps += 1
        if self._steps == 4:
            raise stabint.OpenCLError("device lost")
        return self._sim.step()

    def __getattr__(self, name):
        return getattr(self._sim, name)


def test_a_step_raising_keeps_the_frames_before_it(local, monkeypatch):
    scenes = [BuiltinScene("chain"), BuiltinScene("chain", {"stiffness": 1e3})]
    clean = sweep(scenes, None, FRAMES, batch_size=2, stride=2)
    monkeypatch.setattr(distributed_module, "BatchSimulator", FlakyBatch)
    results = sweep(scenes, None, FRAMES, batch_size=2, stride=2)
    for r, c in zip(results, clean):
        assert r.error.startswith(f"sweep: scene {r.index}: BuiltinScene('chain', ")
        assert "failed: sweep: the batch of scenes [0, 1]: step 4: OpenCLError: device lost" in r.error
        assert r.refused_at == 4 and r.refusal == r.error
        assert np.array_equal(r.frames, [0, 2])  # recorded every 2nd frame; frames 1-3 completed
        assert np.array_equal(r.positions, c.positions[:2]) and np.array_equal(r.velocities, c.velocities[:2])
        assert all(np.array_equal(r.reports[n], c.reports[n][:4]) for n in r.reports)
    with pytest.raises(stabint.OpenCLError, match=r"sweep: the batch of scenes \[0, 1\]: step 4: OpenCLError: device"):
        sweep(scenes, None, FRAMES, batch_size=2, errors="raise")


# --- the option -------------------------------------------------------------------------------

def test_raise_at_once_stays_available(local, counted):
    scenes = good_scenes()
    scenes[2] = failing_factory
    expected = (r"^sweep: scene 2: factory test_sweep_failures.failing_factory: the factory raised ValueError: "
                r"the mesh server is down$")
    with pytest.raises(stabint.InvalidInputError, match=expected) as e:
        sweep(scenes, None, FRAMES, batch_size=2, errors="raise")
    assert isinstance(e.value.__cause__, ValueError)
    assert counted == [(0, 1), (2, 3)]  # stopped at the failing batch
    with pytest.raises(stabint.InvalidInputError, match="errors must be 'report' or 'raise', got 'ignore'"):
        sweep(scenes, None, FRAMES, errors="ignore")


def test_good_input_gives_the_same_results_with_either_option(local):
    scenes = good_scenes()
    reported = sweep(scenes, {"integrator": "EnergyBlend"}, FRAMES, batch_size=2)
    raised = sweep(scenes, {"integrator": "EnergyBlend"}, FRAMES, batch_size=2, errors="raise")
    for a, b in zip(reported, raised):
        assert_same_result(a, b)
