"""stabint.io on hostile input (issue 46): every bad file is a FileFormatError naming it, never a
process exit, a hang or a read without end; read_pvd keeps its paths inside the .pvd's
directory; the VTK writer refuses non-finite numbers and bad cells and then writes nothing."""

import contextlib
import os
import signal

import numpy as np
import pytest

import stabint

meshio = pytest.importorskip("meshio")  # the [io] extra; requirements.txt pins it

import stabint.io  # noqa: E402
from stabint.io import read_mesh, read_pvd, VtkSeriesWriter, write_vtk_series  # noqa: E402


@contextlib.contextmanager
def deadline(seconds=5):
    """Fails the test instead of hanging it (a FIFO opened for reading waits for a writer)."""
    def expired(signum, frame):
        raise AssertionError(f"still running after {seconds} s: the file was opened")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def refused(path, match, file_format=None):
    """read_mesh(path) raises FileFormatError naming the file (message and .file)."""
    with deadline():
        with pytest.raises(stabint.FileFormatError, match=match) as raised:
            read_mesh(path, file_format=file_format)
    assert raised.value.file == str(path)
    assert str(raised.value).startswith(f"{path}: ")
    return raised.value


@pytest.fixture
def bar_mesh():
    bar = stabint.tet_bar(nx=2, ny=1, nz=1)
    return bar.positions, np.array([list(t.vertices) for t in bar.tets])


@pytest.mark.parametrize("name", ["empty.vtu", "empty.vtk", "empty.msh"])
def test_empty_file(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(b"")
    refused(path, "meshio cannot read it")


def test_truncated_vtu_does_not_exit_the_process(tmp_path, bar_mesh):
    x, tets = bar_mesh
    meshio.write(tmp_path / "good.vtu", meshio.Mesh(x, [("tetra", tets)]))
    data = (tmp_path / "good.vtu").read_bytes()
    for cut in (len(data) // 2, len(data) - 20, 40):
        path = tmp_path / f"cut{cut}.vtu"
        path.write_bytes(data[:cut])
        # meshio calls exit(1) on these: SystemExit must not reach the caller.
        refused(path, "meshio cannot read it")


def test_truncated_and_garbage_vtk(tmp_path, bar_mesh):
    x, tets = bar_mesh
    meshio.write(tmp_path / "good.vtk", meshio.Mesh(x, [("tetra", tets)]))
    data = (tmp_path / "good.vtk").read_bytes()
    (tmp_path / "cut.vtk").write_bytes(data[:len(data) // 2])
    refused(tmp_path / "cut.vtk", "meshio cannot read it")
    rng = np.random.default_rng(46)
    (tmp_path / "garbage.vtk").write_bytes(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    refused(tmp_path / "garbage.vtk", "meshio cannot read it")
    (tmp_path / "text.vtk").write_text("not a mesh at all\n" * 10)
    refused(tmp_path / "text.vtk", "meshio cannot read it")
    # A header announcing far more points than the file has (an allocation of terabytes).
    (tmp_path / "huge.vtk").write_text("# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                                       "POINTS 99999999999 double\n0 0 0\n")
    refused(tmp_path / "huge.vtk", "meshio cannot read it")


def test_fifo_named_vtk_is_refused_without_opening_it(tmp_path):
    path = tmp_path / "pipe.vtk"
    os.mkfifo(path)
    refused(path, "not a regular file")


def test_directory_named_msh(tmp_path):
    path = tmp_path / "folder.msh"
    path.mkdir()
    refused(path, "is a directory")


def test_dev_zero_behind_a_symlink_is_refused_as_non_regular(tmp_path):
    if not os.path.exists("/dev/zero"):
        pytest.skip("no /dev/zero")
    path = tmp_path / "x.msh"
    os.symlink("/dev/zero", path)
    refused(path, "not a regular file")


def test_tetgen_companion_file_is_checked_too(tmp_path, bar_mesh):
    # meshio reads x.node's tets from x.ele, opened by name: that file is checked as well.
    x, tets = bar_mesh
    (tmp_path / "x.node").write_text(f"{len(x)} 3 0 0\n" + "".join(f"{i} {a} {b} {c}\n"
                                                                    for i, (a, b, c) in enumerate(x)))
    os.mkfifo(tmp_path / "x.ele")
    refused(tmp_path / "x.node", "TetGen companion .*x.ele: not a regular file")


def test_missing_file(tmp_path):
    refused(tmp_path / "missing.vtu", "meshio cannot read it: no such file")


def test_oversized_file(tmp_path, bar_mesh, monkeypatch):
    x, tets = bar_mesh
    path = tmp_path / "big.vtu"
    meshio.write(path, meshio.Mesh(x, [("tetra", tets)]))
    assert read_mesh(path).num_particles == len(x)  # under the limit: read
    assert stabint.io.MAX_FILE_BYTES == 256 << 20   # the library's kMaxTextFileBytes
    monkeypatch.setattr(stabint.io, "MAX_FILE_BYTES", path.stat().st_size - 1)
    error = refused(path, "larger than")
    assert f"{path.stat().st_size} bytes" in str(error)


def test_system_exit_and_any_exception_inside_meshio_become_file_format_errors(tmp_path, bar_mesh, monkeypatch):
    x, tets = bar_mesh
    path = tmp_path / "ok.vtu"
    meshio.write(path, meshio.Mesh(x, [("tetra", tets)]))

    def exits(*args, **kwargs):
        raise SystemExit(1)

    monkeypatch.setattr(meshio, "read", exits)
    refused(path, "meshio cannot read it: meshio gave up \\(exit\\(1\\)\\)")

    class Strange(Exception):
        pass

    def strange(*args, **kwargs):
        raise Strange("something odd")

    monkeypatch.setattr(meshio, "read", strange)
    refused(path, "meshio cannot read it: Strange: something odd")


@pytest.mark.parametrize("velocity, match", [
    ("nan", "point data 'velocity' of point 2 is not finite"),
    ("inf", "point data 'velocity' of point 2 is not finite"),
    ("huge", "point data 'velocity' of point 2 .* exceeds 1e\\+150 in magnitude"),
    ("short", "point data 'velocity' has shape \\(\\d+, 2\\), expected \\(\\d+, 3\\)"),
    ("scalar", "point data 'velocity' has shape \\(\\d+,\\), expected \\(\\d+, 3\\)"),
], ids=["nan", "inf", "huge", "short", "scalar"])
def test_velocities_are_checked_at_read(tmp_path, bar_mesh, velocity, match):
    x, tets = bar_mesh
    v = np.zeros_like(x)
    if velocity in ("nan", "inf", "huge"):
        v[2, 1] = {"nan": np.nan, "inf": -np.inf, "huge": 1e200}[velocity]
    elif velocity == "short":
        v = v[:, :2]
    else:
        v = v[:, 0]
    path = tmp_path / f"{velocity}.vtu"
    meshio.write(path, meshio.Mesh(x, [("tetra", tets)], point_data={"velocity": v}))
    refused(path, match)


def test_finite_velocities_still_load(tmp_path, bar_mesh):
    x, tets = bar_mesh
    v = np.arange(x.size, dtype=np.float64).reshape(x.shape) * 1e-3
    path = tmp_path / "moving.vtu"
    meshio.write(path, meshio.Mesh(x, [("tetra", tets)], point_data={"velocity": v}))
    assert np.array_equal(read_mesh(path).velocities, v)


def pvd(tmp_path, body, name="frames.pvd"):
    path = tmp_path / name
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
                    + body + "\n</Collection>\n</VTKFile>\n")
    return path


def pvd_refused(path, match):
    with deadline():
        with pytest.raises(stabint.FileFormatError, match=match) as raised:
            read_pvd(path)
    assert raised.value.file == str(path)
    assert str(raised.value).startswith(f"{path}: ")
    return raised.value


@pytest.mark.parametrize("entry", ["../outside.vtu", "a/../../outside.vtu", "/etc/passwd", "..", ".", ""],
                         ids=["parent", "climbs", "absolute", "dotdot", "dot", "empty"])
def test_read_pvd_keeps_paths_inside_its_directory(tmp_path, entry):
    path = pvd(tmp_path, f'<DataSet timestep="0" file="frame_00000.vtu"/>\n<DataSet timestep="1" file="{entry}"/>')
    error = pvd_refused(path, "DataSet 1: file .* (is an absolute path|is outside the .pvd's directory)")
    assert repr(entry) in str(error)


def test_read_pvd_entries_inside_the_directory_are_kept(tmp_path):
    path = pvd(tmp_path, '<DataSet timestep="0.5" file="frame_00000.vtu"/>\n'
                         '<DataSet timestep="1.5" file="sub/../sub/frame_00001.vtu"/>')
    assert read_pvd(path) == [(0.5, str(tmp_path / "frame_00000.vtu")),
                              (1.5, str(tmp_path / "sub" / "frame_00001.vtu"))]


@pytest.mark.parametrize("body, match", [
    ('<DataSet timestep="0" file="a.vtu">', "not a readable .pvd collection"),  # unclosed element
    ('<DataSet file="a.vtu"/>', "DataSet 0 has no timestep attribute"),
    ('<DataSet timestep="0"/>', "DataSet 0 has no file attribute"),
    ('<DataSet/>', "DataSet 0 has no timestep and file attribute"),
    ('<DataSet timestep="soon" file="a.vtu"/>', "DataSet 0: timestep 'soon' is not a number"),
    ('<DataSet timestep="nan" file="a.vtu"/>', "DataSet 0: timestep 'nan' is not finite"),
], ids=["unclosed", "no-timestep", "no-file", "neither", "time-text", "time-nan"])
def test_read_pvd_malformed_xml_and_attributes(tmp_path, body, match):
    pvd_refused(pvd(tmp_path, body), match)


def test_read_pvd_refuses_garbage_non_regular_and_missing_files(tmp_path):
    (tmp_path / "garbage.pvd").write_bytes(b"\x00\xff<<<")
    pvd_refused(tmp_path / "garbage.pvd", "not a readable .pvd collection")
    (tmp_path / "other.pvd").write_text("<Other/>")
    pvd_refused(tmp_path / "other.pvd", "the root element is <Other>")
    os.mkfifo(tmp_path / "pipe.pvd")
    pvd_refused(tmp_path / "pipe.pvd", "not a regular file")
    pvd_refused(tmp_path / "missing.pvd", "no such file")


def test_writer_refuses_non_finite_positions_and_velocities_and_writes_nothing(tmp_path):
    chain = stabint.chain_pendulum(particles=4)
    x, v = chain.positions, chain.velocities
    nan_x = x.copy()
    nan_x[2, 0] = np.nan
    inf_v = v.copy()
    inf_v[1, 2] = np.inf
    with VtkSeriesWriter(tmp_path / "out", chain) as vtk:
        with pytest.raises(stabint.InvalidInputError, match="VtkSeriesWriter.write: position of point 2 is not finite"):
            vtk.write(0.0, nan_x, v)
        with pytest.raises(stabint.InvalidInputError, match="VtkSeriesWriter.write: velocity of point 1 is not finite"):
            vtk.write(0.0, x, inf_v)
        assert os.listdir(tmp_path / "out") == []  # nothing written
        vtk.write(0.0, x, v)
    assert [os.path.basename(p) for _, p in read_pvd(tmp_path / "out" / "frames.pvd")] == ["frame_00000.vtu"]
    with pytest.raises(stabint.InvalidInputError, match="write_vtk_series: positions of frame 1 are not finite"):
        write_vtk_series(tmp_path / "series", [x, nan_x], chain, [0.0, 0.1])
    assert not (tmp_path / "series").exists()


@pytest.mark.parametrize("cells, match", [
    ({"line": [[0, 1], [1, 7]]}, "line cell 1 refers to point 7, outside the 4 points written"),
    ({"triangle": [[0, 1, 4]]}, "triangle cell 0 refers to point 4, outside the 4 points written"),
], ids=["line", "triangle"])
def test_writer_refuses_cells_out_of_range(tmp_path, cells, match):
    chain = stabint.chain_pendulum(particles=4)
    with VtkSeriesWriter(tmp_path / "out", cells) as vtk:
        with pytest.raises(stabint.InvalidInputError, match="VtkSeriesWriter.write: " + match):
            vtk.write(0.0, chain.positions)
    assert os.listdir(tmp_path / "out") == ["frames.pvd"]  # an empty collection, no frame
    assert read_pvd(tmp_path / "out" / "frames.pvd") == []
    with pytest.raises(stabint.InvalidInputError, match="write_vtk_series: " + match):
        write_vtk_series(tmp_path / "series", [chain.positions], cells, [0.0])
    assert not (tmp_path / "series").exists()


@pytest.mark.parametrize("cells, match", [
    ({"line": [[0, -1]]}, "line cell refers to point -1, a negative index"),
    ({"triangle": [[0, 1]]}, "triangle cell block has shape \\(1, 2\\)"),
    ({"line": [[0, 1], [2]]}, "cells: "),  # ragged
    ({"line": [[0, 1.5]]}, "not an integer"),
    ({"line": [[0, np.nan]]}, "not an integer"),
    ([("line",)], "cells: "),
], ids=["negative", "width", "ragged", "fraction", "nan", "no-data"])
def test_writer_refuses_malformed_cells_before_creating_anything(tmp_path, cells, match):
    with pytest.raises(stabint.InvalidInputError, match="VtkSeriesWriter: .*" + match):
        VtkSeriesWriter(tmp_path / "out", cells)
    assert not (tmp_path / "out").exists()
