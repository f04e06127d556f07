"""stabint.io (meshio in, VTK time series out) and stabint-run --vtk, read back with meshio."""

import os
import pathlib
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import stabint

meshio = pytest.importorskip("meshio")  # the [io] extra; requirements.txt pins it

from stabint.io import read_mesh, read_mesh_collider, read_pvd, vtk_cells, VtkSeriesWriter, write_vtk_series  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def tets_of(scene):
    return np.array([list(t.vertices) for t in scene.tets])


def test_round_trip_mesh_in_scene_stepped_series_out_exact(tmp_path):
    bar = stabint.tet_bar(nx=4, ny=2, nz=2)
    # Gmsh 2.2 text: a format of meshio's, not of the library's own loaders.
    meshio.write(tmp_path / "bar.msh", meshio.Mesh(bar.positions, [("tetra", tets_of(bar))]), file_format="gmsh22",
                 binary=False)
    scene = read_mesh(tmp_path / "bar.msh", stabint.SolidMaterial())
    assert scene.name == "bar"
    assert np.array_equal(scene.positions, bar.positions)  # the numbers, to the last bit
    assert np.array_equal(tets_of(scene), tets_of(bar))    # the builder's tets are positive already
    # Masses lumped from the tets (density 1000 kg/m^3, as the builder's default): the loader's.
    np.testing.assert_allclose(scene.masses, bar.masses, rtol=1e-12)
    scene.pins.append(stabint.Pin(0, 1e5, scene.positions[0]))  # hold one corner

    sim = stabint.Simulator(scene)
    positions, velocities, times = [sim.positions], [sim.velocities], [sim.time]
    for _ in range(10):
        sim.step()
        positions.append(sim.positions)
        velocities.append(sim.velocities)
        times.append(sim.time)
    pvd = write_vtk_series(tmp_path / "series", positions, scene, times, velocities=velocities)

    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    datasets = root.findall("./Collection/DataSet")
    assert [float(d.get("timestep")) for d in datasets] == times  # every frame, with its time
    assert [d.get("file") for d in datasets] == [f"frame_{k:05d}.vtu" for k in range(11)]
    for (time, path), x, v in zip(read_pvd(pvd), positions, velocities):
        frame = meshio.read(path)
        assert np.array_equal(frame.points, x)
        assert np.array_equal(frame.point_data["velocity"], v)
        assert np.array_equal(frame.cells_dict["tetra"], tets_of(scene))
    # A frame reads back as a scene that starts where the frame was, moving as it was.
    restart = read_mesh(read_pvd(pvd)[-1][1])
    assert np.array_equal(restart.positions, positions[-1])
    assert np.array_equal(restart.velocities, velocities[-1])


def test_a_mesh_file_becomes_a_collider_that_holds_a_cloth(tmp_path):
    # A tet bar's surface through meshio (Gmsh 2.2) as a mesh collider, 0.25 m high and moved
    # below the origin: a cloth dropped onto it stops on its top (no vertex deeper inside than the
    # contact tolerance, which the mesh's own query measures), and a surface with a triangle
    # flipped is refused by name.
    bar = stabint.tet_bar(nx=4, ny=2, nz=2)
    meshio.write(tmp_path / "bar.msh", meshio.Mesh(bar.positions, [("tetra", tets_of(bar))]), file_format="gmsh22",
                 binary=False)
    collider = read_mesh_collider(tmp_path / "bar.msh", translate=[-0.5, -0.25, -0.125])
    assert collider.shape == stabint.ColliderShape.Mesh
    assert np.array_equal(collider.mesh_vertices, bar.positions + np.array([-0.5, -0.25, -0.125]))
    assert len(collider.mesh_triangles) == 2 * (4 * 2 + 4 * 2 + 2 * 2) * 2  # the box's faces, two per square
    cloth = stabint.cloth_grid(nx=10, ny=10)
    cloth.pins.clear()
    x = cloth.positions
    cloth.positions = np.column_stack([x[:, 0] - 0.5, np.full(len(x), 0.2), x[:, 1] - 0.5])
    cloth.rest_positions = cloth.positions
    cloth.colliders.append(collider)
    options = stabint.SimulatorOptions(contact_tolerance=0.01)
    sim = stabint.Simulator(cloth, options)
    lowest_middle = []
    middle = np.flatnonzero((np.abs(cloth.positions[:, 0]) < 0.4) & (np.abs(cloth.positions[:, 2]) < 0.1))
    for _ in range(30):
        sim.step()
        lowest_middle.append(sim.positions[middle, 1].min())
    assert min(lowest_middle) > -0.01  # the bar's top is at y = 0
    flipped = stabint.Scene(cloth)
    bad = flipped.colliders[0]
    triangles = bad.mesh_triangles
    triangles[0] = triangles[0][::-1]
    bad.mesh_triangles = triangles
    flipped.colliders[0] = bad
    with pytest.raises(stabint.InvalidInputError, match="collider 0.*closed, consistently oriented"):
        stabint.Simulator(flipped, options)


def test_triangles_become_cloth_of_the_chosen_model(tmp_path):
    cloth = stabint.cloth_grid(nx=4, ny=3)
    meshio.write(tmp_path / "cloth.vtk", meshio.Mesh(cloth.positions, [("triangle", cloth.triangles)]))
    springs = read_mesh(tmp_path / "cloth.vtk")
    # Default ClothMaterial: a spring per edge and across each interior edge (load_obj_cloth).
    edges = {tuple(sorted(e)) for t in cloth.triangles for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    interior = sum(1 for e in edges if sum(set(e) <= set(t) for t in cloth.triangles) == 2)
    assert len(springs.springs) == len(edges) + interior
    assert np.array_equal(springs.triangles, cloth.triangles)
    material = stabint.ClothMaterial()
    material.model = stabint.ClothModel.Triangles
    membrane = read_mesh(tmp_path / "cloth.vtk", material)
    assert len(membrane.triangle_strains) == len(cloth.triangles)
    assert len(membrane.bending_hinges) == interior
    assert len(membrane.springs) == 0
    # 2D points (a flat mesh as many tools write it) lie at z = 0.
    meshio.write(tmp_path / "flat.vtu", meshio.Mesh(cloth.positions[:, :2], [("triangle", cloth.triangles)]))
    flat = read_mesh(tmp_path / "flat.vtu")
    assert np.array_equal(flat.positions[:, :2], cloth.positions[:, :2]) and not flat.positions[:, 2].any()


def test_bad_meshes_are_file_format_errors_naming_the_file(tmp_path):
    bar = stabint.tet_bar(nx=2, ny=1, nz=1)
    x, tets = bar.positions, tets_of(bar)

    def refused(name, mesh, match):
        path = tmp_path / name
        meshio.write(path, mesh)
        with pytest.raises(stabint.FileFormatError, match=match) as raised:
            read_mesh(path)
        assert raised.value.file == str(path)
        assert str(path) in str(raised.value)

    refused("quads.vtu", meshio.Mesh(x, [("quad", np.array([[0, 1, 3, 2]]))]),
            "no tetra or triangle cells to simulate \\(cells found: quad\\)")
    nan = x.copy()
    nan[3, 1] = np.nan
    refused("nan.vtu", meshio.Mesh(nan, [("tetra", tets)]), "point 3 is not finite")
    extra = np.vstack([x, [[5.0, 5.0, 5.0]]])
    refused("orphan.vtu", meshio.Mesh(extra, [("tetra", tets)]), f"point {len(x)} is in no tetra cell")
    mixed = tets.copy()
    mixed[0, [1, 2]] = mixed[0, [2, 1]]
    # The loader's orientation rule (io.hpp), with tets numbered as meshio numbers them.
    refused("mixed.vtu", meshio.Mesh(x, [("tetra", mixed)]), "tet 0: mixed orientation")
    meshio.write(tmp_path / "bar.vtu", meshio.Mesh(x, [("tetra", tets)]))
    with pytest.raises(stabint.InvalidInputError, match="a tetra mesh takes a SolidMaterial, got ClothMaterial"):
        read_mesh(tmp_path / "bar.vtu", stabint.ClothMaterial())
    with pytest.raises(stabint.FileFormatError, match="missing.vtu: meshio cannot read it") as raised:
        read_mesh(tmp_path / "missing.vtu")
    assert raised.value.file == str(tmp_path / "missing.vtu")


def test_writer_checks_its_input_and_draws_every_kind_of_scene(tmp_path):
    chain = stabint.chain_pendulum(particles=4)
    assert [kind for kind, _ in vtk_cells(chain)] == ["line"]
    assert [kind for kind, _ in vtk_cells(stabint.linear_oscillator())] == ["vertex"]
    assert [kind for kind, _ in vtk_cells(stabint.cloth_grid(nx=3, ny=3))] == ["triangle"]
    with VtkSeriesWriter(tmp_path / "chain", chain) as vtk:
        vtk.write(0.0, chain.positions, chain.velocities)
        with pytest.raises(stabint.InvalidInputError, match="positions have shape \\(4, 2\\)"):
            vtk.write(0.1, chain.positions[:, :2])
        with pytest.raises(stabint.InvalidInputError, match="point data 'velocity' has shape \\(3, 3\\)"):
            vtk.write(0.1, chain.positions, chain.velocities[:3])
    assert len(read_pvd(tmp_path / "chain" / "frames.pvd")) == 1  # the refused writes left no frame
    frame = meshio.read(tmp_path / "chain" / "frame_00000.vtu")
    assert np.array_equal(frame.points, chain.positions)
    with pytest.raises(stabint.InvalidInputError, match="expected \\(k, n, 3\\) and \\(k,\\)"):
        write_vtk_series(tmp_path / "bad", [chain.positions] * 2, chain, [0.0])


def stabint_run():
    """The CLI from scripts/test.sh's build (ctest runs before pytest there, so it is built)."""
    path = ROOT / "build" / "tools" / "run" / "stabint-run"
    if not path.exists():
        pytest.skip(f"{path} not built (cmake --build build)")
    return path


@pytest.mark.parametrize("scene, params, cell", [("tetbar", ["nx=3", "ny=1", "nz=1"], "tetra"),
                                                 ("cloth", ["nx=4", "ny=4"], "triangle"),
                                                 ("chain", ["particles=5"], "line"),
                                                 ("oscillator", [], "vertex")])
def test_cli_vtk_series_matches_the_python_api_stepping_the_same_scene(tmp_path, scene, params, cell):
    out = tmp_path / "vtk"
    frames, every, dt = 7, 3, 0.02
    command = [str(stabint_run()), "--scene", scene, "--backend", "cpu", "--integrator", "blend", "--dt", str(dt),
               "--frames", str(frames), "--every", str(every), "--vtk", str(out), "--quiet"]
    for p in params:
        command += ["--param", p]
    subprocess.run(command, check=True, timeout=60, capture_output=True)

    built = stabint.builtin_scene(scene, "{" + ", ".join('"{}": {}'.format(*p.split("=")) for p in params) + "}")
    sim = stabint.Simulator(built, stabint.SimulatorOptions(integrator=stabint.Integrator.EnergyBlend, time_step=dt))
    expected = {0: (0.0, sim.positions, sim.velocities)}
    for frame in range(1, frames + 1):
        sim.step()
        expected[frame] = (sim.time, sim.positions, sim.velocities)
    written = [0, 3, 6, 7]  # every 3rd frame, and always the last (--every)
    series = read_pvd(out / "frames.pvd")
    assert [os.path.basename(p) for _, p in series] == [f"frame_{k:05d}.vtu" for k in written]
    for (time, path), k in zip(series, written):
        t, x, v = expected[k]
        assert time == t
        mesh = meshio.read(path)
        # The same library, scene, options and backend (the CPU reference is deterministic) and
        # 17 significant digits in the file: the CLI's frames are the API's, bit for bit.
        assert np.array_equal(mesh.points, x)
        assert np.array_equal(mesh.point_data["velocity"], v)
        assert list(mesh.cells_dict) == [cell]
        assert np.array_equal(mesh.cells_dict[cell], dict(vtk_cells(built))[cell])


def test_cli_vtk_series_after_a_blow_up_ends_at_the_last_finite_frame(tmp_path):
    # Symplectic Euler at h = 1/30 s on 3 particles of 1/30 kg with 40 N/m springs and pin: the
    # fastest mode is just past SE's limit (omega h > 2), so the energy grows slowly and passes
    # the limit at frame 20 (measured). The run exits 2 (README, "Errors") and, as its CSV, the
    # series keeps the last finite frame (19) although --every 10 skipped it; the .pvd lists
    # only files that exist.
    out = tmp_path / "vtk"
    result = subprocess.run([str(stabint_run()), "--scene", "chain", "--param", "particles=3", "--param",
                             "stiffness=40", "--param", "pin_stiffness=40", "--backend", "cpu", "--integrator", "SE",
                             "--energy-limit", "1", "--frames", "200", "--every", "10", "--vtk", str(out), "--quiet"],
                            timeout=60, capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    assert "exceeded at frame 20 " in result.stderr
    series = read_pvd(out / "frames.pvd")
    assert [os.path.basename(p) for _, p in series] == ["frame_00000.vtu", "frame_00010.vtu", "frame_00019.vtu"]
    assert sorted(os.listdir(out)) == [os.path.basename(p) for _, p in series] + ["frames.pvd"]
    assert series[-1][0] == pytest.approx(19 / 30, rel=1e-15)
    assert np.isfinite(meshio.read(series[-1][1]).points).all()
