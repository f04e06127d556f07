"""Per-frame reporters from Python: Simulator.add_reporter with a callable or a CsvReporter
(include/stabint/reporters.hpp; tests/test_reporters.cpp does the same in C++)."""

import csv

import numpy as np
import pytest

import stabint
from stabint import Integrator


def blend_chain():
    return stabint.Simulator(stabint.chain_pendulum(),
                             stabint.SimulatorOptions(integrator=Integrator.EnergyBlend))


def test_a_callable_reports_every_k_steps_with_the_simulator_and_its_report():
    sim = blend_chain()
    seen = []
    reporter = sim.add_reporter(lambda s, r: seen.append((s, s.step_count, r)), every=3)
    assert isinstance(reporter, stabint.CallbackReporter) and reporter.every == 3
    reports = [sim.step() for _ in range(10)]
    assert [count for _, count, _ in seen] == [3, 6, 9]
    assert all(s is sim for s, _, _ in seen)  # the caller's own Simulator object
    for _, count, r in seen:
        assert r.step == count - 1
        assert r.energy.total == reports[count - 1].energy.total
    assert sim.reporters == [reporter]
    assert sim.remove_reporter(reporter) and not sim.remove_reporter(reporter)
    sim.step()
    assert len(seen) == 3
    sim.add_reporter(print)
    sim.clear_reporters()
    assert sim.reporters == []
    with pytest.raises(stabint.InvalidInputError):
        sim.add_reporter(print, every=0)
    with pytest.raises(TypeError):
        sim.add_reporter(42)


def test_the_csv_reporter_writes_the_reported_steps(tmp_path):
    sim = blend_chain()
    path = tmp_path / "steps.csv"
    writer = stabint.CsvReporter(str(path), every=2)
    writer.initial_row(sim)
    assert sim.add_reporter(writer) is writer
    reports = [sim.step() for _ in range(5)]
    with open(path, newline="") as f:  # each row is flushed: complete while the reporter lives
        rows = list(csv.DictReader(f))
    assert [int(row["frame"]) for row in rows] == [0, 2, 4]
    for row, report in zip(rows[1:], (reports[1], reports[3])):
        assert float(row["time"]) == report.time
        assert float(row["total"]) == report.energy.total
        assert float(row["target"]) == report.target
        assert int(row["iterations"]) == report.iterations
    with pytest.raises(stabint.FileFormatError):
        stabint.CsvReporter(str(tmp_path / "missing" / "x.csv"))


class Stop(Exception):
    pass


def test_an_exception_from_a_reporter_propagates_and_the_step_stands():
    sim, twin = blend_chain(), blend_chain()
    after = []

    def fail_at_two(s, r):
        if s.step_count == 2:
            raise Stop("enough")

    sim.add_reporter(fail_at_two)
    sim.add_reporter(lambda s, r: after.append(s.step_count))
    sim.step()
    twin.step()
    with pytest.raises(Stop, match="enough") as raised:
        sim.step()
    assert any(frame.name == "fail_at_two" for frame in raised.traceback)
    twin.step()
    assert sim.step_count == 2
    np.testing.assert_array_equal(sim.positions, twin.positions)
    assert after == [1]
    sim.step()
    assert after == [1, 3]


def test_an_unwritable_csv_is_a_file_format_error():
    with pytest.raises(stabint.FileFormatError, match="write failed"):
        stabint.CsvReporter("/dev/full")  # the header's flush fails
    # A C++ reporter failing after a step raises ReporterError (a stabint.Error) with its step.
    assert stabint.ReporterError.__bases__ == (stabint.Error,)


def test_a_refused_step_reports_nothing():
    sim = stabint.Simulator(stabint.chain_pendulum(), stabint.SimulatorOptions(
        integrator=Integrator.ImplicitMidpoint, energy_limit=1.0))
    counts = []
    sim.add_reporter(lambda s, r: counts.append(s.step_count))
    with pytest.raises(stabint.EnergyLimitError):
        for _ in range(300):
            sim.step()
    assert counts == list(range(1, sim.step_count + 1))


def test_the_vtk_reporter_writes_a_series_paraview_reads(tmp_path):
    meshio = pytest.importorskip("meshio")  # the [io] extra
    from stabint.io import VtkReporter, read_pvd

    scene = stabint.cloth_grid(nx=5, ny=4)
    sim = stabint.Simulator(scene)
    with VtkReporter(tmp_path / "out", scene, initial=sim) as vtk:
        sim.add_reporter(vtk, 2)
        for _ in range(6):
            sim.step()
    frames = read_pvd(tmp_path / "out" / "frames.pvd")
    # The initial state, then steps 2, 4 and 6, at their times; the last one bit for bit.
    assert [t for t, _ in frames] == pytest.approx([0.0, 2 / 30, 4 / 30, 6 / 30], rel=0, abs=1e-15)
    last = meshio.read(frames[-1][1])
    assert np.array_equal(last.points, sim.positions)
    assert np.array_equal(last.point_data["velocity"], sim.velocities)
