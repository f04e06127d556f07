"""Parameter sweeps over many scenes on a Dask cluster: ``sweep`` and ``grid``.

A sweep splits a list of scenes into batches; each batch is one Dask task that builds a
:class:`stabint.BatchSimulator` in the worker, steps it and sends back, per scene, the trajectory
(positions, and velocities, every ``stride``-th frame) and the per-step reports (energies, H*,
the energy book, the blend's branch and alpha, refusals). Results come back in input order.

Why Dask and not Ray: Dask's ``distributed`` is pure-Python wheels (no compiled daemon), a
``LocalCluster`` of worker processes starts inside a test in seconds with no network beyond
loopback and no services to install, and the very same client code runs unchanged on a
multi-machine ``dask.distributed`` cluster (``Client("tcp://scheduler:8786")``, dask-jobqueue on
SLURM/PBS, Kubernetes). Ray's wheel is about 100 MB and runs its own GCS and raylet daemons,
which is a lot to bring in for "run this function on those workers and give me the arrays".
Install with ``pip install stabint[distributed]``; ``import stabint`` never imports Dask, and
without a client (and no default client) ``sweep`` runs the batches in this process.

What travels to the workers is a picklable description, never a C++ handle: a
:class:`BuiltinScene` (builder name and parameters), a :class:`stabint.Scene` (sent as the text
of its JSON scene file, which reads back exactly), or a picklable function returning a Scene,
called in the worker (for scenes that are cheaper to build than to send). Options travel as a
dict of :class:`stabint.SimulatorOptions` fields, enums by name.

Batches and options: a BatchSimulator has one set of options for all its scenes (one time step,
integrator and iteration count: one ``c M + L`` per solve, docs/batch_design.md), so cells are
first grouped by their full options, in order of first appearance, and each group is cut into
batches of at most ``batch_size`` scenes. Scenes of one batch must also share gravity (the batch
refuses others with ``InvalidInputError``); each scene's colliders act on its own particles only.

Determinism (what the tests check): a batch on a worker gives the same numbers, bit for bit, as
the same BatchSimulator stepped in this process (the CPU reference is deterministic, whatever its
thread count). A scene in a *different* batch (another ``batch_size``) agrees to round-off only:
the block-diagonal factor's fill-reducing ordering may order its block differently
(docs/batch_design.md), so compare across batch sizes with a tolerance.
"""

from __future__ import annotations

import enum
import itertools
import json
import os
import tempfile
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _stabint
from ._stabint import BatchSimulator, InvalidInputError, OpenCLOptions, Scene, SimulatorOptions

__all__ = ["BuiltinScene", "Cell", "SceneResult", "grid", "sweep", "run_batch", "REPORT_FIELDS"]


@dataclass(frozen=True)
class BuiltinScene:
    """A built-in scene by builder name (``"cloth"``, ``"chain"``, ``"tetbar"``,
    ``"oscillator"``) and its builder's parameters, e.g. ``BuiltinScene("cloth", {"nx": 10})``:
    a few bytes to send, built in the worker."""

    name: str
    params: Mapping[str, Any] = field(default_factory=dict)

    def build(self) -> Scene:
        from . import _builtin  # the package's shortcut: enum values by name, JSON parameters

        return _builtin(self.name, dict(self.params))


@dataclass(frozen=True)
class Cell:
    """One cell of a sweep: a scene description, the SimulatorOptions fields that differ from the
    sweep's ``options`` (by field name, e.g. ``{"time_step": 0.01}``) and ``key``, the values that
    identify the cell (the grid's axes), copied into its result."""

    scene: Any
    options: Mapping[str, Any] = field(default_factory=dict)
    key: Mapping[str, Any] = field(default_factory=dict)


# Per-step report fields, one array each in SceneResult.reports (frame 0 = the initial state:
# its energies and H*, zero elsewhere, as the CSV of stabint-run). Phase timings are left out:
# they are wall-clock and would make two identical runs differ.
REPORT_FIELDS = ("time", "kinetic", "elastic", "external", "total", "target", "forcing", "damping", "event_energy",
                 "friction", "contact_projection", "alpha", "velocity_scale", "iterations", "energy_evaluations",
                 "branch")


@dataclass
class SceneResult:
    """What a sweep gives back for one scene.

    ``frames`` (k,): the frame numbers recorded (0 = the initial state, then every ``stride``-th,
    and always the last); ``times`` (k,); ``positions`` and ``velocities`` (k, n, 3) (velocities
    None when not recorded); ``reports``: REPORT_FIELDS -> (frames + 1,) arrays, one entry per
    frame (``branch`` as names: 'none', 'IM', ...); ``refusal``: '' or the message of the first
    refused step (its own Simulator would have raised it), ``refused_at`` that frame (-1: none;
    the scene keeps its state from then on); ``index``: position in the sweep's input; ``key``
    and ``options`` of its cell; ``batch``: which batch ran it."""

    index: int
    key: Dict[str, Any]
    options: Dict[str, Any]
    batch: int
    frames: np.ndarray
    times: np.ndarray
    positions: np.ndarray
    velocities: Optional[np.ndarray]
    reports: Dict[str, np.ndarray]
    refusal: str = ""
    refused_at: int = -1


# --- options as plain data --------------------------------------------------------------------

def _option_fields() -> List[str]:
    return sorted(n for n in dir(SimulatorOptions) if not n.startswith("_"))


def _plain(value: Any) -> Any:
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, OpenCLOptions):
        return {"platform": value.platform, "device": value.device, "precision": value.precision.name}
    return value


def options_to_dict(options: Optional[Union[SimulatorOptions, Mapping[str, Any]]] = None,
                    **overrides: Any) -> Dict[str, Any]:
    """Every SimulatorOptions field as plain data (enums by name), from ``options`` (a
    SimulatorOptions, a dict of fields or None for the defaults) and ``overrides``. Unknown field
    names or values of the wrong type are an InvalidInputError naming the field."""
    base = options if isinstance(options, SimulatorOptions) else _options_from_dict(dict(options or {}))
    merged = {name: _plain(getattr(base, name)) for name in _option_fields()}
    if overrides:
        merged = {name: _plain(getattr(_options_from_dict({**merged, **overrides}), name))
                  for name in _option_fields()}
    return merged


def _options_from_dict(values: Mapping[str, Any]) -> SimulatorOptions:
    options = SimulatorOptions()
    known = set(_option_fields())
    for name, value in values.items():
        if name not in known:
            raise InvalidInputError(f"options: unknown SimulatorOptions field '{name}' (fields: {', '.join(sorted(known))})")
        current = getattr(options, name)
        try:
            if isinstance(current, enum.Enum) and isinstance(value, str):
                value = type(current)[value]
            elif isinstance(current, OpenCLOptions) and isinstance(value, Mapping):
                opencl = OpenCLOptions()
                opencl.platform = value["platform"]
                opencl.device = value["device"]
                opencl.precision = type(opencl.precision)[value["precision"]]
                value = opencl
            setattr(options, name, value)
        except (KeyError, TypeError, ValueError) as e:
            raise InvalidInputError(f"options.{name}: cannot take {value!r} ({e})") from e
    return options


# --- scenes as picklable descriptions ---------------------------------------------------------

@dataclass(frozen=True)
class _SceneJson:
    """A Scene in transit: the text of its JSON scene file (save_scene_file writes every number
    so that load_scene_file reads back the same scene)."""

    text: str

    def build(self) -> Scene:
        with tempfile.TemporaryDirectory(prefix="stabint-sweep-") as d:
            path = os.path.join(d, "scene.json")
            with open(path, "w", encoding="utf-8") as f:
                f.write(self.text)
            return _stabint.load_scene_file(path)


def _scene_json(scene: Scene) -> _SceneJson:
    with tempfile.TemporaryDirectory(prefix="stabint-sweep-") as d:
        path = os.path.join(d, "scene.json")
        _stabint.save_scene_file(scene, path)
        with open(path, encoding="utf-8") as f:
            return _SceneJson(f.read())


def _describe(scene: Any, index: int) -> Any:
    if isinstance(scene, Scene):
        try:
            return _scene_json(scene)  # validates it (a scene file holds valid scenes only)
        except InvalidInputError as e:
            raise InvalidInputError(f"sweep: scene {index}: {e}") from e
    if isinstance(scene, BuiltinScene):
        return scene
    if callable(scene):
        return scene
    raise InvalidInputError(f"sweep: scene {index}: expected a stabint.Scene, a BuiltinScene, a Cell or a function "
                            f"returning a Scene, got {type(scene).__name__}")


def _build(description: Any, index: int) -> Scene:
    try:
        scene = description.build() if isinstance(description, (BuiltinScene, _SceneJson)) else description()
    except _stabint.FileFormatError as e:  # a builder's unknown parameter, a factory's loader
        error = _stabint.FileFormatError(f"sweep: scene {index}: {e}")
        error.file, error.line = e.file, e.line
        raise error from e
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"sweep: scene {index}: the factory returned {type(scene).__name__}, not a stabint.Scene")
    try:
        scene.validate()
    except InvalidInputError as e:
        raise InvalidInputError(f"sweep: scene {index}: {e}") from e
    return scene


# --- the grid ---------------------------------------------------------------------------------

def grid(scene: Union[str, BuiltinScene], **axes: Sequence[Any]) -> List[Cell]:
    """The cells of a full-factorial sweep of a built-in scene, e.g.
    ``grid("cloth", nx=[10], stretch_stiffness=[1e2, 1e3], time_step=[1/30, 1/60])``: every
    combination of the axes' values, the first axis varying slowest. An axis named like a
    SimulatorOptions field (``time_step``, ``integrator``, ``iterations``, ...) sets that option;
    any other name is a parameter of the builder (its own parsing checks it in the worker). A
    scalar instead of a list is an axis of one value; parameters that are lists themselves
    (``pinned``) go into the base: ``grid(BuiltinScene("cloth", {"pinned": [0]}), ...)``.
    Enum options may be given by name (``integrator=["BackwardEuler", "EnergyBlend"]``). Each
    cell's ``key`` holds its axis values."""
    base = BuiltinScene(scene) if isinstance(scene, str) else scene
    if not isinstance(base, BuiltinScene):
        raise InvalidInputError(f"grid: expected a built-in scene name or a BuiltinScene, got {type(scene).__name__}")
    option_names = set(_option_fields())
    names = list(axes)
    values = []
    for name in names:
        v = axes[name]
        v = list(v) if isinstance(v, (list, tuple, np.ndarray, range)) else [v]
        if not v:
            raise InvalidInputError(f"grid: axis '{name}' has no values")
        values.append(v)
    cells = []
    for combination in itertools.product(*values):
        key = dict(zip(names, combination))
        params = {**base.params, **{k: v for k, v in key.items() if k not in option_names}}
        options = {k: v for k, v in key.items() if k in option_names}
        cells.append(Cell(BuiltinScene(base.name, params), options, key))
    return cells


# --- one batch: what a worker runs --------------------------------------------------------------

@dataclass(frozen=True)
class _Batch:
    number: int
    indices: Tuple[int, ...]
    scenes: Tuple[Any, ...]
    keys: Tuple[Dict[str, Any], ...]
    options: Dict[str, Any]
    frames: int
    stride: int
    velocities: bool


def _recorded(frames: int, stride: int) -> List[int]:
    recorded = list(range(0, frames + 1, stride))
    if recorded[-1] != frames:
        recorded.append(frames)  # the last frame always, as stabint-run --every
    return recorded


def run_batch(scenes: Sequence[Scene], options: Union[SimulatorOptions, Mapping[str, Any], None], frames: int, *,
              stride: int = 1, velocities: bool = True) -> List[SceneResult]:
    """Steps ``scenes`` (built Scenes) as one BatchSimulator for ``frames`` steps in this process
    and returns their SceneResults: what each worker of a sweep does with its batch."""
    _check_counts(frames, 1, stride)
    descriptions = tuple(_scene_json(s) if isinstance(s, Scene) else s for s in scenes)
    batch = _Batch(0, tuple(range(len(scenes))), descriptions, tuple({} for _ in scenes), options_to_dict(options),
                   frames, stride, velocities)
    return _run(batch)


def _run(batch: _Batch) -> List[SceneResult]:
    scenes = [_build(d, i) for d, i in zip(batch.scenes, batch.indices)]
    options = _options_from_dict(batch.options)
    try:
        sim = BatchSimulator(scenes, options)
    except InvalidInputError as e:
        raise InvalidInputError(f"sweep: the batch of scenes {list(batch.indices)}: {e}") from e
    count = len(scenes)
    recorded = _recorded(batch.frames, batch.stride)
    slot = {frame: k for k, frame in enumerate(recorded)}
    sizes = [sim.num_particles(s) for s in range(count)]
    positions = [np.empty((len(recorded), n, 3)) for n in sizes]
    velocities = [np.empty((len(recorded), n, 3)) for n in sizes] if batch.velocities else None
    times = np.empty(len(recorded))
    reports = [{name: np.zeros(batch.frames + 1, dtype=np.int64 if name in ("iterations", "energy_evaluations")
                               else "<U16" if name == "branch" else np.float64) for name in REPORT_FIELDS}
               for _ in range(count)]
    refusal = [""] * count
    refused_at = [-1] * count

    def record(frame: int) -> None:
        if frame in slot:
            k = slot[frame]
            times[k] = sim.time
            for s in range(count):
                positions[s][k] = sim.positions(s)
                if velocities is not None:
                    velocities[s][k] = sim.velocities(s)

    for s in range(count):
        e = sim.energy(s)
        r = reports[s]
        r["kinetic"][0], r["elastic"][0], r["external"][0], r["total"][0] = e.kinetic, e.elastic, e.external, e.total
        r["target"][0] = sim.target(s)
        r["branch"][0] = "none"
    record(0)
    for frame in range(1, batch.frames + 1):
        step = sim.step()
        for s in range(count):
            rep, r = step.scenes[s], reports[s]
            r["time"][frame] = rep.time
            r["kinetic"][frame], r["elastic"][frame] = rep.energy.kinetic, rep.energy.elastic
            r["external"][frame], r["total"][frame] = rep.energy.external, rep.energy.total
            for name in ("target", "forcing", "damping", "event_energy", "friction", "contact_projection", "alpha",
                         "velocity_scale", "iterations", "energy_evaluations"):
                r[name][frame] = getattr(rep, name)
            r["branch"][frame] = _stabint.blend_branch_name(rep.branch)
            if step.refusals[s] and refused_at[s] < 0:
                refusal[s], refused_at[s] = step.refusals[s], frame
        record(frame)
    return [SceneResult(index=batch.indices[s], key=dict(batch.keys[s]), options=dict(batch.options),
                        batch=batch.number, frames=np.array(recorded), times=times.copy(), positions=positions[s],
                        velocities=None if velocities is None else velocities[s], reports=reports[s],
                        refusal=refusal[s], refused_at=refused_at[s])
            for s in range(count)]


# --- the sweep --------------------------------------------------------------------------------

def _check_counts(frames: Any, batch_size: Any, stride: Any) -> None:
    for name, value, least in (("frames", frames, 0), ("batch_size", batch_size, 1), ("stride", stride, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise InvalidInputError(f"sweep: {name} must be an integer >= {least}, got {value!r}")


def plan(scenes: Sequence[Any], options: Union[SimulatorOptions, Mapping[str, Any], None] = None, *,
         batch_size: int = 64) -> List[List[int]]:
    """The batches a sweep would run, as lists of input indices: cells grouped by their full
    options (in order of first appearance), each group cut into runs of ``batch_size``."""
    _check_counts(0, batch_size, 1)
    return [list(b.indices) for b in _batches(scenes, options, 0, batch_size, 1, False)]


def _batches(scenes: Sequence[Any], options: Any, frames: int, batch_size: int, stride: int,
             velocities: bool) -> List[_Batch]:
    if isinstance(scenes, (Scene, Cell, BuiltinScene)) or not isinstance(scenes, Sequence) or len(scenes) == 0:
        raise InvalidInputError("sweep: expected a non-empty list of scenes or cells "
                                f"(got {type(scenes).__name__}{' of length 0' if isinstance(scenes, Sequence) else ''})")
    base = options_to_dict(options)
    groups: Dict[str, List[Tuple[int, Any, Dict[str, Any], Dict[str, Any]]]] = {}
    for index, item in enumerate(scenes):
        cell = item if isinstance(item, Cell) else Cell(item)
        try:
            cell_options = options_to_dict(base, **dict(cell.options)) if cell.options else base
        except InvalidInputError as e:
            raise InvalidInputError(f"sweep: scene {index}: {e}") from e
        signature = json.dumps(cell_options, sort_keys=True)
        if signature not in groups:
            _check_batch_options(cell_options, index, batch_size)
        groups.setdefault(signature, []).append((index, _describe(cell.scene, index), dict(cell.key), cell_options))
    batches = []
    for members in groups.values():
        for first in range(0, len(members), batch_size):
            chunk = members[first:first + batch_size]
            batches.append(_Batch(len(batches), tuple(m[0] for m in chunk), tuple(m[1] for m in chunk),
                                  tuple(m[2] for m in chunk), chunk[0][3], frames, stride, velocities))
    return batches


def _check_batch_options(options: Dict[str, Any], index: int, batch_size: int) -> None:
    # Options the library refuses (their values: a batch takes every solver option) are found
    # here, before any task is sent, by the library's own check on a batch of one-particle scenes
    # as large as the sweep's batches (up to two). Only for the CPU reference: an OpenCL choice is
    # checked where the device is, in the worker.
    if options["backend"] != "CpuReference":
        return
    try:
        BatchSimulator([_stabint.builtin_scene("oscillator")] * min(batch_size, 2), _options_from_dict(options))
    except InvalidInputError as e:
        raise InvalidInputError(f"sweep: scene {index}: {e}") from e


def _default_client() -> Any:
    try:
        from distributed import default_client
    except ImportError:
        return None
    try:
        return default_client()
    except ValueError:  # no client has been created in this process
        return None


def sweep(scenes: Sequence[Any], options: Union[SimulatorOptions, Mapping[str, Any], None] = None,
          frames: int = 100, *, batch_size: int = 64, stride: int = 1, velocities: bool = True,
          client: Any = None) -> List[SceneResult]:
    """Steps every scene for ``frames`` steps and returns one SceneResult per input, in order.

    ``scenes``: stabint.Scene, BuiltinScene, functions returning a Scene (pickled to the worker
    and called there), or :class:`Cell` (a scene with its own option overrides and key, e.g. from
    :func:`grid`). ``options``: the SimulatorOptions shared by all cells (or a dict of fields).
    Cells with equal options are batched together, ``batch_size`` at most per BatchSimulator;
    ``stride``: record positions (and velocities) every ``stride``-th frame (reports: every
    frame). ``client``: a ``dask.distributed.Client``; None uses the default client when one
    exists, else runs the batches one after another in this process.

    Bad input raises InvalidInputError naming the scene or batch: an empty list, an object that
    is not a scene description, an unknown option field, a scene that does not validate, or a
    batch the BatchSimulator refuses (differing gravity, a bad option value). Errors raised in a worker reach the caller with their own class."""
    _check_counts(frames, batch_size, stride)
    batches = _batches(scenes, options, frames, batch_size, stride, velocities)
    client = client if client is not None else _default_client()
    if client is None:
        per_batch = [_run(b) for b in batches]
    else:
        # pure=False: two identical batches are still two tasks (Dask would otherwise merge them
        # by their hash, which is right but surprising when timing a sweep).
        futures = [client.submit(_run, b, pure=False, key=f"stabint-sweep-batch-{b.number}-{os.urandom(4).hex()}")
                   for b in batches]
        per_batch = client.gather(futures)
    results: List[Optional[SceneResult]] = [None] * len(scenes)
    for batch_results in per_batch:
        for r in batch_results:
            results[r.index] = r
    return results  # type: ignore[return-value]
