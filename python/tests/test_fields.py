"""The classes generated from the field tables of the public structs (stabint/field_list.hpp,
python/src/fields.hpp): every field is a property and a constructor keyword, defaults are the
C++ struct's, and __repr__ names every field (a Collider's: those of its shape and the ones set).

The expected fields and defaults are written out here from the C++ structs (include/stabint/
scene.hpp, types.hpp), not read from the binding, so that a field missing from a table, a
misassigned keyword or a default that differs from the struct's fails here; the C++ side checks
the tables against the structs (tests/test_field_tables.cpp)."""

import enum
import re

import numpy as np
import pytest

import stabint
from stabint import ColliderShape

ZERO = [0.0, 0.0, 0.0]


class Nested:
    """The expected fields of a nested struct (Pin.target, ScriptedEvent.action, ...)."""

    def __init__(self, cls, **fields):
        self.cls, self.fields = cls, fields


TARGET = Nested(stabint.PinTarget, position=ZERO, velocity=ZERO, amplitude=ZERO, frequency=0.0)
GRAB = Nested(stabint.GrabEvent, id="", vertex=0, stiffness=0.0, path=[])

# Each constructible class with a table: its fields and the C++ default of each, in the struct's
# order.
DEFAULTS = {
    stabint.Spring: dict(a=0, b=0, rest_length=0.0, stiffness=0.0),
    stabint.Tet: dict(vertices=[0, 0, 0, 0], stiffness=0.0),
    stabint.TriangleStrain: dict(vertices=[0, 0, 0], stiffness=0.0, strain_min=1.0, strain_max=1.0),
    stabint.BendingHinge: dict(vertices=[0, 0, 0, 0], stiffness=0.0),
    stabint.PinTarget: TARGET.fields,
    stabint.Pin: dict(vertex=0, stiffness=0.0, target=TARGET),
    stabint.ForceField: dict(particles=[], force=ZERO, rate=ZERO, amplitude=ZERO, frequency=0.0),
    stabint.Body: dict(name="", particles=[], damping=0.0),
    stabint.Collider: dict(shape=ColliderShape.Plane, center=ZERO, normal=[0.0, 1.0, 0.0], half_extents=ZERO,
                           end=ZERO, radius=0.0, mesh_vertices=np.zeros((0, 3)),
                           mesh_triangles=np.zeros((0, 3), dtype=np.int64), velocity=ZERO, friction=0.0,
                           stiffness=1e4, elastic_ratio=1.0, restitution=1.0, first_particle=0, num_particles=-1),
    stabint.PathKey: dict(frame=0, position=ZERO),
    stabint.GrabEvent: GRAB.fields,
    stabint.ReleaseEvent: dict(id="", vertex=-1),
    stabint.ImpulseEvent: dict(vertices=[], velocity=ZERO),
    stabint.ElementEvent: dict(kind=stabint.ElementKind.Spring, indices=[], stiffness=None, enabled=None),
    stabint.ColliderEvent: dict(collider=0, path=[], velocity=None),
    stabint.ScriptedEvent: dict(frame=0, action=GRAB),
    stabint.ClothMaterial: dict(areal_density=0.1, stretch_stiffness=1e3, bend_stiffness=1e1,
                                model=stabint.ClothModel.Springs, strain_stiffness=1e3, strain_min=1.0,
                                strain_max=1.0, hinge_stiffness=1e-3),
    stabint.SolidMaterial: dict(density=1000.0, stiffness=1e5),
}

# Values that changed() cannot make from the default: optional fields (None) and lists of structs.
CHANGED = {
    (stabint.ElementEvent, "stiffness"): 2.5,
    (stabint.ElementEvent, "enabled"): False,
    (stabint.ColliderEvent, "velocity"): [0.5, 0.0, -1.0],
    (stabint.Collider, "mesh_vertices"): [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
    (stabint.Collider, "mesh_triangles"): [[0, 1, 2]],
    (stabint.ColliderEvent, "path"): [Nested(stabint.PathKey, frame=4, position=[1.0, 2.0, 3.0])],
    (stabint.GrabEvent, "path"): [Nested(stabint.PathKey, frame=2, position=[0.0, 1.0, 0.0]),
                                  Nested(stabint.PathKey, frame=7, position=[0.0, 2.0, 0.0])],
    (stabint.ScriptedEvent, "action"): Nested(stabint.ImpulseEvent, vertices=[1, 2], velocity=[0.0, 0.0, 1.0]),
}

# The constructors of before the tables keep their positional, required arguments; a Pin's target
# is a required keyword (the third positional argument is Pin(vertex, stiffness, position)'s).
REQUIRED = {
    stabint.Spring: ["a", "b", "rest_length", "stiffness"],
    stabint.Tet: ["vertices", "stiffness"],
    stabint.TriangleStrain: ["vertices", "stiffness"],
    stabint.BendingHinge: ["vertices", "stiffness"],
    stabint.Pin: ["vertex", "stiffness", "target"],
    stabint.PathKey: ["frame", "position"],
    stabint.ScriptedEvent: ["frame", "action"],
}

# The read-only reports: their fields, and the computed `total`.
REPORT_FIELDS = {
    stabint.EnergyReport: ["kinetic", "elastic", "external", "total"],
    stabint.PhaseTimes: ["local", "gather", "transfer", "global_", "energy", "bookkeeping", "total"],
    stabint.StepReport: ["step", "time", "energy", "target", "forcing", "damping", "branch", "alpha",
                         "velocity_scale", "event_energy", "friction", "contact_projection", "iterations",
                         "energy_evaluations", "times"],
    stabint.OpenCLDeviceInfo: ["platform_index", "device_index", "platform_name", "device_name", "vendor",
                               "fp64", "gpu"],
}

SCENE_FIELDS = ["name", "rest_positions", "positions", "velocities", "masses", "springs", "tets",
                "triangle_strains", "bending_hinges", "pins", "gravity", "force_fields", "bodies", "colliders",
                "triangles", "num_particles"]


def properties(cls):
    return {name for name, value in vars(cls).items() if isinstance(value, property)}


def python_value(value):
    # An expected value as the binding takes it: a nested struct as the struct, a vector of floats
    # or a matrix as a numpy array (as the properties take them).
    if isinstance(value, Nested):
        obj = value.cls()
        for name, v in value.fields.items():
            setattr(obj, name, python_value(v))
        return obj
    if isinstance(value, list) and value and isinstance(value[0], float):
        return np.array(value)
    if isinstance(value, list) and value and isinstance(value[0], list):
        return np.array(value)
    if isinstance(value, list):
        return [python_value(v) for v in value]
    return value


def same(actual, expected):
    if isinstance(expected, Nested):
        return type(actual) is expected.cls and all(same(getattr(actual, name), value)
                                                   for name, value in expected.fields.items())
    if expected is None or isinstance(expected, (str, bool, enum.Enum)):
        return type(actual) is type(expected) and actual == expected
    if isinstance(expected, list) and expected and isinstance(expected[0], Nested):
        return len(actual) == len(expected) and all(same(a, e) for a, e in zip(actual, expected))
    actual, expected = np.asarray(actual), np.asarray(expected)
    return actual.shape == expected.shape and bool(np.all(actual == expected))


def changed(cls, name, value):
    # A valid value other than `value`, of the same kind.
    if (cls, name) in CHANGED:
        return CHANGED[cls, name]
    if isinstance(value, Nested):
        first = next(iter(value.fields))
        return Nested(value.cls, **dict(value.fields, **{first: changed(value.cls, first, value.fields[first])}))
    if isinstance(value, enum.Enum):
        return next(v for v in type(value) if v != value)
    if isinstance(value, str):
        return "changed"
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 3
    if isinstance(value, float):
        return 0.5 * value + 0.25
    if len(value) == 0:
        return [2, 5]
    if isinstance(value[0], int):
        return list(range(1, len(value) + 1))
    return [1.5, -2.0, 3.25]


@pytest.mark.parametrize("cls", list(DEFAULTS), ids=lambda cls: cls.__name__)
def test_every_field_is_a_property_with_the_cpp_default(cls):
    fields = DEFAULTS[cls]
    assert properties(cls) == set(fields)
    default = cls()
    for name, value in fields.items():
        assert same(getattr(default, name), value), name
    text = repr(default)
    assert text.startswith(cls.__name__ + "(")
    # A collider's repr shows its shape's fields, the others where they differ from the defaults
    # (test_conventions.py); every other class's names every field.
    for name in (["shape", "center", "normal"] if cls is stabint.Collider else fields):
        assert f"{name}=" in text, name


@pytest.mark.parametrize("cls", list(DEFAULTS), ids=lambda cls: cls.__name__)
def test_every_field_round_trips_through_its_keyword_and_its_property(cls):
    fields = DEFAULTS[cls]
    required = {name: python_value(fields[name]) for name in REQUIRED.get(cls, [])}
    for name, value in fields.items():
        new = changed(cls, name, value)
        assert not same(new, value), name
        by_keyword = cls(**dict(required, **{name: python_value(new)}))
        assert same(getattr(by_keyword, name), new), name
        for other, default in fields.items():
            if other != name:  # the others keep their defaults
                assert same(getattr(by_keyword, other), default), (name, other)
        by_property = cls()
        setattr(by_property, name, python_value(new))
        assert same(getattr(by_property, name), new), name
        assert f"{name}=" in repr(by_property)
    with pytest.raises(TypeError):
        cls(**dict(required, no_such_field=1))


def test_the_old_element_constructors_keep_their_arguments():
    s = stabint.Spring(1, 2, 0.5, 10.0)
    assert (s.a, s.b, s.rest_length, s.stiffness) == (1, 2, 0.5, 10.0)
    t = stabint.TriangleStrain([0, 1, 2], 5.0, 0.9, 1.1)
    assert (list(t.vertices), t.stiffness, t.strain_min, t.strain_max) == ([0, 1, 2], 5.0, 0.9, 1.1)
    assert list(stabint.Tet([0, 1, 2, 3], 7.0).vertices) == [0, 1, 2, 3]
    assert stabint.BendingHinge([0, 1, 2, 3], 2.0).stiffness == 2.0
    pin = stabint.Pin(4, 100.0, np.array([1.0, 2.0, 3.0]))
    assert pin.vertex == 4 and list(pin.target.position) == [1.0, 2.0, 3.0]
    assert list(stabint.PathKey(3, [1.0, 2.0, 3.0]).position) == [1.0, 2.0, 3.0]
    assert stabint.PathKey(3, np.array([1.0, 2.0, 3.0])).frame == 3
    assert isinstance(stabint.ScriptedEvent(2, stabint.ReleaseEvent()).action, stabint.ReleaseEvent)
    for call in (lambda: stabint.ScriptedEvent(2), lambda: stabint.Spring(1, 2), lambda: stabint.Tet([0, 1, 2, 3]), lambda: stabint.Pin(4, 100.0),
                 lambda: stabint.Collider(ColliderShape.Sphere)):  # missing, or keyword-only
        with pytest.raises(TypeError):
            call()


@pytest.mark.parametrize("cls", list(REPORT_FIELDS), ids=lambda cls: cls.__name__)
def test_reports_have_every_field_read_only(cls):
    assert properties(cls) == set(REPORT_FIELDS[cls])
    for name in REPORT_FIELDS[cls]:
        assert vars(cls)[name].fset is None, name
    with pytest.raises(TypeError):
        cls()


def test_report_repr_names_every_field():
    sim = stabint.Simulator(stabint.linear_oscillator(), stabint.SimulatorOptions())
    report = sim.step()
    text = repr(report)
    for name in REPORT_FIELDS[stabint.StepReport]:
        assert f"{name}=" in text, name
    assert "kinetic=" in text and "global_=" in text  # nested reports too


def test_scene_has_every_field():
    assert properties(stabint.Scene) == set(SCENE_FIELDS)
    for kind in stabint.ElementKind:  # every element type users reach is a Scene list and a class
        plural = re.sub(r"(?<!^)([A-Z])", r"_\1", kind.name).lower() + "s"  # TriangleStrain: triangle_strains
        assert isinstance(getattr(stabint.Scene(), plural), getattr(stabint, kind.name + "List")), kind
        assert isinstance(getattr(stabint, kind.name), type), kind
        assert isinstance(getattr(stabint, kind.name + "List"), type), kind
