"""Mesh exchange through meshio: read any tet or triangle mesh into a Scene, write a VTK time
series (one ``.vtu`` per frame and a ``.pvd`` collection) for ParaView.

Install with ``pip install stabint[io]`` (meshio); ``import stabint`` never imports meshio.

``read_mesh`` hands the mesh to the library's own loaders (TetGen for tets, OBJ cloth for
triangles) through a temporary file, numbers written to the last bit, so a mesh read this way
gets exactly what ``load_tetgen`` / ``load_obj_cloth`` give: masses lumped from the material's
density, the mesh-wide tet orientation rule and every check of docs/scene-format.md ("Meshes").
Errors are ``stabint.FileFormatError`` naming the file (``.file``), as for every loader: a
file meshio cannot read, no ``tetra`` or ``triangle`` cells, a non-finite coordinate, a point in
no cell, a flat tet or zero-area triangle. Point numbers in messages are 0-based, as meshio
numbers them.

The series layout is the one ``stabint-run --vtk DIR`` writes: ``DIR/frame_00000.vtu``, ...
and ``DIR/frames.pvd``; open the ``.pvd`` in ParaView (File > Open) to play it with its times.
"""

from __future__ import annotations

import os
import re
import tempfile
import xml.etree.ElementTree as ET
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _stabint
from ._stabint import ClothMaterial, FileFormatError, Scene, SolidMaterial

__all__ = ["read_mesh", "vtk_cells", "VtkSeriesWriter", "write_vtk_series", "read_pvd"]

Cells = List[Tuple[str, np.ndarray]]


def _meshio() -> Any:
    try:
        import meshio
    except ImportError as e:  # the optional extra is missing: say how to get it
        raise ImportError("stabint.io needs meshio: pip install stabint[io]") from e
    return meshio


def _file_error(path: str, message: str, line: int = 0) -> FileFormatError:
    # The library's convention for a file's content: FileFormatError with file and line.
    error = FileFormatError(f"{path}: {message}")
    error.file = str(path)
    error.line = line
    return error


def _cells_of(mesh: Any, kind: str) -> np.ndarray:
    blocks = [np.asarray(block.data, dtype=np.int64) for block in mesh.cells if block.type == kind]
    return np.concatenate(blocks) if blocks else np.empty((0, 4 if kind == "tetra" else 3), np.int64)


def read_mesh(path: Union[str, os.PathLike], material: Optional[Union[SolidMaterial, ClothMaterial]] = None, *,
              file_format: Optional[str] = None) -> Scene:
    """A Scene from any mesh file meshio reads (``.msh``, ``.vtu``, ``.vtk``, ``.mesh``, ``.inp``,
    ``.xdmf``, ``.off``, ...). Linear tetrahedra (``tetra``) make a solid: co-rotated tets of
    ``material.stiffness`` (a :class:`SolidMaterial`; default density 1000 kg/m^3, 1e5), with the
    file's triangles, if any, kept as its surface. Without tets, linear ``triangle`` cells make a
    cloth (a :class:`ClothMaterial`: by default springs along edges and across interior edges;
    ``model=ClothModel.Triangles`` gives triangle strain and bending hinges, docs/elements.md).
    2D points get z = 0. A ``velocity`` point array of shape (n, 3), as the series written by
    :class:`VtkSeriesWriter` carries, becomes the initial velocities; the rest shape is the
    file's points. No pins: append ``stabint.Pin`` to ``scene.pins``. ``file_format``: meshio's
    name, when the extension does not say it. Raises FileFormatError naming the file."""
    meshio = _meshio()
    path = os.fspath(path)
    try:
        mesh = meshio.read(path, file_format=file_format)
    except Exception as e:  # meshio raises ReadError, KeyError, ValueError, OSError ... by format
        raise _file_error(path, f"meshio cannot read it: {type(e).__name__}: {e}") from e
    points = np.asarray(mesh.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise _file_error(path, f"points have shape {points.shape}, expected (n, 2) or (n, 3)")
    if points.shape[1] == 2:
        points = np.hstack([points, np.zeros((points.shape[0], 1))])
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise _file_error(path, f"point {bad[0]} is not finite ({points[bad[0]].tolist()}); "
                                f"{bad.size} non-finite point(s) in all")
    tets, triangles = _cells_of(mesh, "tetra"), _cells_of(mesh, "triangle")
    if len(tets) == 0 and len(triangles) == 0:
        found = sorted({block.type for block in mesh.cells}) or ["none"]
        raise _file_error(path, f"no tetra or triangle cells to simulate (cells found: {', '.join(found)})")
    elements = tets if len(tets) else triangles
    noun = "tetra" if len(tets) else "triangle"
    if elements.min() < 0 or elements.max() >= len(points):
        raise _file_error(path, f"a {noun} cell refers to point {int(elements.min() if elements.min() < 0 else elements.max())}, "
                                f"outside [0, {len(points)})")
    # A point in no element would get no mass (the loaders refuse it too; saying it here keeps
    # meshio's 0-based numbering in the message).
    unused = np.flatnonzero(np.bincount(elements.ravel(), minlength=len(points)) == 0)
    if unused.size:
        raise _file_error(path, f"point {unused[0]} is in no {noun} cell ({unused.size} such point(s)): it would "
                                "have no mass; remove unused points first (e.g. meshio's mesh.remove_orphaned_nodes())")
    wanted = SolidMaterial if len(tets) else ClothMaterial
    if material is not None and not isinstance(material, wanted):
        from . import InvalidInputError

        raise InvalidInputError(f"read_mesh({path!r}): a {noun} mesh takes a {wanted.__name__}, "
                                f"got {type(material).__name__}")
    with tempfile.TemporaryDirectory(prefix="stabint-read-mesh-") as tmp:
        try:
            if len(tets):
                scene = _load_tets(tmp, points, tets, material if material is not None else SolidMaterial())
            else:
                scene = _load_triangles(tmp, points, triangles, material if material is not None else ClothMaterial())
        except FileFormatError as e:
            # The loader names the temporary file and its line: say the user's file instead, and
            # keep what the loader found (it numbers points and tets 0-based here, as meshio).
            message = str(e)
            prefix = f"{e.file}:{e.line}: " if e.line > 0 else f"{e.file}: "
            message = message[len(prefix):] if message.startswith(prefix) else message
            raise _file_error(path, re.sub(r" \(line \d+\)", "", message)) from e
    if len(tets) and len(triangles):
        scene.triangles = np.ascontiguousarray(triangles, dtype=np.int32)
    scene.name = os.path.splitext(os.path.basename(path))[0]
    velocity = mesh.point_data.get("velocity")
    if velocity is not None and np.shape(velocity) == points.shape:
        scene.velocities = np.asarray(velocity, dtype=np.float64)
    return scene


def _load_tets(tmp: str, points: np.ndarray, tets: np.ndarray, material: SolidMaterial) -> Scene:
    # TetGen's .node/.ele, numbered from 0 so that the loader's "point k" / "tetrahedron k" are
    # meshio's indices; repr() writes the shortest text that reads back as the same double.
    base = os.path.join(tmp, "mesh")
    with open(base + ".node", "w") as f:
        f.write(f"{len(points)} 3 0 0\n")
        f.writelines(f"{i} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(points.tolist()))
    with open(base + ".ele", "w") as f:
        f.write(f"{len(tets)} 4 0\n")
        f.writelines(f"{i} {a} {b} {c} {d}\n" for i, (a, b, c, d) in enumerate(tets.tolist()))
    return _stabint.load_tetgen(base, material)


def _load_triangles(tmp: str, points: np.ndarray, triangles: np.ndarray, material: ClothMaterial) -> Scene:
    path = os.path.join(tmp, "mesh.obj")
    with open(path, "w") as f:
        f.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in triangles.tolist())
    return _stabint.load_obj_cloth(path, material)


def vtk_cells(scene: Scene) -> Cells:
    """The cells a scene is drawn with, as meshio cell blocks: its tets, else its surface
    triangles, else its springs as lines, else one vertex per particle (the rule of
    ``stabint-run --vtk``)."""
    if len(scene.tets):
        return [("tetra", np.array([list(t.vertices) for t in scene.tets], dtype=np.int64))]
    triangles = scene.triangles
    if len(triangles):
        return [("triangle", triangles.astype(np.int64))]
    if len(scene.springs):
        return [("line", np.array([[s.a, s.b] for s in scene.springs], dtype=np.int64))]
    return [("vertex", np.arange(scene.num_particles, dtype=np.int64).reshape(-1, 1))]


def _as_cells(cells: Union[Scene, Sequence[Tuple[str, Any]], Mapping[str, Any]]) -> Cells:
    if isinstance(cells, Scene):
        return vtk_cells(cells)
    items = cells.items() if isinstance(cells, Mapping) else cells
    return [(str(kind), np.asarray(data, dtype=np.int64)) for kind, data in items]


class VtkSeriesWriter:
    """Writes a VTK time series while stepping: ``write(time, positions, velocities)`` per frame
    makes ``directory/frame_00000.vtu``, ... (meshio, XML UnstructuredGrid; float64 points, so a
    reader gets the positions back to the last bit), and ``close()`` (or leaving a ``with``
    block) writes ``directory/frames.pvd``, the collection listing each file with its time.

    ``cells``: a Scene (its tets, else triangles, else springs as lines, else vertices; see
    :func:`vtk_cells`), or meshio-style ``[("triangle", array), ...]`` / ``{"tetra": array}``.
    The ``.vtu`` files are meshio's binary (base64, zlib) form: its ASCII form rounds the
    numbers, the binary one keeps every bit.

    Example::

        with stabint.io.VtkSeriesWriter("out", scene) as vtk:
            vtk.write(sim.time, sim.positions, sim.velocities)
            for _ in range(100):
                sim.step()
                vtk.write(sim.time, sim.positions, sim.velocities)
    """

    def __init__(self, directory: Union[str, os.PathLike], cells: Any) -> None:
        self._meshio = _meshio()
        self.directory = os.fspath(directory)
        self.cells = _as_cells(cells)
        self.frames: List[Tuple[float, str]] = []
        os.makedirs(self.directory, exist_ok=True)

    def write(self, time: float, positions: Any, velocities: Optional[Any] = None, **point_data: Any) -> str:
        """Writes the next frame's ``.vtu`` (positions (n, 3); velocities and any other
        ``point_data`` arrays with one row per point, as point data) and returns its path."""
        from . import InvalidInputError

        x = np.asarray(positions, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != 3:
            raise InvalidInputError(f"VtkSeriesWriter.write: positions have shape {x.shape}, expected (n, 3)")
        if not np.isfinite(time):
            raise InvalidInputError(f"VtkSeriesWriter.write: time {time} is not finite")
        data: Dict[str, np.ndarray] = {}
        if velocities is not None:
            point_data = {"velocity": velocities, **point_data}
        for name, values in point_data.items():
            values = np.asarray(values)
            if values.shape[:1] != (x.shape[0],):
                raise InvalidInputError(f"VtkSeriesWriter.write: point data '{name}' has shape {values.shape}, "
                                        f"expected {x.shape[0]} rows (one per point)")
            data[name] = values
        name = f"frame_{len(self.frames):05d}.vtu"
        path = os.path.join(self.directory, name)
        mesh = self._meshio.Mesh(x, self.cells, point_data=data)
        self._meshio.write(path, mesh, file_format="vtu", binary=True)
        self.frames.append((float(time), name))
        return path

    def close(self) -> str:
        """Writes ``frames.pvd`` listing every frame written so far and returns its path."""
        root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
        collection = ET.SubElement(root, "Collection")
        for time, name in self.frames:
            # repr: the shortest text that reads back as the same double.
            ET.SubElement(collection, "DataSet", timestep=repr(time), group="", part="0", file=name)
        ET.indent(root)  # Python >= 3.9
        path = os.path.join(self.directory, "frames.pvd")
        ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
        return path

    def __enter__(self) -> "VtkSeriesWriter":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def write_vtk_series(directory: Union[str, os.PathLike], positions: Any, cells: Any, times: Any, *,
                     velocities: Optional[Any] = None) -> str:
    """Writes a whole trajectory as a VTK time series and returns the ``.pvd`` path:
    ``positions`` (k, n, 3), ``times`` (k,), ``velocities`` (k, n, 3) or None, ``cells`` as for
    :class:`VtkSeriesWriter` (e.g. the Scene). A sweep's result goes straight in:
    ``write_vtk_series(dir, r.positions, scene, r.times, velocities=r.velocities)``."""
    from . import InvalidInputError

    x = np.asarray(positions, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    if x.ndim != 3 or x.shape[2] != 3 or len(t) != len(x):
        raise InvalidInputError(f"write_vtk_series: positions have shape {x.shape} and times {t.shape}, "
                                "expected (k, n, 3) and (k,)")
    v = None if velocities is None else np.asarray(velocities, dtype=np.float64)
    if v is not None and v.shape != x.shape:
        raise InvalidInputError(f"write_vtk_series: velocities have shape {v.shape}, expected {x.shape}")
    with VtkSeriesWriter(directory, cells) as writer:
        for k in range(len(x)):
            writer.write(t[k], x[k], None if v is None else v[k])
    return os.path.join(os.fspath(directory), "frames.pvd")


def read_pvd(path: Union[str, os.PathLike]) -> List[Tuple[float, str]]:
    """The (time, absolute path of the .vtu) pairs a ``.pvd`` collection lists, in order."""
    path = os.fspath(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as e:
        raise _file_error(path, f"not a readable .pvd collection: {e}") from e
    directory = os.path.dirname(path)
    return [(float(d.get("timestep")), os.path.join(directory, d.get("file"))) for d in root.iter("DataSet")]
