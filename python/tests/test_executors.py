"""stabint.distributed.sweep on the executor a user already runs (issue 47): a process pool, a
thread pool and Ray (where it is installed) give the same bits as the batches stepped in this
process; progress comes back batch by batch (sweep_iter, on_batch); a failing batch does not
hide the others; an executor of another kind is refused before anything runs."""

import concurrent.futures
import functools
import multiprocessing

import numpy as np
import pytest

import stabint
import stabint.distributed as distributed_module
from stabint.distributed import BuiltinScene, plan, run_batch, sweep, sweep_iter

FRAMES = 12
OPTIONS = {"integrator": "EnergyBlend", "iterations": 10}


@pytest.fixture(autouse=True)
def local(monkeypatch):
    """executor=None runs in this process even when another test module left a default Dask client."""
    monkeypatch.setattr(distributed_module, "_default_client", lambda: None)


def scenes():
    return [BuiltinScene("cloth", {"nx": 5, "ny": 5, "pinned": [0], "stretch_stiffness": 1e3}),
            stabint.chain_pendulum(stiffness=1e3),
            functools.partial(stabint.chain_pendulum, stiffness=1e2),
            BuiltinScene("tetbar", {"nx": 3, "ny": 1, "nz": 1}),
            BuiltinScene("cloth", {"nx": 4, "ny": 6, "pinned": [0, 3]})]


def reference():
    """Each batch of plan() stepped here by run_batch: what every executor must reproduce."""
    items = scenes()
    expected = {}
    for indices in plan(items, OPTIONS, batch_size=2):
        built = [items[i].build() if isinstance(items[i], BuiltinScene) else
                 items[i]() if callable(items[i]) else items[i] for i in indices]
        for i, r in zip(indices, run_batch(built, OPTIONS, FRAMES)):
            expected[i] = r
    return expected


def assert_same_bits(results, expected):
    assert [r.index for r in results] == list(range(len(expected)))
    for r in results:
        e = expected[r.index]
        assert r.error == "" and r.refusal == ""
        assert np.array_equal(r.positions, e.positions) and np.array_equal(r.velocities, e.velocities)
        for name in ("total", "target", "alpha", "iterations", "branch"):
            assert np.array_equal(r.reports[name], e.reports[name]), name


@pytest.fixture(scope="module")
def expected():
    return reference()


def test_a_process_pool_gives_the_bits_of_this_process(expected):
    # spawn, not fork: a forked child would inherit this process's library thread pool mid-state.
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        results = sweep(scenes(), OPTIONS, FRAMES, batch_size=2, executor=pool)
    assert_same_bits(results, expected)


def test_a_thread_pool_gives_the_bits_of_this_process(expected):
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        results = sweep(scenes(), OPTIONS, FRAMES, batch_size=2, executor=pool)
    assert_same_bits(results, expected)


def test_no_executor_gives_the_bits_of_run_batch(expected):
    assert_same_bits(sweep(scenes(), OPTIONS, FRAMES, batch_size=2), expected)


def test_ray_gives_the_bits_of_this_process(expected):
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        assert_same_bits(sweep(scenes(), OPTIONS, FRAMES, batch_size=2, executor=ray), expected)
    finally:
        ray.shutdown()
    with pytest.raises(stabint.InvalidInputError, match=r"ray.init\(\)"):
        sweep(scenes(), OPTIONS, FRAMES, executor=ray)


def test_progress_comes_back_batch_by_batch(expected):
    seen = []
    results = sweep(scenes(), OPTIONS, FRAMES, batch_size=2, on_batch=lambda rs: seen.append([r.index for r in rs]))
    assert sorted(seen) == plan(scenes(), OPTIONS, batch_size=2)  # once per batch, with its scenes
    assert_same_bits(results, expected)
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        batches = list(sweep_iter(scenes(), OPTIONS, FRAMES, batch_size=2, executor=pool))
    assert sorted([r.index for r in b] for b in batches) == plan(scenes(), OPTIONS, batch_size=2)
    assert_same_bits(sorted((r for b in batches for r in b), key=lambda r: r.index), expected)


def not_a_scene():
    return 42


def test_a_failing_batch_in_a_pool_does_not_hide_the_others(expected):
    items = scenes()
    items[2] = not_a_scene  # batch [2, 3] fails in its worker
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        results = sweep(items, OPTIONS, FRAMES, batch_size=2, executor=pool)
        assert "scene 2" in results[2].error and results[3].error
        for i in (0, 1, 4):
            assert results[i].error == "" and np.array_equal(results[i].positions, expected[i].positions)
        with pytest.raises(stabint.InvalidInputError, match="scene 2"):
            sweep(items, OPTIONS, FRAMES, batch_size=2, executor=pool, errors="raise")


def test_an_executor_of_another_kind_is_refused_before_anything_runs():
    with pytest.raises(stabint.InvalidInputError, match="executor must be a dask.distributed.Client"):
        sweep(scenes(), OPTIONS, FRAMES, executor="processes")
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        with pytest.raises(stabint.InvalidInputError, match="not both"):
            sweep(scenes(), OPTIONS, FRAMES, executor=pool, client=pool)
    with pytest.raises(stabint.InvalidInputError, match="on_batch must be callable"):
        sweep(scenes(), OPTIONS, FRAMES, on_batch=3)
