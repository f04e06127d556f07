"""stabint: stabilizing integrators for real-time deformable bodies.

The C++ library's API (scenes, builders, loaders, ``Simulator``, ``StepReport``, errors) from
the extension ``stabint._stabint``, plus builder shortcuts and :func:`scene_from_arrays`.

Copies and views: arrays returned by ``Simulator.positions``/``velocities`` and by the array
properties of :class:`Scene` are fresh copies the caller owns; step reports are copies; the
element lists of a scene (``scene.springs``, ``scene.pins``, ...) are views that edit it.

Per-frame input between steps: ``Simulator.set_pin_target``, ``set_external_forces``,
``set_collider_position``/``set_collider_velocity``, ``set_state``/``set_positions``/
``set_velocities``, ``set_iterations``; ``Simulator.checkpoint()`` returns a :class:`Checkpoint`
(``save``/``load``, ``bytes``, picklable) that ``restore`` continues from bit for bit. Scripted
events: ``load_scene_file_with_events`` gives a scene and an :class:`EventScript` whose
``apply(sim)`` before each step plays them (copy the script with a checkpoint to resume both).

Optional submodules, each behind its own extra and imported only when used:
``stabint.distributed`` (parameter sweeps of BatchSimulator batches on a Dask cluster,
``pip install stabint[distributed]``) and ``stabint.io`` (meshes in through meshio, VTK time
series out, ``pip install stabint[io]``); docs/distributed_and_io.md.

Example::

    import stabint
    sim = stabint.Simulator(stabint.cloth_grid(nx=30, ny=30),
                            stabint.SimulatorOptions(integrator=stabint.Integrator.EnergyBlend))
    for _ in range(300):
        report = sim.step()          # report.energy.total, report.target, report.branch, ...
    x = sim.positions                # (900, 3) float64 copy
"""

# The helpers' modules and names under private aliases, so that `dir(stabint)` and
# `from stabint import *` show the library alone (__all__ below); no `from __future__` import,
# which would add the name `annotations`: the annotations below are valid at run time on 3.9.
import json as _json
from typing import Any as _Any, Dict as _Dict, Optional as _Optional

import numpy as _np

from ._stabint import *  # noqa: F401,F403  (the extension's public names)
from ._stabint import InvalidInputError as _InvalidInputError, Pin as _Pin, Scene as _Scene, Spring as _Spring
from ._stabint import Tet as _Tet, builtin_scene as _builtin_scene
from . import _stabint

# The exception classes live in the extension (so that its stub declares them); they are used
# as stabint.<Name>, so they say so in tracebacks.
for _name in ("Error", "InvalidInputError", "FileFormatError", "NonFiniteStateError", "EnergyLimitError",
              "OpenCLError", "NoOpenCLDeviceError", "KernelBuildError", "UnsupportedPrecisionError",
              "OutOfMemoryError", "ReporterError"):
    getattr(_stabint, _name).__module__ = "stabint"

__version__ = "0.1.0"

_SUBMODULES = ("distributed", "io")

# The public names: the extension's and this file's. Not the submodules: `from stabint import *`
# would import them, and with them their optional extras (Dask, meshio).
__all__ = sorted([name for name in dir(_stabint) if not name.startswith("_")] +
                 ["cloth_grid", "tet_bar", "chain_pendulum", "linear_oscillator", "scene_from_arrays"])


def __getattr__(name: str) -> _Any:
    # stabint.distributed / stabint.io on first use (PEP 562): `import stabint` must not import
    # Dask or meshio, which are optional extras.
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'stabint' has no attribute '{name}'")


def _builtin(name: str, params: _Dict[str, _Any]) -> _Scene:
    # The builder's own parameter parsing (io.hpp builtinScene) checks names and types, so the
    # parameter lists are not repeated here; enum values are passed by name.
    text = {k: (v.name.lower() if hasattr(v, "name") else v) for k, v in params.items()}
    return _builtin_scene(name, _json.dumps(text), label=name)


def cloth_grid(**params: _Any) -> _Scene:
    """Rectangular cloth (``ClothGridParams`` fields as keywords, e.g. ``nx=30, pinned=[0, 29]``)."""
    return _builtin("cloth", params)


def tet_bar(**params: _Any) -> _Scene:
    """Box of tets pinned at x = 0 (``TetBarParams`` fields as keywords, e.g. ``nx=8``)."""
    return _builtin("tetbar", params)


def chain_pendulum(**params: _Any) -> _Scene:
    """Chain of springs pinned at the origin (``ChainPendulumParams`` fields as keywords)."""
    return _builtin("chain", params)


def linear_oscillator(**params: _Any) -> _Scene:
    """One particle on a pin to the origin (``mass``, ``stiffness``, ``amplitude``)."""
    return _builtin("oscillator", params)


def scene_from_arrays(
    positions: _Any,
    masses: _Any,
    *,
    velocities: _Optional[_Any] = None,
    springs: _Optional[_Any] = None,
    spring_stiffness: float = 0.0,
    tets: _Optional[_Any] = None,
    tet_stiffness: float = 0.0,
    triangles: _Optional[_Any] = None,
    pinned: _Optional[_Any] = None,
    pin_stiffness: float = 1e5,
    gravity: _Any = (0.0, -9.81, 0.0),
    name: str = "arrays",
) -> _Scene:
    """A scene from numpy arrays: ``positions`` (n, 3) (also the rest shape), ``masses`` (n,) or
    a scalar per particle, ``springs`` (m, 2) particle pairs (rest lengths from ``positions``),
    ``tets`` (m, 4), ``triangles`` (m, 3) surface, ``pinned`` particle indices held in place.
    A Simulator validates the scene (InvalidInputError); arrays that numpy cannot read as these
    shapes (ragged, wrong width, an index past the end) are an InvalidInputError here, naming the
    problem."""
    try:
        return _scene_from_arrays(positions, masses, velocities, springs, spring_stiffness, tets, tet_stiffness,
                                  triangles, pinned, pin_stiffness, gravity, name)
    except (ValueError, TypeError, IndexError) as e:
        raise _InvalidInputError(f"scene_from_arrays: {e}") from e


def _scene_from_arrays(positions, masses, velocities, springs, spring_stiffness, tets, tet_stiffness, triangles,
                       pinned, pin_stiffness, gravity, name):
    x = _np.asarray(positions, dtype=_np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"positions have shape {x.shape}, expected (n, 3)")
    scene = _Scene()
    scene.name = name
    scene.positions = x
    scene.rest_positions = x
    scene.velocities = _np.zeros_like(x) if velocities is None else _np.asarray(velocities, _np.float64)
    scene.masses = _np.broadcast_to(_np.asarray(masses, _np.float64), (x.shape[0],)).copy()
    scene.gravity = _np.asarray(gravity, _np.float64)
    for a, b in _np.asarray(springs if springs is not None else _np.empty((0, 2)), _np.int64):
        rest = float(_np.linalg.norm(x[a] - x[b]))
        scene.springs.append(_Spring(int(a), int(b), rest, spring_stiffness))
    for t in _np.asarray(tets if tets is not None else _np.empty((0, 4)), _np.int64):
        scene.tets.append(_Tet([int(i) for i in t], tet_stiffness))
    if triangles is not None:
        scene.triangles = _np.ascontiguousarray(triangles, dtype=_np.int32)
    for v in _np.asarray(pinned if pinned is not None else [], _np.int64):
        scene.pins.append(_Pin(int(v), pin_stiffness, x[v]))
    return scene
