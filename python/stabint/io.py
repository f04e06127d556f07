"""Mesh exchange through meshio: read any tet or triangle mesh into a Scene, write a VTK time
series (one ``.vtu`` per frame and a ``.pvd`` collection) for ParaView.

Install with ``pip install stabint[io]`` (meshio); ``import stabint`` never imports meshio.

``read_mesh`` hands the mesh to the library's own loaders (TetGen for tets, OBJ cloth for
triangles) through a temporary file, numbers written to the last bit, so a mesh read this way
gets exactly what ``load_tetgen`` / ``load_obj_cloth`` give: masses lumped from the material's
density, the mesh-wide tet orientation rule and every check of docs/scene-format.md ("Meshes").
Errors are ``stabint.FileFormatError`` naming the file (``.file``), as for every loader: a
missing file, one that is not a regular file (a directory, FIFO, device or socket: refused from
its ``stat``, never opened, so nothing waits for a writer or reads ``/dev/zero`` without end), a
file over :data:`MAX_FILE_BYTES`, a file meshio cannot read (whatever meshio raises, the
``SystemExit`` of its ``exit(1)`` on a truncated or garbage file included: a bad file never
ends the caller's process), no ``tetra`` or ``triangle`` cells, a non-finite coordinate, a
``velocity`` point array of the wrong shape or with a non-finite value, a point in no cell, a flat
tet or zero-area triangle. Point numbers in messages are 0-based, as meshio numbers them.

The series layout is the one ``stabint-run --vtk DIR`` writes: ``DIR/frame_00000.vtu``, ...
and ``DIR/frames.pvd``; open the ``.pvd`` in ParaView (File > Open) to play it with its times.
The writer refuses non-finite positions or velocities and cells that name a point it does not
have (``stabint.InvalidInputError``) and then writes nothing; :func:`read_pvd` returns only paths
inside the ``.pvd``'s directory.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
import xml.etree.ElementTree as ET
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _stabint
from ._stabint import ClothMaterial, FileFormatError, Scene, SolidMaterial

__all__ = ["read_mesh", "read_mesh_collider", "vtk_cells", "VtkSeriesWriter", "VtkReporter", "write_vtk_series",
           "read_pvd", "MAX_FILE_BYTES"]

Cells = List[Tuple[str, np.ndarray]]

#: Largest file :func:`read_mesh` and :func:`read_pvd` read (for a TetGen ``.node``/``.ele`` pair,
#: both together): 256 MiB, the limit of the library's own whole-file reader
#: (``kMaxTextFileBytes``, host/io/text_reader.hpp; scene files and checkpoints). A binary
#: ``.vtu`` of this size holds about ten million points.
MAX_FILE_BYTES = 256 << 20

#: Largest magnitude of a velocity component read from a file: the library's bound on every
#: coordinate and speed (``kMaxMagnitude``, host/common/validation.hpp), which its loaders apply to a
#: file's coordinates as well.
_MAX_MAGNITUDE = 1e150


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


def _checked_size(path: str) -> int:
    # The file's type and size from stat (following links), before anything opens it: opening a
    # FIFO for reading waits for a writer, a device such as /dev/zero never ends. Returns the
    # size; raises ValueError naming what is wrong.
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise ValueError("no such file") from None
    except (OSError, ValueError) as e:  # ValueError: a NUL byte in the path
        raise ValueError(f"cannot stat the file: {getattr(e, 'strerror', None) or e}") from None
    if stat.S_ISDIR(info.st_mode):
        raise ValueError("is a directory, not a file")
    if not stat.S_ISREG(info.st_mode):
        raise ValueError("not a regular file (a FIFO, device or socket); refused without opening it")
    if info.st_size > MAX_FILE_BYTES:
        raise ValueError(f"file of {info.st_size} bytes is larger than {MAX_FILE_BYTES >> 20} MiB, "
                         "the limit of stabint.io (stabint.io.MAX_FILE_BYTES)")
    return info.st_size


def _check_mesh_file(path: str, file_format: Optional[str]) -> None:
    # The file meshio will read, and for TetGen the other file of the pair, which meshio's reader
    # opens by name (x.node with x.ele).
    files = [path]
    base, suffix = os.path.splitext(path)
    if suffix in (".node", ".ele") and file_format in (None, "tetgen"):
        files.append(base + (".ele" if suffix == ".node" else ".node"))
    total = 0
    for name in files:
        try:
            total += _checked_size(name)
        except ValueError as e:
            what = "" if name == path else f"its TetGen companion {name}: "
            raise _file_error(path, f"meshio cannot read it: {what}{e}") from None
    if total > MAX_FILE_BYTES:
        raise _file_error(path, f"meshio cannot read it: with its TetGen companion, {total} bytes, larger than "
                                f"{MAX_FILE_BYTES >> 20} MiB, the limit of stabint.io (stabint.io.MAX_FILE_BYTES)")


def _cells_of(mesh: Any, kind: str) -> np.ndarray:
    width = 4 if kind == "tetra" else 3
    blocks = [_integer_cells(block.data, kind, width) for block in mesh.cells if block.type == kind]
    return np.concatenate(blocks) if blocks else np.empty((0, width), np.int64)


def _integer_cells(data: Any, kind: str, width: Optional[int]) -> np.ndarray:
    # A cell block as int64 (m, width): integers, or floats that hold integers exactly; ValueError
    # naming the block otherwise (a ragged list, a width that is not the kind's, 1.5, NaN, 1e300).
    block = np.asarray(data)
    if block.ndim != 2 or (width is not None and block.shape[1] != width) or block.dtype.kind not in "biuf":
        expected = f"(m, {width})" if width is not None else "(m, k)"
        raise ValueError(f"a {kind} cell block has shape {block.shape} and type {block.dtype}, "
                         f"expected {expected} integers")
    if block.dtype.kind == "f":
        if not (np.isfinite(block).all() and (np.abs(block) < 2.0**62).all() and (block == np.floor(block)).all()):
            raise ValueError(f"a {kind} cell block holds a vertex index that is not an integer")
    elif block.dtype.kind == "u" and block.size and block.max() > np.iinfo(np.int64).max:
        raise ValueError(f"a {kind} cell block holds a vertex index {int(block.max())} past int64")
    return block.astype(np.int64)


def _velocity_of(path: str, mesh: Any, points: np.ndarray, dimension: int) -> Optional[np.ndarray]:
    # The "velocity" point array, if the file has one: one finite row per point, of the points'
    # dimension (2D points: 2 or 3 components, z = 0 when 2), within the library's bound.
    if "velocity" not in mesh.point_data:
        return None
    try:
        velocity = np.asarray(mesh.point_data["velocity"], dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise _file_error(path, f"point data 'velocity' is not an array of numbers: {e}") from None
    n = len(points)
    if velocity.ndim == 2 and velocity.shape == (n, 2) and dimension == 2:
        velocity = np.hstack([velocity, np.zeros((n, 1))])
    if velocity.shape != (n, 3):
        raise _file_error(path, f"point data 'velocity' has shape {velocity.shape}, expected ({n}, {dimension})"
                                " (one velocity per point)")
    bad = np.flatnonzero(~np.isfinite(velocity).all(axis=1))
    if bad.size:
        raise _file_error(path, f"point data 'velocity' of point {bad[0]} is not finite ({velocity[bad[0]].tolist()}); "
                                f"{bad.size} non-finite velocity(ies) in all")
    big = np.flatnonzero(~(np.abs(velocity) <= _MAX_MAGNITUDE).all(axis=1))
    if big.size:
        raise _file_error(path, f"point data 'velocity' of point {big[0]} ({velocity[big[0]].tolist()}) exceeds "
                                f"{_MAX_MAGNITUDE:g} in magnitude")
    return velocity


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
    file's points; a ``velocity`` array of another shape, or with a non-finite component, is a
    FileFormatError. No pins: append ``stabint.Pin`` to ``scene.pins``. ``file_format``: meshio's
    name, when the extension does not say it.

    The file must be a regular file (a directory, FIFO or device is refused from its ``stat``
    without being opened) of at most :data:`MAX_FILE_BYTES`. Raises FileFormatError naming the
    file for these and for every failure inside meshio, whatever it raises (``SystemExit``
    included: meshio calls ``exit(1)`` on a file it cannot parse)."""
    meshio = _meshio()
    path = os.fspath(path)
    _check_mesh_file(path, file_format)
    try:
        mesh = meshio.read(path, file_format=file_format)
    except SystemExit as e:  # meshio's exit(1) when no reader for the name's formats could parse it
        raise _file_error(path, f"meshio cannot read it: meshio gave up (exit({e.code})): the file is empty, truncated "
                                "or not in the format its name says") from e
    except Exception as e:  # ReadError, KeyError, ValueError, OSError, MemoryError ... by format
        raise _file_error(path, f"meshio cannot read it: {type(e).__name__}: {e}") from e
    try:
        points = np.asarray(mesh.points, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise _file_error(path, f"points are not an array of numbers: {e}") from None
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise _file_error(path, f"points have shape {points.shape}, expected (n, 2) or (n, 3)")
    dimension = points.shape[1]
    if dimension == 2:
        points = np.hstack([points, np.zeros((points.shape[0], 1))])
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise _file_error(path, f"point {bad[0]} is not finite ({points[bad[0]].tolist()}); "
                                f"{bad.size} non-finite point(s) in all")
    velocity = _velocity_of(path, mesh, points, dimension)
    try:
        tets, triangles = _cells_of(mesh, "tetra"), _cells_of(mesh, "triangle")
    except (TypeError, ValueError, OverflowError) as e:
        raise _file_error(path, str(e)) from None
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
    if velocity is not None:
        scene.velocities = velocity
    return scene


def read_mesh_collider(path: Union[str, os.PathLike], *, file_format: Optional[str] = None,
                       translate: Optional[Sequence[float]] = None) -> "_stabint.Collider":
    """A mesh collider (``ColliderShape.Mesh``, docs/method.md "Mesh colliders") from any mesh file
    :func:`read_mesh` reads: its triangles, or the surface of its tets, moved by ``translate``.
    The file is checked as by :func:`read_mesh` (FileFormatError naming it); the surface must be
    closed and wound counter-clockwise seen from outside, which building a Simulator checks
    (InvalidInputError naming the collider). Set its other fields (friction, stiffness, center,
    velocity, ...) on the result and append it to ``scene.colliders``."""
    scene = read_mesh(path, file_format=file_format)
    points = scene.positions
    if translate is not None:
        points = points + np.asarray(translate, dtype=np.float64).reshape(1, 3)
    collider = _stabint.Collider()
    collider.shape = _stabint.ColliderShape.Mesh
    collider.mesh_vertices = points
    collider.mesh_triangles = scene.triangles if len(scene.triangles) else _stabint.tet_surface(scene)
    return collider


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


def _as_cells(cells: Union[Scene, Sequence[Tuple[str, Any]], Mapping[str, Any]], who: str) -> Cells:
    # The cell blocks, checked as far as they can be without the points: each a known meshio
    # kind's width of integer vertex indices, none negative. InvalidInputError naming `who`.
    from . import InvalidInputError

    try:
        if isinstance(cells, Scene):
            items = vtk_cells(cells)
        else:
            items = list(cells.items() if isinstance(cells, Mapping) else cells)
        blocks = []
        for kind, data in items:
            kind = str(kind)
            width = _nodes_per_cell(kind)
            if width == 1 and np.ndim(data) == 1:  # vertices as a plain list of point indices
                data = np.reshape(data, (-1, 1))
            block = _integer_cells(data, kind, width)
            if block.size and block.min() < 0:
                raise ValueError(f"a {kind} cell refers to point {int(block.min())}, a negative index")
            blocks.append((kind, block))
    except (TypeError, ValueError) as e:
        raise InvalidInputError(f"{who}: cells: {e}") from None
    return blocks


def _nodes_per_cell(kind: str) -> Optional[int]:
    # meshio's number of vertices of a cell kind (None for a kind of varying size, "polygon").
    try:
        from meshio._common import num_nodes_per_cell
    except ImportError:  # another meshio layout: the width is then left to meshio's writer
        return None
    return num_nodes_per_cell.get(kind)


def _check_cells_in_range(cells: Cells, n: int, who: str) -> None:
    from . import InvalidInputError

    for kind, block in cells:
        if block.size and block.max() >= n:
            row = int(np.argmax(block.max(axis=1) >= n))
            raise InvalidInputError(f"{who}: {kind} cell {row} refers to point {int(block[row].max())}, "
                                    f"outside the {n} points written [0, {n})")


def _finite_rows(values: np.ndarray) -> np.ndarray:
    # Per row (first axis): whether every number in it is finite; empty arrays included.
    return np.isfinite(values).all(axis=tuple(range(1, values.ndim)))


def _check_finite_rows(values: np.ndarray, what: str, who: str) -> None:
    from . import InvalidInputError

    bad = np.flatnonzero(~_finite_rows(values))
    if bad.size:
        raise InvalidInputError(f"{who}: {what} of point {bad[0]} is not finite ({values[bad[0]].tolist()}); "
                                f"{bad.size} non-finite row(s) in all; nothing written")


class VtkSeriesWriter:
    """Writes a VTK time series while stepping: ``write(time, positions, velocities)`` per frame
    makes ``directory/frame_00000.vtu``, ... (meshio, XML UnstructuredGrid; float64 points, so a
    reader gets the positions back to the last bit), and ``close()`` (or leaving a ``with``
    block) writes ``directory/frames.pvd``, the collection listing each file with its time.

    ``cells``: a Scene (its tets, else triangles, else springs as lines, else vertices; see
    :func:`vtk_cells`), or meshio-style ``[("triangle", array), ...]`` / ``{"tetra": array}``.
    The ``.vtu`` files are meshio's binary (base64, zlib) form: its ASCII form rounds the
    numbers, the binary one keeps every bit.

    Refused with ``stabint.InvalidInputError``, writing nothing: cells that are not integer
    vertex indices of their kind's width or are negative (at construction), and at ``write``
    positions or velocities that are not finite, point data with a row count other than the
    points', and a cell naming a point past the positions written.

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
        self.cells = _as_cells(cells, "VtkSeriesWriter")
        self.frames: List[Tuple[float, str]] = []
        os.makedirs(self.directory, exist_ok=True)

    def write(self, time: float, positions: Any, velocities: Optional[Any] = None, **point_data: Any) -> str:
        """Writes the next frame's ``.vtu`` (positions (n, 3); velocities and any other
        ``point_data`` arrays with one row per point, as point data) and returns its path."""
        from . import InvalidInputError

        who = "VtkSeriesWriter.write"
        try:
            x = np.asarray(positions, dtype=np.float64)
            time = float(time)
        except (TypeError, ValueError) as e:
            raise InvalidInputError(f"{who}: positions and time must be numbers: {e}") from None
        if x.ndim != 2 or x.shape[1] != 3:
            raise InvalidInputError(f"{who}: positions have shape {x.shape}, expected (n, 3)")
        if not np.isfinite(time):
            raise InvalidInputError(f"{who}: time {time} is not finite")
        _check_finite_rows(x, "position", who)
        data: Dict[str, np.ndarray] = {}
        if velocities is not None:
            point_data = {"velocity": velocities, **point_data}
        for name, values in point_data.items():
            values = np.asarray(values)
            if values.shape[:1] != (x.shape[0],):
                raise InvalidInputError(f"{who}: point data '{name}' has shape {values.shape}, "
                                        f"expected {x.shape[0]} rows (one per point)")
            if name == "velocity":
                try:
                    values = values.astype(np.float64)
                except (TypeError, ValueError) as e:
                    raise InvalidInputError(f"{who}: point data 'velocity' is not numbers: {e}") from None
                _check_finite_rows(values, "velocity", who)
            data[name] = values
        _check_cells_in_range(self.cells, x.shape[0], who)
        name = f"frame_{len(self.frames):05d}.vtu"
        path = os.path.join(self.directory, name)
        # Written beside and renamed: a write that fails (a disk full, point data meshio cannot
        # store) leaves no partial frame, and a reader never sees one half written.
        partial = path + ".partial"
        try:
            mesh = self._meshio.Mesh(x, self.cells, point_data=data)
            self._meshio.write(partial, mesh, file_format="vtu", binary=True)
            os.replace(partial, path)
        except BaseException as e:
            if os.path.lexists(partial):
                os.remove(partial)
            if isinstance(e, OSError) or not isinstance(e, Exception):
                raise
            raise InvalidInputError(f"{who}: meshio cannot write the frame: {type(e).__name__}: {e}") from e
        self.frames.append((time, name))
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


class VtkReporter:
    """A reporter that writes the simulation as a VTK time series: attach it with
    ``sim.add_reporter(VtkReporter("out", scene), every)`` and it writes the positions and
    velocities of every ``every``-th accepted step through a :class:`VtkSeriesWriter` (``out/
    frame_00000.vtu``, ...; the initial state first when ``initial`` is a Simulator), and
    ``close()`` (or leaving a ``with`` block) writes ``out/frames.pvd`` for ParaView. The reporter
    rules are the Simulator's (docs/guide.md, "Reporters"): a write that fails raises
    ``ReporterError`` from ``step()`` naming this reporter, and the step stands.

    Example::

        with stabint.io.VtkReporter("out", scene, initial=sim) as vtk:
            sim.add_reporter(vtk, 10)
            for _ in range(300):
                sim.step()
    """

    def __init__(self, directory: Union[str, os.PathLike], cells: Any, initial: Any = None) -> None:
        self.writer = VtkSeriesWriter(directory, cells)
        if initial is not None:
            self(initial, None)

    def __call__(self, sim: Any, report: Any) -> None:
        """Writes the simulator's current frame (what a reporter is called with after a step)."""
        self.writer.write(sim.time, sim.positions, sim.velocities)

    def close(self) -> str:
        """Writes the ``frames.pvd`` collection and returns its path."""
        return self.writer.close()

    def __enter__(self) -> "VtkReporter":
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
    # Every frame checked before the first is written: a refused series writes nothing.
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise InvalidInputError(f"write_vtk_series: time of frame {bad[0]} ({t[bad[0]]}) is not finite")
    for what, values in (("positions", x), ("velocities", v)):
        if values is not None:
            bad = np.flatnonzero(~_finite_rows(values))
            if bad.size:
                raise InvalidInputError(f"write_vtk_series: {what} of frame {bad[0]} are not finite; nothing written")
    _check_cells_in_range(_as_cells(cells, "write_vtk_series"), x.shape[1], "write_vtk_series")
    with VtkSeriesWriter(directory, cells) as writer:
        for k in range(len(x)):
            writer.write(t[k], x[k], None if v is None else v[k])
    return os.path.join(os.fspath(directory), "frames.pvd")


def read_pvd(path: Union[str, os.PathLike]) -> List[Tuple[float, str]]:
    """The (time, path of the .vtu) pairs a ``.pvd`` collection lists, in order; each path is the
    ``.pvd``'s directory joined with the entry's ``file``.

    FileFormatError naming the ``.pvd`` (and the entry) when it is not a regular file of at most
    :data:`MAX_FILE_BYTES`, is not well-formed XML, a ``DataSet`` lacks ``timestep`` or ``file``,
    a time is not a finite number, or a ``file`` leaves the ``.pvd``'s directory (an absolute path,
    or ``..`` past it): the paths returned are all inside that directory."""
    path = os.fspath(path)
    try:
        _checked_size(path)
        root = ET.parse(path).getroot()
    except (OSError, ValueError, ET.ParseError) as e:
        raise _file_error(path, f"not a readable .pvd collection: {e}") from e
    except RecursionError as e:  # nesting deeper than the XML parser builds
        raise _file_error(path, "not a readable .pvd collection: elements nested too deep") from e
    if root.tag != "VTKFile":
        raise _file_error(path, f"not a .pvd collection: the root element is <{root.tag}>, expected <VTKFile>")
    directory = os.path.dirname(path)
    frames = []
    for k, dataset in enumerate(root.iter("DataSet")):
        timestep, name = dataset.get("timestep"), dataset.get("file")
        if timestep is None or name is None:
            missing = " and ".join(a for a, v in (("timestep", timestep), ("file", name)) if v is None)
            raise _file_error(path, f"DataSet {k} has no {missing} attribute")
        try:
            time = float(timestep)
        except ValueError:
            raise _file_error(path, f"DataSet {k}: timestep {timestep!r} is not a number") from None
        if not np.isfinite(time):
            raise _file_error(path, f"DataSet {k}: timestep {timestep!r} is not finite")
        frames.append((time, os.path.join(directory, _inside(path, k, name))))
    return frames


def _inside(path: str, k: int, name: str) -> str:
    # The entry `name` as a path relative to the .pvd's directory that stays inside it (checked on
    # the text: no absolute path, no `..` that climbs out, not the directory itself).
    normal = os.path.normpath(name) if name else ""
    if os.path.isabs(name) or os.path.splitdrive(name)[0]:
        raise _file_error(path, f"DataSet {k}: file {name!r} is an absolute path; a .pvd lists files inside "
                                "its own directory")
    if normal in ("", ".") or normal == os.pardir or normal.startswith(os.pardir + os.sep):
        raise _file_error(path, f"DataSet {k}: file {name!r} is outside the .pvd's directory")
    return normal
