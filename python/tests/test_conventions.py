"""The package's Python conventions (docs/guide.md, "Python conventions"): reprs, pickling and
== of the options, enums by name, keyword errors that name the closest field, a clean namespace,
the `stabint-run` console command, the default backend, and which accessors are properties."""

import copy
import pathlib
import pickle
import re
import subprocess
import sys

import numpy as np
import pytest

import stabint
from stabint import BackendKind, Integrator

ROOT = pathlib.Path(__file__).resolve().parents[2]


def option_fields():
    """The fields of SimulatorOptions as their table (include/stabint/options_table.h) names them."""
    header = (ROOT / "include" / "stabint" / "options_table.h").read_text()
    body = header[header.index("#define STABINT_SIMULATOR_OPTIONS_TABLE"):
                  header.index("#define STABINT_OPENCL_OPTIONS_TABLE")]
    return re.findall(r"^\s*(?:FIELD|NESTED)\(T\(\w+\), (\w+),", body, re.M)


# Every field away from its default (the names as the CLI takes them where a field is an enum).
NON_DEFAULT = dict(
    integrator="BE", time_step=0.01, iterations=3, tolerance=1e-9, max_iterations=50, acceleration="anderson",
    chebyshev_rho=0.9, anderson_window=3, lbfgs_history=3, lbfgs_rigid_modes=0, gradient_tolerance=1e-3,
    global_solve="cg", cg_iterations=7, cg_tolerance=1e-6, be_iterations=2, energy_tolerance=1e-2,
    max_velocity_scale=1.5, max_root_evaluations=8, energy_limit=10.0, contact_tolerance=0.05, contact_release=1,
    self_contact_thickness=0.003,
    self_contact_friction=0.4, self_contact_supports=2,
    backend="opencl",
    opencl=stabint.OpenCLOptions(platform="0", device="gpu", precision="float"))


def non_default_options():
    assert set(NON_DEFAULT) == set(option_fields())
    return stabint.SimulatorOptions(**NON_DEFAULT)


# --- repr -----------------------------------------------------------------------------------------
def test_options_repr_names_every_field_and_evaluates_to_equal_options():
    options = non_default_options()
    text = repr(options)
    assert text.startswith("SimulatorOptions(integrator=Integrator.BackwardEuler, time_step=0.01, iterations=3, ")
    assert "acceleration=Acceleration.Anderson" in text and "backend=BackendKind.OpenCL" in text
    assert text.endswith(", opencl=OpenCLOptions(platform='0', device='gpu', precision=Precision.Float))")
    for name in option_fields():
        assert f" {name}=" in text or text.startswith(f"SimulatorOptions({name}="), name
    # The repr is the expression that makes the options again.
    assert eval(text, vars(stabint)) == options
    assert eval(repr(stabint.SimulatorOptions()), vars(stabint)) == stabint.SimulatorOptions()


def test_opencl_options_take_keywords_and_have_a_repr():
    opencl = stabint.OpenCLOptions(platform="NVIDIA", device="1", precision=stabint.Precision.Float)
    assert (opencl.platform, opencl.device, opencl.precision) == ("NVIDIA", "1", stabint.Precision.Float)
    assert repr(opencl) == "OpenCLOptions(platform='NVIDIA', device='1', precision=Precision.Float)"
    assert repr(stabint.OpenCLOptions()) == "OpenCLOptions(platform='', device='', precision=Precision.Double)"
    assert stabint.OpenCLOptions(device="2") == stabint.OpenCLOptions(platform="", device="2")
    with pytest.raises(TypeError, match=r"^OpenCLOptions\(\) got an unexpected keyword argument 'devices'; "
                                        r"did you mean 'device'\?$"):
        stabint.OpenCLOptions(devices="1")


def test_scene_repr_summarizes_the_scene():
    scene = stabint.scene_from_arrays([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 1.0, springs=[[0, 1], [1, 2]],
                                      spring_stiffness=10.0, pinned=[0], name="rope")
    assert repr(scene) == "<Scene 'rope': 3 particles, 2 springs, 1 pin>"
    scene.colliders.append(stabint.Collider(shape="sphere", center=np.array([0.0, -1.0, 0.0]), radius=0.5))
    scene.colliders.append(stabint.Collider())
    # The element counts are the library's summary, the CLI's first line: a contact per particle
    # and collider (the elements the solver carries), pins last.
    assert repr(scene) == "<Scene 'rope': 3 particles, 2 springs, 6 contacts, 1 pin; 2 colliders>"
    cloth = stabint.cloth_grid(nx=4, ny=3, pinned=[0, 3])
    counts = f"{len(cloth.springs)} springs, 2 pins; 1 body, {len(cloth.triangles)} surface triangles"
    assert repr(cloth) == f"<Scene 'cloth': 12 particles, {counts}>"
    assert repr(stabint.Scene()) == "<Scene '': 0 particles, no elements>"


def test_collider_repr_shows_its_shape_and_what_differs_from_the_defaults():
    sphere = stabint.Collider(shape=stabint.ColliderShape.Sphere, center=np.array([0.0, 0.5, 0.0]), radius=0.2,
                              friction=0.3)
    assert repr(sphere) == ("Collider(shape=ColliderShape.Sphere, center=[0.0, 0.5, 0.0], radius=0.2, "
                            "friction=0.3)")
    assert repr(stabint.Collider()) == "Collider(shape=ColliderShape.Plane, center=[0.0, 0.0, 0.0], normal=[0.0, 1.0, 0.0])"
    capsule = stabint.Collider(shape="capsule", end=np.array([1.0, 0.0, 0.0]), radius=0.1, num_particles=4)
    assert repr(capsule) == ("Collider(shape=ColliderShape.Capsule, center=[0.0, 0.0, 0.0], end=[1.0, 0.0, 0.0], "
                             "radius=0.1, num_particles=4)")
    # A field the shape ignores shows once it is set: the repr hides nothing that was changed.
    sphere.half_extents = np.array([1.0, 1.0, 1.0])
    assert "half_extents=[1.0, 1.0, 1.0]" in repr(sphere)
    box = stabint.Collider(shape="box", half_extents=np.array([0.5, 0.25, 0.5]))
    assert repr(box) == ("Collider(shape=ColliderShape.Box, center=[0.0, 0.0, 0.0], "
                         "half_extents=[0.5, 0.25, 0.5])")


# --- pickling and == ------------------------------------------------------------------------------
def test_options_pickle_round_trip_field_by_field():
    options = non_default_options()
    for again in (pickle.loads(pickle.dumps(options)), copy.deepcopy(options), copy.copy(options)):
        assert type(again) is stabint.SimulatorOptions
        for name in option_fields():
            if name == "opencl":
                for sub in ("platform", "device", "precision"):
                    assert getattr(again.opencl, sub) == getattr(options.opencl, sub), sub
            else:
                value = getattr(again, name)
                assert type(value) is type(getattr(options, name)) and value == getattr(options, name), name
        assert again == options
    # A copy is its own object: changing it leaves the original alone.
    again = pickle.loads(pickle.dumps(options))
    again.opencl.device = "other"
    assert options.opencl.device == "gpu" and again != options
    opencl = stabint.OpenCLOptions(platform="1", precision="float")
    assert pickle.loads(pickle.dumps(opencl)) == opencl
    # The state is plain data, enums by the library's names, so a pickle outlives a renumbering.
    state = options.__getstate__()
    assert state["integrator"] == "BE" and state["backend"] == "opencl" and state["acceleration"] == "anderson"


def test_options_compare_by_value_and_are_not_hashable():
    assert stabint.SimulatorOptions() == stabint.SimulatorOptions()
    assert stabint.SimulatorOptions(iterations=4) != stabint.SimulatorOptions()
    assert stabint.SimulatorOptions(opencl=stabint.OpenCLOptions(device="1")) != stabint.SimulatorOptions()
    assert stabint.SimulatorOptions() != "SimulatorOptions()"
    with pytest.raises(TypeError):
        hash(stabint.SimulatorOptions())


# --- enums by name --------------------------------------------------------------------------------
def test_enums_are_accepted_by_the_names_the_cli_and_scene_files_use():
    options = stabint.SimulatorOptions(integrator="BE", backend="auto", acceleration="none", global_solve="cg")
    assert options.integrator == Integrator.BackwardEuler and options.backend == BackendKind.Auto
    assert options.acceleration == stabint.Acceleration.None_
    assert options.global_solve == stabint.GlobalSolve.ConjugateGradient
    options.integrator = "blend"
    assert options.integrator == Integrator.EnergyBlend
    options.integrator = "im"  # any case, as the CLI
    assert options.integrator == Integrator.ImplicitMidpoint
    options.opencl.precision = "float"
    assert options.opencl.precision == stabint.Precision.Float
    # Every value of every option's enum by the name the library prints (and the CLI takes).
    for enum_type, name_of in ((Integrator, stabint.integrator_name), (BackendKind, stabint.backend_name),
                               (stabint.Acceleration, stabint.acceleration_name)):
        field = {Integrator: "integrator", BackendKind: "backend", stabint.Acceleration: "acceleration"}[enum_type]
        for value in enum_type:
            assert getattr(stabint.SimulatorOptions(**{field: name_of(value)}), field) == value
            # ... and by the enumerator's name, as stabint.distributed's option dicts hold them.
            assert getattr(stabint.SimulatorOptions(**{field: value.name}), field) == value
    # Wherever an enum is an argument: a scene part's field, a method's argument.
    assert stabint.Collider(shape="box").shape == stabint.ColliderShape.Box
    assert stabint.ClothMaterial(model="triangles").model == stabint.ClothModel.Triangles
    sim = stabint.Simulator(stabint.chain_pendulum(particles=4), stabint.SimulatorOptions(integrator="BE"))
    sim.set_element_enabled("springs", 0, False)
    assert not sim.element_enabled("Spring", 0) and sim.element_enabled(stabint.ElementKind.Spring, 1)
    assert sim.options.integrator == Integrator.BackwardEuler


def test_an_unknown_enum_name_is_an_invalid_input_error_listing_the_names():
    expected = r"^unknown integrator 'RK4' \(expected FE, SE, BE, BDF2, IM or blend\)$"
    with pytest.raises(stabint.InvalidInputError, match=expected):
        stabint.SimulatorOptions(integrator="RK4")
    options = stabint.SimulatorOptions()
    with pytest.raises(stabint.InvalidInputError, match=expected):
        options.integrator = "RK4"
    assert options.integrator == Integrator.EnergyBlend  # unchanged
    with pytest.raises(stabint.InvalidInputError, match=r"unknown backend 'gpu' \(expected cpu, opencl or auto\)"):
        stabint.SimulatorOptions(backend="gpu")
    with pytest.raises(stabint.InvalidInputError, match="unknown collider shape 'cube'"):
        stabint.Collider(shape="cube")
    # Not a name and not the enum: a TypeError, as for any other wrongly typed value.
    with pytest.raises(TypeError, match=r"^SimulatorOptions.integrator takes Integrator \| str, not float$"):
        stabint.SimulatorOptions(integrator=2.5)
    with pytest.raises(TypeError):
        options.integrator = 2.5


# --- keyword errors -------------------------------------------------------------------------------
def test_an_unknown_keyword_is_one_line_naming_the_closest_field():
    with pytest.raises(TypeError) as error:
        stabint.SimulatorOptions(integrater="BE")
    assert str(error.value) == ("SimulatorOptions() got an unexpected keyword argument 'integrater'; "
                                "did you mean 'integrator'?")
    with pytest.raises(TypeError, match=r"^SimulatorOptions\(\) got an unexpected keyword argument 'dt'; "
                                        r"its fields are integrator, time_step, iterations, .*, backend, opencl$"):
        stabint.SimulatorOptions(dt=0.01)
    with pytest.raises(TypeError, match=r"^SimulatorOptions\(\) takes keyword arguments only$"):
        stabint.SimulatorOptions(Integrator.BackwardEuler)
    with pytest.raises(TypeError, match=r"^SimulatorOptions.time_step takes float, not str$"):
        stabint.SimulatorOptions(time_step="fast")
    with pytest.raises(TypeError, match=r"^SimulatorOptions.opencl takes OpenCLOptions, not dict$"):
        stabint.SimulatorOptions(opencl={"device": "1"})


def test_help_shows_every_option_with_its_type_and_default():
    doc = stabint.SimulatorOptions.__init__.__doc__
    signature = doc.splitlines()[0]
    assert signature.startswith("__init__(self, *, integrator: Integrator | str = Integrator.EnergyBlend, "
                                "time_step: float = 0.03333333333333333, iterations: int = 10, ")
    assert signature.endswith(", backend: BackendKind | str = BackendKind.CpuReference, opencl: OpenCLOptions = "
                              "OpenCLOptions(platform='', device='', precision=Precision.Double)) -> None")
    for name in option_fields():
        assert f"{name}: " in signature, name
    stub = (pathlib.Path(stabint.__file__).parent / "_stabint.pyi").read_text()
    assert "def __init__(self, *, integrator: Integrator | str = Integrator.EnergyBlend," in stub


# --- the namespace --------------------------------------------------------------------------------
def test_dir_shows_the_library_alone():
    names = set(dir(stabint))
    assert not names & {"np", "json", "typing", "Any", "Dict", "Optional", "annotations"}
    assert set(stabint.__all__) <= names
    public = {n for n in names if not n.startswith("_") and n not in ("distributed", "io")}
    assert public == set(stabint.__all__)
    assert {"Simulator", "SimulatorOptions", "cloth_grid", "scene_from_arrays", "InvalidInputError"} <= public
    namespace = {}
    exec("from stabint import *", namespace)
    assert "np" not in namespace and "Simulator" in namespace and "distributed" not in namespace


# --- the default backend --------------------------------------------------------------------------
def test_the_default_backend_is_the_libraries_and_the_cli_picks_auto():
    # Python's defaults are the C++ struct's: the CPU reference (deterministic on every machine);
    # the options table is where C++ takes it from.
    header = (ROOT / "include" / "stabint" / "options_table.h").read_text()
    assert re.search(r"FIELD\(T\(BackendKind\), backend, BackendKind::CpuReference,", header)
    assert stabint.SimulatorOptions().backend == BackendKind.CpuReference
    assert stabint.Simulator(stabint.linear_oscillator()).options.backend == BackendKind.CpuReference
    # The command-line tool starts from auto (a GPU when one pays off), as its help says.
    out = subprocess.run([str(stabint_run()), "--help"], capture_output=True, text=True, check=True).stdout
    assert re.search(r"--backend cpu\|opencl\|auto\s+where the element work runs: cpu, opencl or auto\s+"
                     r"\(default auto\)", out)


# --- the console command --------------------------------------------------------------------------
def stabint_run():
    """The `stabint-run` command pip installed next to this interpreter."""
    command = pathlib.Path(sys.executable).parent / "stabint-run"
    assert command.exists(), command
    return command


def test_pip_installs_the_stabint_run_command():
    version = subprocess.run([str(stabint_run()), "--version"], capture_output=True, text=True)
    assert version.returncode == 0 and version.stdout == f"stabint-run {stabint.__version__}\n"
    short = subprocess.run([str(stabint_run()), "-h"], capture_output=True, text=True)
    assert short.returncode == 0 and short.stdout.startswith("Usage: stabint-run --scene NAME|FILE")
    run = subprocess.run([str(stabint_run()), "--scene", "oscillator", "--integrator", "IM", "--frames", "3",
                          "--csv", "-"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    rows = run.stdout.splitlines()
    assert rows[0].startswith("frame,time,kinetic,") and [r.split(",")[0] for r in rows[1:]] == ["0", "1", "2", "3"]
    assert "stabint-run: scene 'oscillator'" in run.stderr and "3 frames in" in run.stderr
    bad = subprocess.run([str(stabint_run()), "--scene", "oscillator", "--integrator", "RK4"], capture_output=True,
                         text=True)
    assert bad.returncode == 1
    assert bad.stderr == ("stabint-run: error: --integrator: unknown integrator 'RK4' "
                          "(expected FE, SE, BE, BDF2, IM or blend)\n")


def test_the_command_loads_mesh_files(tmp_path):
    # The same tool as the C++ one: a mesh file is a scene (docs/guide.md, "Command line").
    run = subprocess.run([str(stabint_run()), "--scene", str(ROOT / "scenes" / "bar.mesh"), "--frames", "2",
                          "--quiet", "--csv", str(tmp_path / "bar.csv")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert len((tmp_path / "bar.csv").read_text().splitlines()) == 4


# --- properties and methods -----------------------------------------------------------------------
def test_state_is_a_property_without_an_argument_and_a_method_with_one():
    # The rule (docs/guide.md, "Python conventions"): what needs no argument is a property
    # (Simulator.positions, BatchSimulator.all_positions, .time, .size), what takes one is a method
    # (BatchSimulator.positions(scene), .scene_time(scene)); a method without arguments does work.
    does_work = {"step", "checkpoint", "energy", "clear_reporters"}
    for cls in (stabint.Simulator, stabint.BatchSimulator):
        for name, attribute in vars(cls).items():
            if name.startswith("_") or isinstance(attribute, property):
                continue
            signatures = [s[0] for s in attribute.__nb_signature__]
            if any(re.match(rf"def {name}\(self\)", s) for s in signatures):
                assert name in does_work, f"{cls.__name__}.{name} takes no argument: a property"
    assert isinstance(vars(stabint.BatchSimulator)["all_positions"], property)
    assert isinstance(vars(stabint.Simulator)["positions"], property)
    batch = stabint.BatchSimulator([stabint.chain_pendulum(particles=4), stabint.chain_pendulum(particles=3)])
    np.testing.assert_array_equal(batch.all_positions[batch.first_particle(1):], batch.positions(1))
