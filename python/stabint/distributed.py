"""Parameter sweeps over many scenes, on the executor a user already runs: ``sweep`` and ``grid``.

A sweep splits a list of scenes into batches; each batch is one task that builds a
:class:`stabint.BatchSimulator` where it runs, steps it and sends back, per scene, the trajectory
(positions, and velocities, every ``stride``-th frame) and the per-step reports (energies, H*,
the energy book, the blend's branch and alpha, refusals). ``sweep`` returns the results in input
order; ``sweep_iter`` yields each batch's as it finishes, and ``sweep(on_batch=...)`` calls back
with them, so that a progress bar can follow.

Executors, through one argument (``executor``): a ``dask.distributed.Client`` (a LocalCluster in
one machine, or a multi-machine cluster: ``Client("tcp://scheduler:8786")``, dask-jobqueue on
SLURM/PBS, Kubernetes), the ``ray`` module after ``ray.init()``, or a ``concurrent.futures``
process or thread pool; without one, the batches run in this process. A batch gives the same
numbers, bit for bit, on each of them. The ``[distributed]`` extra pins Dask (pure-Python
wheels, a LocalCluster starts inside a test in seconds); Ray (about 100 MB, its own daemons) and
the standard library's pools need nothing from stabint. ``import stabint`` never imports Dask or
Ray.

What travels to the workers is a picklable description, never a C++ handle: a
:class:`BuiltinScene` (builder name and parameters), a :class:`stabint.Scene` (sent as the text
of its JSON scene file, which reads back exactly), or a picklable function returning a Scene,
called in the worker (for scenes that are cheaper to build than to send). Options travel as a
dict of :class:`stabint.SimulatorOptions` fields, enums by name.

Checked before any task is sent: every scene description that can be checked in this process is
(a BuiltinScene's builder name and parameter names, with a "did you mean" for a close name, its
values (a NaN or an infinity is named as such) and the scene it builds, once per distinct set of
parameters; a Scene's validation; the options; the gravity of the scenes of each batch). A typo
is an error at once, not a failure in a worker after everything else has run.

Finished work is kept: with ``errors="report"`` (the default) a batch that fails in its worker (a
factory raising, a scene it cannot build, the BatchSimulator refusing the batch, a step raising)
gives each of its scenes a SceneResult whose ``error`` (and ``refusal``) names the scene (its
index and description) and the cause, and every other batch's results come back as usual.
``errors="raise"`` raises the first failure instead, with its class, naming the scene.

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

import concurrent.futures
import difflib
import enum
import itertools
import json
import math
import os
import re
import tempfile
import types
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _stabint
from ._stabint import BatchSimulator, FileFormatError, InvalidInputError, OpenCLOptions, Scene, SimulatorOptions

__all__ = ["BuiltinScene", "Cell", "SceneResult", "SceneParameterError", "grid", "plan", "sweep", "sweep_iter",
           "run_batch", "REPORT_FIELDS"]


class SceneParameterError(InvalidInputError, FileFormatError):
    """A built-in scene's name or parameters refused: an unknown builder or parameter name (with
    the closest known name when there is one), a NaN or infinite value, or a value its builder
    refuses. It is an :class:`stabint.InvalidInputError` (bad input to a sweep) and the builder's
    own :class:`stabint.FileFormatError` (``file``: the builder's name, ``line``: 0), so either
    ``except`` catches it."""


SceneParameterError.__module__ = "stabint.distributed"


def _did_you_mean(name: Any, known: Sequence[str]) -> str:
    close = difflib.get_close_matches(str(name), list(known), n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'? " if close else ""


def _parameter_error(message: str, builder: Any) -> SceneParameterError:
    error = SceneParameterError(message)
    error.file, error.line = str(builder), 0
    return error


def _plain_param(value: Any) -> Any:
    # numpy scalars and arrays (a grid axis from np.linspace) as JSON numbers and lists
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain_param(v) for v in value]
    return value


def _non_finite(value: Any, path: str) -> Optional[Tuple[str, float]]:
    if isinstance(value, float) and not math.isfinite(value):
        return path, value
    if isinstance(value, list):
        for k, v in enumerate(value):
            found = _non_finite(v, f"{path}[{k}]")
            if found:
                return found
    return None


def _builtin_params(name: Any, params: Any) -> Dict[str, Any]:
    """The parameters of built-in scene ``name`` as JSON-ready values, after the checks the
    caller can make without building: a known builder, known parameter names, finite numbers."""
    names = list(_stabint.builtin_scene_names())
    if not isinstance(name, str) or name not in names:
        raise _parameter_error(f"unknown built-in scene {name!r} ({_did_you_mean(name, names)}"
                               f"expected one of: {', '.join(names)})", name)
    if not isinstance(params, Mapping):
        raise _parameter_error(f"{name}: params must be a mapping of parameter names to values, got "
                               f"{type(params).__name__}", name)
    known = sorted(_stabint.builtin_scene_parameters(name))
    plain = {}
    for key, value in params.items():
        if key not in known:
            raise _parameter_error(f"{name}: params: unknown field {key!r} ({_did_you_mean(key, known)}"
                                   f"expected one of: {', '.join(known)})", name)
        value = _plain_param(value)
        found = _non_finite(value, str(key))
        if found:
            path, bad = found
            what = "NaN" if math.isnan(bad) else f"infinite ({bad})"
            raise _parameter_error(f"{name}: params.{path} is {what}; a parameter must be a finite number", name)
        plain[key] = value
    return plain


@dataclass(frozen=True)
class BuiltinScene:
    """A built-in scene by builder name (``"cloth"``, ``"chain"``, ``"tetbar"``,
    ``"oscillator"``) and its builder's parameters, e.g. ``BuiltinScene("cloth", {"nx": 10})``:
    a few bytes to send, built in the worker (a sweep also builds it once in the caller, to
    check it before any task is sent). ``build`` raises :class:`SceneParameterError` for an
    unknown builder or parameter name, a NaN or infinite value, or a value the builder refuses."""

    name: str
    params: Mapping[str, Any] = field(default_factory=dict)

    def build(self) -> Scene:
        """The Scene the builder makes from the parameters (SceneParameterError when it cannot)."""
        from . import _builtin  # the package's shortcut: enum values by name, JSON parameters

        params = _builtin_params(self.name, self.params)
        try:
            return _builtin(self.name, params)
        except FileFormatError as e:  # a value the builder's own parsing refuses (nx = 1, a string, ...)
            error = _parameter_error(str(e), self.name)
            error.file, error.line = getattr(e, "file", self.name), getattr(e, "line", 0)
            raise error from e
        except (TypeError, ValueError) as e:  # a value JSON cannot hold (an arbitrary object)
            raise _parameter_error(f"{self.name}: params: {e}", self.name) from e


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
    and ``options`` of its cell; ``batch``: which batch ran it.

    ``error``: '' when the scene's batch ran to the end; else why it did not (``sweep(...,
    errors="report")``, the default): a message naming the scene (``sweep: scene <index>:
    <description>: ...``) and the cause (the factory's exception with its class, the batch the
    BatchSimulator refused, a step that raised, or "its batch <n> (scenes [...]) failed: ..."
    for the other scenes of that batch). Such a result keeps what was computed before the
    failure (``frames``, ``times``, ``positions``, ``velocities`` and ``reports`` hold the frames
    completed, none when the batch failed before its first step: then they are empty, of length
    0), ``refusal`` is the same message unless a step was refused earlier, and ``refused_at`` the
    first frame not completed (0: none was), so that ``[r for r in results if r.refusal]`` finds
    every scene that did not run to the end."""

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
    error: str = ""


# --- options as plain data --------------------------------------------------------------------

def _option_fields() -> List[str]:
    return sorted(n for n in dir(SimulatorOptions) if not n.startswith("_"))


def _plain(value: Any) -> Any:
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, OpenCLOptions):
        return {name: _plain(getattr(value, name)) for name in value.__getstate__()}
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
        # An enum field takes its value's name itself ("BE", "EnergyBlend"), as SimulatorOptions does.
        try:
            if isinstance(getattr(options, name), OpenCLOptions) and isinstance(value, Mapping):
                value = OpenCLOptions(**value)
            setattr(options, name, value)
        except (InvalidInputError, TypeError, ValueError) as e:
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


def _callable_name(function: Any) -> str:
    if hasattr(function, "func") and hasattr(function, "args") and hasattr(function, "keywords"):  # functools.partial
        arguments = [repr(a) for a in function.args] + [f"{k}={v!r}" for k, v in function.keywords.items()]
        return f"partial({_callable_name(function.func)}, {', '.join(arguments)})"
    qualname = getattr(function, "__qualname__", None)
    if qualname is None:
        return repr(function)
    module = getattr(function, "__module__", None)
    return f"{module}.{qualname}" if module else qualname


def _label(description: Any, key: Optional[Mapping[str, Any]] = None) -> str:
    """A short description of a scene for messages: builder and parameters, the scene's name, or
    the factory, and the cell's key."""
    if isinstance(description, BuiltinScene):
        params = description.params
        text = f"BuiltinScene({description.name!r}, {dict(params) if isinstance(params, Mapping) else params!r})"
    elif isinstance(description, Scene):
        text = f"Scene {description.name!r}"
    elif isinstance(description, _SceneJson):
        found = re.search(r'"name"\s*:\s*("(?:[^"\\]|\\.)*")', description.text[:4096])
        try:
            text = f"Scene {json.loads(found.group(1))!r}" if found else "Scene"
        except ValueError:
            text = "Scene"
    else:
        text = f"factory {_callable_name(description)}"
    if key:
        text += f" (key {dict(key) if isinstance(key, Mapping) else key!r})"
    return text if len(text) <= 200 else text[:197] + "..."


def _named(error: BaseException, prefix: str, with_class: bool) -> Exception:
    """``error`` with ``prefix`` before its message: the library's errors keep their class (and
    attributes: a FileFormatError's file and line), others become InvalidInputError."""
    message = prefix + (f"{type(error).__name__}: " if with_class else "") + str(error)
    if isinstance(error, _stabint.Error):
        try:
            named = type(error)(message)
            named.__dict__.update(getattr(error, "__dict__", {}))
            return named
        except Exception:  # an error class that takes other arguments: fall through
            pass
    return InvalidInputError(message)


def _describe(scene: Any, index: int, key: Mapping[str, Any], checked: Dict[str, Tuple[float, ...]]
              ) -> Tuple[Any, Optional[Tuple[float, ...]]]:
    """What travels for input ``scene`` and its gravity when known here (None for a factory),
    after the checks this process can make. ``checked``: the gravity of each BuiltinScene built
    so far, by its parameters (a grid repeats them across option axes)."""
    if isinstance(scene, Scene):
        try:
            description = _scene_json(scene)  # validates it (a scene file holds valid scenes only)
        except InvalidInputError as e:
            raise InvalidInputError(f"sweep: scene {index}: {e}") from e
        return description, tuple(float(g) for g in scene.gravity)
    if isinstance(scene, BuiltinScene):
        label = _label(scene, key)
        try:
            params = _builtin_params(scene.name, scene.params)
            signature = json.dumps([scene.name, params], sort_keys=True, default=repr)
        except SceneParameterError as e:
            raise _named(e, f"sweep: scene {index}: {label}: ", False) from e
        except (TypeError, ValueError) as e:  # parameter names JSON cannot sort or hold
            raise _parameter_error(f"sweep: scene {index}: {label}: {scene.name}: params: {e}", scene.name) from e
        if signature not in checked:
            try:
                built = scene.build()
                built.validate()
            except SceneParameterError as e:
                raise _named(e, f"sweep: scene {index}: {label}: ", False) from e
            except InvalidInputError as e:
                raise InvalidInputError(f"sweep: scene {index}: {label}: {e}") from e
            except Exception as e:  # anything else building it raised, named
                raise _named(e, f"sweep: scene {index}: {label}: ", True) from e
            checked[signature] = tuple(float(g) for g in built.gravity)
        return scene, checked[signature]
    if callable(scene):
        return scene, None
    raise InvalidInputError(f"sweep: scene {index}: expected a stabint.Scene, a BuiltinScene, a Cell or a function "
                            f"returning a Scene, got {type(scene).__name__}")


def _build(description: Any, index: int, key: Optional[Mapping[str, Any]] = None) -> Scene:
    """Builds a scene description in the worker; every error names the scene (its index in the
    sweep and its description) and keeps its class when it is one of the library's."""
    try:
        if isinstance(description, (BuiltinScene, _SceneJson)):
            scene = description.build()
        else:
            scene = description()
    except Exception as e:  # a builder's or loader's refusal, anything a factory raises
        factory = not isinstance(description, (BuiltinScene, _SceneJson))
        prefix = f"sweep: scene {index}: {_label(description, key)}: " + ("the factory raised " if factory else "")
        raise _named(e, prefix, factory) from e
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"sweep: scene {index}: {_label(description, key)}: the factory returned "
                                f"{type(scene).__name__}, not a stabint.Scene")
    try:
        scene.validate()
    except InvalidInputError as e:
        raise InvalidInputError(f"sweep: scene {index}: {_label(description, key)}: {e}") from e
    return scene


# --- the grid ---------------------------------------------------------------------------------

def grid(scene: Union[str, BuiltinScene], **axes: Sequence[Any]) -> List[Cell]:
    """The cells of a full-factorial sweep of a built-in scene, e.g.
    ``grid("cloth", nx=[10], stretch_stiffness=[1e2, 1e3], time_step=[1/30, 1/60])``: every
    combination of the axes' values, the first axis varying slowest. An axis named like a
    SimulatorOptions field (``time_step``, ``integrator``, ``iterations``, ...) sets that option;
    any other name must be a parameter of the builder: an unknown builder or axis name is a
    :class:`SceneParameterError` here (with the closest known name), and the values are checked
    by the sweep, before any task is sent. A scalar instead of a list is an axis of one value;
    parameters that are lists themselves (``pinned``) go into the base:
    ``grid(BuiltinScene("cloth", {"pinned": [0]}), ...)``. Enum options may be given by name
    (``integrator=["BackwardEuler", "EnergyBlend"]``). Each cell's ``key`` holds its axis values."""
    base = BuiltinScene(scene) if isinstance(scene, str) else scene
    if not isinstance(base, BuiltinScene):
        raise InvalidInputError(f"grid: expected a built-in scene name or a BuiltinScene, got {type(scene).__name__}")
    option_names = set(_option_fields())
    try:
        _builtin_params(base.name, {})
    except SceneParameterError as e:
        raise _named(e, "grid: ", False) from e
    parameters = sorted(_stabint.builtin_scene_parameters(base.name))
    names = list(axes)
    values = []
    for name in names:
        if name not in option_names and name not in parameters:
            raise _parameter_error(
                f"grid: axis '{name}' is neither a parameter of the {base.name} builder nor a SimulatorOptions field "
                f"({_did_you_mean(name, parameters + sorted(option_names))}{base.name} takes: {', '.join(parameters)})",
                base.name)
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
    and returns their SceneResults: what each worker of a sweep does with its batch. A failure
    raises, as ``sweep(..., errors="raise")``, naming the scene or the batch."""
    _check_counts(frames, 1, stride)
    descriptions = tuple(_scene_json(s) if isinstance(s, Scene) else s for s in scenes)
    batch = _Batch(0, tuple(range(len(scenes))), descriptions, tuple({} for _ in scenes), options_to_dict(options),
                   frames, stride, velocities)
    return _run(batch)


_ERRORS = ("report", "raise")


def _check_errors(errors: Any) -> None:
    if not isinstance(errors, str) or errors not in _ERRORS:
        raise InvalidInputError(f"sweep: errors must be 'report' or 'raise', got {errors!r}")


class _BatchRun:
    """One batch's trajectories and reports as far as they were computed: ``done`` is the last
    frame recorded (-1: none), so that a failure can still return what came before it."""

    def __init__(self, batch: _Batch) -> None:
        self.batch = batch
        self.count = len(batch.indices)
        self.recorded = _recorded(batch.frames, batch.stride)
        self.sizes = [0] * self.count
        self.positions: Optional[List[np.ndarray]] = None
        self.velocities: Optional[List[np.ndarray]] = None
        self.times = np.empty(len(self.recorded))
        self.reports: Optional[List[Dict[str, np.ndarray]]] = None
        self.refusal = [""] * self.count
        self.refused_at = [-1] * self.count
        self.done = -1

    def step(self, sim: BatchSimulator) -> None:
        batch, count, recorded = self.batch, self.count, self.recorded
        slot = {frame: k for k, frame in enumerate(recorded)}
        self.sizes = sizes = [sim.num_particles(s) for s in range(count)]
        self.positions = positions = [np.empty((len(recorded), n, 3)) for n in sizes]
        self.velocities = velocities = [np.empty((len(recorded), n, 3)) for n in sizes] if batch.velocities else None
        times = self.times
        self.reports = reports = [
            {name: np.zeros(batch.frames + 1, dtype=np.int64 if name in ("iterations", "energy_evaluations")
                            else "<U16" if name == "branch" else np.float64) for name in REPORT_FIELDS}
            for _ in range(count)]
        refusal, refused_at = self.refusal, self.refused_at

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
            r["kinetic"][0], r["elastic"][0] = e.kinetic, e.elastic
            r["external"][0], r["total"][0] = e.external, e.total
            r["target"][0] = sim.target(s)
            r["branch"][0] = "none"
        record(0)
        self.done = 0
        for frame in range(1, batch.frames + 1):
            try:
                step = sim.step()
            except Exception as e:  # the library's errors (a device's), not a scene's refusal
                raise _named(e, f"sweep: the batch of scenes {list(batch.indices)}: step {frame}: ", True) from e
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
            self.done = frame

    def results(self) -> List[SceneResult]:
        batch = self.batch
        assert self.positions is not None and self.reports is not None
        return [SceneResult(index=batch.indices[s], key=dict(batch.keys[s]), options=dict(batch.options),
                            batch=batch.number, frames=np.array(self.recorded), times=self.times.copy(),
                            positions=self.positions[s],
                            velocities=None if self.velocities is None else self.velocities[s],
                            reports=self.reports[s], refusal=self.refusal[s], refused_at=self.refused_at[s])
                for s in range(self.count)]

    def failed(self, cause: BaseException, culprit: Optional[int] = None) -> List[SceneResult]:
        """Every scene's result after ``cause`` stopped the batch: what was recorded up to frame
        ``done`` and a message naming the scene and the cause (``culprit``: the input index of
        the scene that caused it, when known; its message is the cause's own)."""
        batch, done = self.batch, self.done
        kept = [frame for frame in self.recorded if frame <= done]
        text = str(cause)
        cause_text = text if text.startswith("sweep: ") else f"{type(cause).__name__}: {text}"
        results = []
        for s in range(self.count):
            index = batch.indices[s]
            own = f"sweep: scene {index}: "
            if index == culprit and text.startswith(own):
                message = text
            else:
                message = (f"{own}{_label(batch.scenes[s], batch.keys[s])}: its batch {batch.number} "
                           f"(scenes {list(batch.indices)}) failed: {cause_text}")
            n = self.sizes[s]
            if self.reports is None:
                reports = {name: np.zeros(0, dtype=np.int64 if name in ("iterations", "energy_evaluations")
                                          else "<U16" if name == "branch" else np.float64) for name in REPORT_FIELDS}
            else:
                reports = {name: values[:done + 1].copy() for name, values in self.reports[s].items()}
            positions = self.positions[s][:len(kept)].copy() if self.positions is not None else np.empty((0, n, 3))
            velocities = None
            if batch.velocities:
                velocities = (self.velocities[s][:len(kept)].copy() if self.velocities is not None
                              else np.empty((0, n, 3)))
            refused = self.refused_at[s] >= 0
            results.append(SceneResult(
                index=index, key=dict(batch.keys[s]), options=dict(batch.options), batch=batch.number,
                frames=np.array(kept, dtype=np.int64), times=self.times[:len(kept)].copy(), positions=positions,
                velocities=velocities, reports=reports, refusal=self.refusal[s] if refused else message,
                refused_at=self.refused_at[s] if refused else done + 1, error=message))
        return results


def _run(batch: _Batch, errors: str = "raise") -> List[SceneResult]:
    """What a worker runs: builds the batch's scenes and BatchSimulator and steps it. A failure
    raises (``errors="raise"``, naming the scene or the batch) or becomes every scene's
    SceneResult.error (``"report"``)."""
    run = _BatchRun(batch)
    culprit: Optional[int] = None
    try:
        scenes = []
        for description, index, key in zip(batch.scenes, batch.indices, batch.keys):
            culprit = index
            scenes.append(_build(description, index, key))
        culprit = None
        options = _options_from_dict(batch.options)
        try:
            sim = BatchSimulator(scenes, options)
        except InvalidInputError as e:
            message = str(e)
            which = re.match(r"scene (\d+): ", message)  # the batch's own numbering: say which input it is
            if which and int(which.group(1)) < len(batch.indices):
                message += f" (the batch's scene {which.group(1)} is scene {batch.indices[int(which.group(1))]})"
            raise InvalidInputError(f"sweep: the batch of scenes {list(batch.indices)}: {message}") from e
        run.step(sim)
    except Exception as e:
        if errors == "raise":
            raise
        return run.failed(e, culprit)
    return run.results()


# --- the sweep --------------------------------------------------------------------------------

def _check_counts(frames: Any, batch_size: Any, stride: Any) -> None:
    for name, value, least in (("frames", frames, 0), ("batch_size", batch_size, 1), ("stride", stride, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
            raise InvalidInputError(f"sweep: {name} must be an integer >= {least}, got {value!r}")


def plan(scenes: Sequence[Any], options: Union[SimulatorOptions, Mapping[str, Any], None] = None, *,
         batch_size: int = 64) -> List[List[int]]:
    """The batches a sweep would run, as lists of input indices: cells grouped by their full
    options (in order of first appearance), each group cut into runs of ``batch_size``. Makes
    every check ``sweep`` makes before sending a task (bad parameters raise here, naming the
    scene)."""
    _check_counts(0, batch_size, 1)
    return [list(b.indices) for b in _batches(scenes, options, 0, batch_size, 1, False)]


def _batches(scenes: Sequence[Any], options: Any, frames: int, batch_size: int, stride: int,
             velocities: bool) -> List[_Batch]:
    if isinstance(scenes, (Scene, Cell, BuiltinScene)) or not isinstance(scenes, Sequence) or len(scenes) == 0:
        raise InvalidInputError("sweep: expected a non-empty list of scenes or cells "
                                f"(got {type(scenes).__name__}{' of length 0' if isinstance(scenes, Sequence) else ''})")
    base = options_to_dict(options)
    groups: Dict[str, List[Tuple[int, Any, Dict[str, Any], Dict[str, Any], Optional[Tuple[float, ...]]]]] = {}
    checked: Dict[str, Tuple[float, ...]] = {}
    for index, item in enumerate(scenes):
        cell = item if isinstance(item, Cell) else Cell(item)
        try:
            cell_options = options_to_dict(base, **dict(cell.options)) if cell.options else base
        except InvalidInputError as e:
            raise InvalidInputError(f"sweep: scene {index}: {e}") from e
        signature = json.dumps(cell_options, sort_keys=True)
        if signature not in groups:
            _check_batch_options(cell_options, index, batch_size)
        description, gravity = _describe(cell.scene, index, cell.key, checked)
        groups.setdefault(signature, []).append((index, description, dict(cell.key), cell_options, gravity))
    batches = []
    for members in groups.values():
        for first in range(0, len(members), batch_size):
            chunk = members[first:first + batch_size]
            _check_gravity([(m[0], m[1], m[2], m[4]) for m in chunk])
            batches.append(_Batch(len(batches), tuple(m[0] for m in chunk), tuple(m[1] for m in chunk),
                                  tuple(m[2] for m in chunk), chunk[0][3], frames, stride, velocities))
    return batches


def _check_gravity(members: List[Tuple[int, Any, Dict[str, Any], Optional[Tuple[float, ...]]]]) -> None:
    # The scenes of a batch share one gravity (the BatchSimulator refuses others): checked here
    # for the scenes whose gravity is known before they are sent (not a factory's).
    known = [(index, description, key, g) for index, description, key, g in members if g is not None]
    for index, description, key, gravity in known[1:]:
        first, first_gravity = known[0][0], known[0][3]
        if gravity != first_gravity:
            raise InvalidInputError(
                f"sweep: the batch of scenes {[m[0] for m in members]}: scene {index}: {_label(description, key)}: "
                f"gravity {list(gravity)} differs from scene {first}'s {list(first_gravity)}; the scenes of a batch "
                "share one gravity (sweep them separately, or give them different options)")


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


# --- where the batches run --------------------------------------------------------------------

class _Here:
    """No executor: each batch runs in this process when the caller asks for the next result."""

    def run(self, batches: List[_Batch], errors: str) -> Iterator[Tuple[_Batch, Any]]:
        for b in batches:
            yield b, lambda b=b: _run(b, errors)


class _Futures:
    """A ``concurrent.futures.Executor`` (a process or thread pool) or a ``dask.distributed.Client``:
    both submit a function and hand back futures with ``result()`` and ``cancel()``."""

    def __init__(self, executor: Any, dask: bool) -> None:
        self.executor, self.dask = executor, dask

    def run(self, batches: List[_Batch], errors: str) -> Iterator[Tuple[_Batch, Any]]:
        if self.dask:
            from distributed import as_completed
            # pure=False: two identical batches are still two tasks (Dask would otherwise merge
            # them by their hash, which is right but surprising when timing a sweep).
            futures = {self.executor.submit(_run, b, errors, pure=False,
                                            key=f"stabint-sweep-batch-{b.number}-{os.urandom(4).hex()}"): b
                       for b in batches}
        else:
            from concurrent.futures import as_completed  # type: ignore[assignment]
            futures = {self.executor.submit(_run, b, errors): b for b in batches}
        try:
            for future in as_completed(list(futures)):
                yield futures[future], future.result
        finally:  # a failure raised to the caller, or the caller stopped iterating
            for future in futures:
                future.cancel()


class _Ray:
    """Ray (the ``ray`` module, after ``ray.init()``): one remote task per batch."""

    def __init__(self, ray: Any) -> None:
        self.ray = ray

    def run(self, batches: List[_Batch], errors: str) -> Iterator[Tuple[_Batch, Any]]:
        ray = self.ray
        task = ray.remote(_run)
        refs = {task.remote(b, errors): b for b in batches}
        pending = list(refs)
        try:
            while pending:
                (ready,), pending = ray.wait(pending, num_returns=1)
                yield refs[ready], lambda ready=ready: ray.get(ready)
        finally:
            for ref in pending:
                ray.cancel(ref)


def _executor(executor: Any, client: Any) -> Any:
    if client is not None:
        if executor is not None:
            raise InvalidInputError("sweep: give executor or client (its former name), not both")
        executor = client
    if executor is None:
        executor = _default_client()
        if executor is None:
            return _Here()
    if isinstance(executor, types.ModuleType) and executor.__name__ == "ray":
        if not executor.is_initialized():
            raise InvalidInputError("sweep: executor is the ray module but Ray is not initialised: call ray.init() first")
        return _Ray(executor)
    if isinstance(executor, concurrent.futures.Executor):
        return _Futures(executor, dask=False)
    if type(executor).__module__.split(".")[0] == "distributed" and hasattr(executor, "submit"):
        return _Futures(executor, dask=True)
    raise InvalidInputError(
        "sweep: executor must be a dask.distributed.Client, the ray module (after ray.init()), a "
        f"concurrent.futures.Executor (a process or thread pool) or None, got {type(executor).__name__}")


def sweep_iter(scenes: Sequence[Any], options: Union[SimulatorOptions, Mapping[str, Any], None] = None,
               frames: int = 100, *, batch_size: int = 64, stride: int = 1, velocities: bool = True,
               executor: Any = None, errors: str = "report", client: Any = None) -> Iterator[List[SceneResult]]:
    """The same sweep as :func:`sweep`, given back one batch at a time as each batch finishes
    (completion order, not input order): each item is that batch's list of SceneResults, whose
    ``index`` says which input each one is. Every check runs, and every batch is submitted,
    before the first item comes back; stopping early cancels the batches not yet finished."""
    _check_counts(frames, batch_size, stride)
    _check_errors(errors)
    batches = _batches(scenes, options, frames, batch_size, stride, velocities)
    runner = _executor(executor, client)
    for batch, result in runner.run(batches, errors):
        try:
            batch_results = result()
        except Exception as e:  # _run reports its own failures; this is a task lost by the executor
            if errors == "raise":
                raise
            batch_results = _BatchRun(batch).failed(e)
        yield batch_results


def sweep(scenes: Sequence[Any], options: Union[SimulatorOptions, Mapping[str, Any], None] = None,
          frames: int = 100, *, batch_size: int = 64, stride: int = 1, velocities: bool = True,
          executor: Any = None, errors: str = "report", on_batch: Optional[Callable[[List[SceneResult]], Any]] = None,
          client: Any = None) -> List[SceneResult]:
    """Steps every scene for ``frames`` steps and returns one SceneResult per input, in order.

    ``scenes``: stabint.Scene, BuiltinScene, functions returning a Scene (pickled to the worker
    and called there), or :class:`Cell` (a scene with its own option overrides and key, e.g. from
    :func:`grid`). ``options``: the SimulatorOptions shared by all cells (or a dict of fields).
    Cells with equal options are batched together, ``batch_size`` at most per BatchSimulator;
    ``stride``: record positions (and velocities) every ``stride``-th frame (reports: every
    frame).

    ``executor``: where the batches run, one task per batch: a ``dask.distributed.Client``, the
    ``ray`` module after ``ray.init()``, or a ``concurrent.futures`` process or thread pool. None
    uses Dask's default client when one exists, else runs the batches one after another in this
    process. A batch gives the same numbers, bit for bit, wherever it runs. ``client`` is the
    former name of ``executor``.

    ``on_batch``: called here with each batch's list of SceneResults as that batch finishes (in
    completion order), e.g. to advance a progress bar by ``len(results)``; :func:`sweep_iter`
    gives the same as an iterator.

    Bad input raises InvalidInputError naming the scene or batch before any task is sent: an
    empty list, an object that is not a scene description, an unknown option field, a scene that
    does not validate, an option value the library refuses, scenes of one batch with different
    gravity, an executor of none of the kinds above, and a BuiltinScene's unknown builder or
    parameter name, NaN or infinite value or value its builder refuses
    (:class:`SceneParameterError`, also a FileFormatError).

    ``errors``: what a batch that fails where it runs does (a factory raising or returning no
    Scene, the BatchSimulator refusing the batch, a step raising, a task the executor lost).
    ``"report"`` (the default): its scenes' results carry ``error`` (and ``refusal``), a message
    naming the scene (index and description) and the cause, with whatever was computed before
    the failure; every other batch's results are returned as usual. ``"raise"``: the first
    failure raises in the caller with its class (a factory's foreign exception as
    InvalidInputError), naming the scene or the batch; the batches not yet finished are cancelled.
    A step a scene's energy check refuses is never a failure of the batch: it is that scene's
    ``refusal``."""
    if on_batch is not None and not callable(on_batch):
        raise InvalidInputError(f"sweep: on_batch must be callable, got {type(on_batch).__name__}")
    results: List[Optional[SceneResult]] = [None] * (len(scenes) if isinstance(scenes, Sequence) else 0)
    for batch_results in sweep_iter(scenes, options, frames, batch_size=batch_size, stride=stride,
                                    velocities=velocities, executor=executor, errors=errors, client=client):
        for r in batch_results:
            results[r.index] = r
        if on_batch is not None:
            on_batch(batch_results)
    return results  # type: ignore[return-value]
