// The Python extension stabint._stabint (nanobind). The pure-Python package python/stabint
// re-exports it and adds scene_from_arrays and the builder shortcuts.
//
// Copies and views: every numpy array this module returns (positions, velocities, masses,
// triangles, gravity) is a fresh copy that the caller owns: a view into a Simulator's state
// would change under the caller at the next step(), and one into a Scene would dangle when the
// scene is reassigned. Element lists (scene.springs, scene.pins, ...) are the opposite: opaque
// list-like views into the scene, so scene.springs.append(...) edits the scene.
#include <stabint/options_fields.hpp>
#include <stabint/stabint.hpp>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/bind_vector.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/variant.h>
#include <nanobind/stl/vector.h>

#include <cstdint>
#include <cstring>

namespace nb = nanobind;
using namespace nb::literals;
using namespace stabint;

NB_MAKE_OPAQUE(std::vector<Spring>)
NB_MAKE_OPAQUE(std::vector<Tet>)
NB_MAKE_OPAQUE(std::vector<TriangleStrain>)
NB_MAKE_OPAQUE(std::vector<BendingHinge>)
NB_MAKE_OPAQUE(std::vector<Pin>)
NB_MAKE_OPAQUE(std::vector<ForceField>)
NB_MAKE_OPAQUE(std::vector<Body>)
NB_MAKE_OPAQUE(std::vector<Collider>)

namespace {

using Rows3d = nb::ndarray<nb::numpy, double, nb::shape<-1, 3>, nb::c_contig>;
using Rows3i = nb::ndarray<nb::numpy, int32_t, nb::shape<-1, 3>, nb::c_contig>;
using Triangles = std::vector<std::array<int, 3>>;

// An n by 3 matrix as a new C-contiguous (n, 3) array: x y z per row, interleaved.
Rows3d rowsCopy(const Eigen::MatrixX3d& m) {
  const size_t n = static_cast<size_t>(m.rows());
  double* data = new double[3 * n];
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(data, m.rows(), 3) = m;
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<double*>(p); });
  return Rows3d(data, {n, 3}, owner);
}

Rows3i trianglesCopy(const Triangles& triangles) {
  const size_t n = triangles.size();
  int32_t* data = new int32_t[3 * n];
  for (size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) data[3 * t + k] = triangles[t][k];
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<int32_t*>(p); });
  return Rows3i(data, {n, 3}, owner);
}

Triangles trianglesFrom(nb::ndarray<const int32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu> a) {
  Triangles triangles(a.shape(0));
  for (size_t t = 0; t < a.shape(0); ++t)
    for (size_t k = 0; k < 3; ++k) triangles[t][k] = a(t, k);
  return triangles;
}

// The exception classes, created once at import; owned by the module (never freed).
struct ErrorTypes {
  PyObject* error = nullptr;
  PyObject* invalid_input = nullptr;
  PyObject* file_format = nullptr;
  PyObject* non_finite_state = nullptr;
  PyObject* energy_limit = nullptr;
  PyObject* opencl = nullptr;
  PyObject* no_opencl_device = nullptr;
  PyObject* kernel_build = nullptr;
  PyObject* unsupported_precision = nullptr;
  PyObject* out_of_memory = nullptr;
} errors;

PyObject* newErrorType(nb::module_& m, const char* name, PyObject* base, const char* doc) {
  // Defined in stabint._stabint so that stubgen writes the classes into the stub; the package
  // sets __module__ to "stabint" for readable tracebacks.
  const std::string qualified = std::string("stabint._stabint.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
  if (type == nullptr) throw nb::python_error();
  m.attr(name) = nb::handle(type);
  return type;
}

// Raises `type` with message `what` and the given attributes on the exception object.
void raise(PyObject* type, const char* what,
           std::initializer_list<std::pair<const char*, nb::object>> attributes = {}) {
  nb::object exc = nb::handle(type)(nb::str(what));
  for (const auto& [name, value] : attributes) nb::setattr(exc, name, value);
  PyErr_SetObject(type, exc.ptr());
}

// Most specific class first, as in the C API: each catch precedes the catches of its bases.
void translate(const std::exception_ptr& p, void*) {
  try {
    std::rethrow_exception(p);
  } catch (const EnergyLimitError& e) {
    raise(errors.energy_limit, e.what(), {{"step", nb::int_(e.step())}});
  } catch (const NonFiniteStateError& e) {
    raise(errors.non_finite_state, e.what(), {{"step", nb::int_(e.step())}});
  } catch (const InvalidInputError& e) {
    raise(errors.invalid_input, e.what());
  } catch (const FileFormatError& e) {
    raise(errors.file_format, e.what(), {{"file", nb::str(e.file().c_str())}, {"line", nb::int_(e.line())}});
  } catch (const NoOpenCLDeviceError& e) {
    raise(errors.no_opencl_device, e.what());
  } catch (const KernelBuildError& e) {
    raise(errors.kernel_build, e.what(), {{"build_log", nb::str(e.buildLog().c_str())}});
  } catch (const UnsupportedPrecisionError& e) {
    raise(errors.unsupported_precision, e.what());
  } catch (const OpenCLError& e) {
    raise(errors.opencl, e.what());
  } catch (const OutOfMemoryError& e) {
    raise(errors.out_of_memory, e.what());
  } catch (const Error& e) {
    raise(errors.error, e.what());
  }
  // Anything else propagates to nanobind's own translators (bad_alloc -> MemoryError, ...).
}

void bindErrors(nb::module_& m) {
  errors.error =
      newErrorType(m, "Error", PyExc_RuntimeError, "Base of every error stabint raises (C++ stabint::Error).");
  errors.invalid_input = newErrorType(m, "InvalidInputError", errors.error,
                                      "A scene or an option failed validation; the message names the field.");
  errors.file_format = newErrorType(m, "FileFormatError", errors.error,
                                    "A file could not be opened or parsed. Attributes: file, line (0: none).");
  errors.non_finite_state = newErrorType(
      m, "NonFiniteStateError", errors.error,
      "A step was refused (non-finite state); the simulator keeps the last accepted state. Attribute: step.");
  errors.energy_limit = newErrorType(m, "EnergyLimitError", errors.non_finite_state,
                                     "A step would have exceeded SimulatorOptions.energy_limit. Attribute: step.");
  errors.opencl = newErrorType(m, "OpenCLError", errors.error, "Any OpenCL failure.");
  errors.no_opencl_device = newErrorType(m, "NoOpenCLDeviceError", errors.opencl,
                                         "No OpenCL device matches: fall back to BackendKind.CpuReference.");
  errors.kernel_build =
      newErrorType(m, "KernelBuildError", errors.opencl, "A kernel failed to compile. Attribute: build_log.");
  errors.unsupported_precision =
      newErrorType(m, "UnsupportedPrecisionError", errors.opencl, "Double precision on a device without cl_khr_fp64.");
  // Both a stabint.Error and Python's MemoryError, so either handler catches it.
  nb::object bases = nb::make_tuple(nb::handle(errors.error), nb::handle(PyExc_MemoryError));
  errors.out_of_memory = newErrorType(m, "OutOfMemoryError", bases.release().ptr(),
                                      "Memory ran out inside the call the message names; a simulator keeps its state.");
  nb::register_exception_translator(translate);
}

// A C++ enumerator's name as Python's: "None" is a keyword, so that value is None_.
const char* pythonName(const char* enumerator) { return std::strcmp(enumerator, "None") == 0 ? "None_" : enumerator; }

// Python's enum `cpp_enum` with the values of its list (stabint/types.hpp): the enumerators'
// names and, where the list has one, each value's doc (its third field).
#define STABINT_PY_ENUM(cpp_enum, LIST, doc)           \
  {                                                    \
    using Enum = cpp_enum;                             \
    auto py_enum = nb::enum_<Enum>(m, #cpp_enum, doc); \
    LIST(STABINT_PY_VALUE)                             \
  }
#define STABINT_PY_VALUE(enumerator, ...) \
  py_enum.value(pythonName(#enumerator), Enum::enumerator, STABINT_PY_SECOND(__VA_ARGS__, nullptr, ));
#define STABINT_PY_SECOND(first, second, ...) second

void bindEnums(nb::module_& m) {
  STABINT_PY_ENUM(Integrator, STABINT_INTEGRATORS, "The six integrators (docs/method.md sections 2 and 3).")
  STABINT_PY_ENUM(BackendKind, STABINT_BACKENDS, "Where the local step and the energies run.")
  STABINT_PY_ENUM(Precision, STABINT_PRECISIONS, "Floating-point precision of the OpenCL backend.")
  STABINT_PY_ENUM(Acceleration, STABINT_ACCELERATIONS,
                  "Acceleration of the local/global iterations (None_: 'None' is a Python keyword).")
  STABINT_PY_ENUM(GlobalSolve, STABINT_GLOBAL_SOLVES, "How the global step solves K_c x = rhs.")
  STABINT_PY_ENUM(BlendBranch, STABINT_BLEND_BRANCHES,
                  "What the blend did with the IM candidate (None_: 'None' is a Python keyword).")
  STABINT_PY_ENUM(ColliderShape, STABINT_COLLIDER_SHAPE_VALUES, "Shape of a Collider.")
  STABINT_PY_ENUM(ClothModel, STABINT_CLOTH_MODELS, "How a cloth resists deformation.")
  STABINT_PY_ENUM(ElementKind, STABINT_ELEMENT_KINDS,
                  "An element list of a Scene, for set_element_stiffness and set_element_enabled.")
#undef STABINT_PY_ENUM
#undef STABINT_PY_VALUE
#undef STABINT_PY_SECOND

  m.def("integrator_name", &integratorName, "The integrator's name: 'FE', 'blend', ...");
  m.def("parse_integrator", &parseIntegrator, "name"_a,
        "Integrator from a name as integrator_name prints it (any case).");
  m.def("backend_name", &backendName);
  m.def("parse_backend", &parseBackend, "name"_a);
  m.def("acceleration_name", &accelerationName);
  m.def("parse_acceleration", &parseAcceleration, "name"_a);
  m.def("blend_branch_name", &blendBranchName);
  m.def("all_integrators", &allIntegrators);
}

void bindElements(nb::module_& m) {
  nb::class_<Spring>(m, "Spring", "E = k/2 (|x_a - x_b| - rest_length)^2.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](Spring* s, int a, int b, double rest_length, double stiffness) {
            new (s) Spring{a, b, rest_length, stiffness};
          },
          "a"_a, "b"_a, "rest_length"_a, "stiffness"_a)
      .def_rw("a", &Spring::a)
      .def_rw("b", &Spring::b)
      .def_rw("rest_length", &Spring::rest_length)
      .def_rw("stiffness", &Spring::stiffness);
  nb::class_<Tet>(m, "Tet", "Co-rotated strain of a tetrahedron against the scene's rest positions.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](Tet* t, std::array<int, 4> v, double k) {
            new (t) Tet{v, k};
          },
          "vertices"_a, "stiffness"_a)
      .def_rw("vertices", &Tet::vertices)
      .def_rw("stiffness", &Tet::stiffness);
  nb::class_<TriangleStrain>(m, "TriangleStrain",
                             "Membrane strain of a triangle, singular values kept in [strain_min, strain_max].")
      .def(nb::init<>())
      .def(
          "__init__",
          [](TriangleStrain* t, std::array<int, 3> v, double k, double lo, double hi) {
            new (t) TriangleStrain{v, k, lo, hi};
          },
          "vertices"_a, "stiffness"_a, "strain_min"_a = 1.0, "strain_max"_a = 1.0)
      .def_rw("vertices", &TriangleStrain::vertices)
      .def_rw("stiffness", &TriangleStrain::stiffness)
      .def_rw("strain_min", &TriangleStrain::strain_min)
      .def_rw("strain_max", &TriangleStrain::strain_max);
  nb::class_<BendingHinge>(m, "BendingHinge", "Bending across the edge (vertices[0], vertices[1]).")
      .def(nb::init<>())
      .def(
          "__init__",
          [](BendingHinge* h, std::array<int, 4> v, double k) {
            new (h) BendingHinge{v, k};
          },
          "vertices"_a, "stiffness"_a)
      .def_rw("vertices", &BendingHinge::vertices)
      .def_rw("stiffness", &BendingHinge::stiffness);
  nb::class_<PinTarget>(m, "PinTarget", "q(t) = position + velocity t + amplitude sin(2 pi frequency t).")
      .def(nb::init<>())
      .def_rw("position", &PinTarget::position)
      .def_rw("velocity", &PinTarget::velocity)
      .def_rw("amplitude", &PinTarget::amplitude)
      .def_rw("frequency", &PinTarget::frequency)
      .def("at", &PinTarget::at, "t"_a)
      .def("moving", &PinTarget::moving);
  nb::class_<Pin>(m, "Pin", "Zero-rest-length spring from a particle to a target: E = k/2 |x - q(t)|^2.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](Pin* p, int vertex, double k, const Eigen::Vector3d& position) {
            new (p) Pin{vertex, k, PinTarget{}};
            p->target.position = position;
          },
          "vertex"_a, "stiffness"_a, "position"_a, "A static pin at `position`.")
      .def_rw("vertex", &Pin::vertex)
      .def_rw("stiffness", &Pin::stiffness)
      .def_rw("target", &Pin::target);
  nb::class_<ForceField>(m, "ForceField",
                         "f(t) = force + rate t + amplitude sin(2 pi frequency t) on `particles` (all when empty).")
      .def(nb::init<>())
      .def_rw("particles", &ForceField::particles)
      .def_rw("force", &ForceField::force)
      .def_rw("rate", &ForceField::rate)
      .def_rw("amplitude", &ForceField::amplitude)
      .def_rw("frequency", &ForceField::frequency)
      .def("at", &ForceField::at, "t"_a);
  nb::class_<Body>(m, "Body", "Particles damped together (momentum-preserving), damping in [0, 1].")
      .def(nb::init<>())
      .def_rw("name", &Body::name)
      .def_rw("particles", &Body::particles)
      .def_rw("damping", &Body::damping);
  nb::class_<Collider>(m, "Collider",
                       "A rigid obstacle the scene's particles, or a range of them, collide with (docs/method.md, "
                       "'Contact'); the fields "
                       "are documented in stabint/scene.hpp.")
      .def(nb::init<>())
      .def_rw("shape", &Collider::shape)
      .def_rw("center", &Collider::center, "Plane: a point of it; sphere and box: the center; capsule: one end.")
      .def_rw("normal", &Collider::normal, "Plane: the outward normal.")
      .def_rw("half_extents", &Collider::half_extents, "Box (axis-aligned): half sizes.")
      .def_rw("end", &Collider::end, "Capsule: the other end of its axis.")
      .def_rw("radius", &Collider::radius, "Sphere and capsule.")
      .def_rw("velocity", &Collider::velocity, "Translation in m/s (0: static).")
      .def_rw("friction", &Collider::friction, "Coulomb coefficient mu >= 0.")
      .def_rw("stiffness", &Collider::stiffness, "Contact weight per unit of particle mass, 1/s^2 (> 0).")
      .def_rw("first_particle", &Collider::first_particle,
              "The first particle it acts on (with num_particles; a batch sets each scene's).")
      .def_rw("num_particles", &Collider::num_particles,
              "How many particles from first_particle it acts on; -1 (default): every particle.")
      .def("moving", &Collider::moving);

  nb::bind_vector<std::vector<Spring>>(m, "SpringList");
  nb::bind_vector<std::vector<Tet>>(m, "TetList");
  nb::bind_vector<std::vector<TriangleStrain>>(m, "TriangleStrainList");
  nb::bind_vector<std::vector<BendingHinge>>(m, "BendingHingeList");
  nb::bind_vector<std::vector<Pin>>(m, "PinList");
  nb::bind_vector<std::vector<ForceField>>(m, "ForceFieldList");
  nb::bind_vector<std::vector<Body>>(m, "BodyList");
  nb::bind_vector<std::vector<Collider>>(m, "ColliderList");
}

// Matrix properties of a Scene: get a copy, set from any (n, 3) array.
template <Eigen::MatrixX3d Scene::*field>
void rowsProperty(nb::class_<Scene>& c, const char* name, const char* doc) {
  c.def_prop_rw(
      name, [](const Scene& s) { return rowsCopy(s.*field); },
      [](Scene& s, const Eigen::MatrixX3d& value) { s.*field = value; }, nb::for_getter(nb::rv_policy::move), doc);
}

void bindScene(nb::module_& m) {
  nb::class_<Scene> scene(m, "Scene",
                          "A simulation scene. Array properties return copies (assign to change them); "
                          "element lists (springs, tets, pins, ...) are views: append to edit the scene.");
  scene.def(nb::init<>()).def(nb::init<const Scene&>(), "other"_a, "A deep copy.");
  scene.def_rw("name", &Scene::name);
  rowsProperty<&Scene::rest_positions>(scene, "rest_positions",
                                       "(n, 3) rest shape used by tets, triangles and hinges (copy).");
  rowsProperty<&Scene::positions>(scene, "positions", "(n, 3) initial positions (copy).");
  rowsProperty<&Scene::velocities>(scene, "velocities", "(n, 3) initial velocities (copy).");
  scene.def_prop_rw(
      "masses", [](const Scene& s) { return Eigen::VectorXd(s.masses); },
      [](Scene& s, const Eigen::VectorXd& v) { s.masses = v; }, nb::for_getter(nb::rv_policy::move),
      "(n,) lumped masses, > 0 (copy).");
  scene.def_rw("gravity", &Scene::gravity, "(3,) gravity in m/s^2.");
  scene.def_prop_rw(
      "triangles", [](const Scene& s) { return trianglesCopy(s.triangles); },
      [](Scene& s, nb::ndarray<const int32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu> a) {
        s.triangles = trianglesFrom(a);
      },
      nb::for_getter(nb::rv_policy::move),
      "(m, 3) int32 surface triangles for rendering and mass lumping (copy); no force of their own.");
  scene.def_rw("springs", &Scene::springs)
      .def_rw("tets", &Scene::tets)
      .def_rw("triangle_strains", &Scene::triangle_strains)
      .def_rw("bending_hinges", &Scene::bending_hinges)
      .def_rw("pins", &Scene::pins)
      .def_rw("force_fields", &Scene::force_fields)
      .def_rw("bodies", &Scene::bodies)
      .def_rw("colliders", &Scene::colliders)
      .def_prop_ro("num_particles", &Scene::numParticles)
      .def(
          "validate", [](const Scene& s) { validateScene(s); },
          "Raises InvalidInputError naming the first offending element or field.");

  m.def("builtin_scene", &builtinScene, "name"_a, "params_json"_a = "{}", "label"_a = "builtin scene",
        "A built-in scene ('oscillator', 'chain', 'cloth', 'tetbar') with its builder's parameters as a "
        "JSON object text; prefer the shortcuts cloth_grid(**params) etc. Raises FileFormatError for an "
        "unknown name or parameter.");
  m.def("builtin_scene_names", &builtinSceneNames);
  m.def("builtin_scene_parameters", &builtinSceneParameters, "name"_a);
  m.def(
      "cloth_grid_triangles", [](int nx, int ny) { return trianglesCopy(clothGridTriangles(nx, ny)); }, "nx"_a, "ny"_a,
      "The (m, 3) triangles of cloth_grid's nx by ny grid.");

  nb::class_<ClothMaterial>(m, "ClothMaterial", "Material of a loaded cloth mesh.")
      .def(nb::init<>())
      .def_rw("areal_density", &ClothMaterial::areal_density)
      .def_rw("stretch_stiffness", &ClothMaterial::stretch_stiffness)
      .def_rw("bend_stiffness", &ClothMaterial::bend_stiffness)
      .def_rw("model", &ClothMaterial::model)
      .def_rw("strain_stiffness", &ClothMaterial::strain_stiffness)
      .def_rw("strain_min", &ClothMaterial::strain_min)
      .def_rw("strain_max", &ClothMaterial::strain_max)
      .def_rw("hinge_stiffness", &ClothMaterial::hinge_stiffness);
  nb::class_<SolidMaterial>(m, "SolidMaterial", "Material of a loaded tet mesh.")
      .def(nb::init<>())
      .def_rw("density", &SolidMaterial::density)
      .def_rw("stiffness", &SolidMaterial::stiffness);
  m.def("load_obj_cloth", &loadObjCloth, "path"_a, "material"_a = ClothMaterial(),
        "A Wavefront OBJ triangle mesh as cloth. Raises FileFormatError (file, line).");
  m.def("load_tetgen", &loadTetGen, "base_path"_a, "material"_a = SolidMaterial(),
        "A TetGen mesh from <base_path>.node and <base_path>.ele.");
  m.def("load_medit", &loadMedit, "path"_a, "material"_a = SolidMaterial(), "A Medit .mesh file.");
  m.def("load_scene_file", &loadSceneFile, "path"_a, "A JSON scene file (docs/scene-format.md), validated.");
  m.def("save_scene_file", &saveSceneFile, "scene"_a, "path"_a,
        "Writes the scene as an explicit JSON scene file that load_scene_file reads back exactly.");
}

void bindSimulator(nb::module_& m) {
  const SimulatorOptions d;  // the defaults of every keyword come from the C++ struct
  nb::class_<OpenCLOptions>(m, "OpenCLOptions",
                            "OpenCL device choice: index or name substring; empty: "
                            "STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE, then the first.")
      .def(nb::init<>())
#define STABINT_PY_SUB(parent, type, name, doc) .def_rw(#name, &OpenCLOptions::name, doc)
          STABINT_OPENCL_OPTIONS_FIELDS(STABINT_PY_SUB, opencl);
#undef STABINT_PY_SUB
  nb::class_<OpenCLDeviceInfo>(m, "OpenCLDeviceInfo")
      .def_ro("platform_index", &OpenCLDeviceInfo::platform_index)
      .def_ro("device_index", &OpenCLDeviceInfo::device_index)
      .def_ro("platform_name", &OpenCLDeviceInfo::platform_name)
      .def_ro("device_name", &OpenCLDeviceInfo::device_name)
      .def_ro("vendor", &OpenCLDeviceInfo::vendor)
      .def_ro("fp64", &OpenCLDeviceInfo::fp64)
      .def_ro("gpu", &OpenCLDeviceInfo::gpu);
  m.def("list_opencl_devices", &listOpenCLDevices, "Every OpenCL device; empty when none is installed.");

  // Generated from the field list (stabint/options_fields.hpp): one keyword per field, by name,
  // with the C++ default, and one property per field.
#define STABINT_PY_PARAM(type, name, ...) , type name
#define STABINT_PY_SET(type, name, ...) o->name = name;
#define STABINT_PY_KEYWORD(type, name, ...) , nb::arg(#name) = d.name
#define STABINT_PY_PROPERTY(type, name, doc) .def_rw(#name, &SimulatorOptions::name, doc)
#define STABINT_PY_NESTED_PROPERTY(type, name, fields, doc) .def_rw(#name, &SimulatorOptions::name, doc)
  nb::class_<SimulatorOptions>(m, "SimulatorOptions",
                               "Options of a Simulator; every field is documented in stabint/simulator.hpp.")
      .def(
          "__init__",
          [](SimulatorOptions* o STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_PY_PARAM, STABINT_PY_PARAM)) {
            new (o) SimulatorOptions{};
            STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_PY_SET, STABINT_PY_SET)
          },
          nb::kw_only() STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_PY_KEYWORD, STABINT_PY_KEYWORD),
          "Keyword arguments set the fields of the same names; values are checked when a Simulator is built.")
          STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_PY_PROPERTY, STABINT_PY_NESTED_PROPERTY);
#undef STABINT_PY_PARAM
#undef STABINT_PY_SET
#undef STABINT_PY_KEYWORD
#undef STABINT_PY_PROPERTY
#undef STABINT_PY_NESTED_PROPERTY

  nb::class_<EnergyReport>(m, "EnergyReport", "Energies of a state, in joules.")
      .def_ro("kinetic", &EnergyReport::kinetic)
      .def_ro("elastic", &EnergyReport::elastic, "Springs, tets, triangles, hinges and pins.")
      .def_ro("external", &EnergyReport::external, "Gravity and force fields.")
      .def_prop_ro("total", &EnergyReport::total, "H = kinetic + elastic + external.")
      .def("__repr__", [](const EnergyReport& e) {
        return "EnergyReport(kinetic=" + std::to_string(e.kinetic) + ", elastic=" + std::to_string(e.elastic) +
               ", external=" + std::to_string(e.external) + ")";
      });
  nb::class_<PhaseTimes>(m, "PhaseTimes", "Wall-clock seconds per phase of a step.")
      .def_ro("local", &PhaseTimes::local)
      .def_ro("gather", &PhaseTimes::gather)
      .def_ro("transfer", &PhaseTimes::transfer)
      .def_ro("global_", &PhaseTimes::global, "'global' is a Python keyword.")
      .def_ro("energy", &PhaseTimes::energy)
      .def_ro("bookkeeping", &PhaseTimes::bookkeeping)
      .def_prop_ro("total", &PhaseTimes::total);
  nb::class_<StepReport>(m, "StepReport", "What one step did (a copy: later steps do not change it).")
      .def_ro("step", &StepReport::step, "Index of the step (0 = first).")
      .def_ro("time", &StepReport::time, "Time at the end of the step.")
      .def_ro("energy", &StepReport::energy, "H of the new state, split by term.")
      .def_ro("target", &StepReport::target, "Tracked target H* after the step.")
      .def_ro("forcing", &StepReport::forcing, "Energy added to H* by time-dependent potentials.")
      .def_ro("damping", &StepReport::damping, "Kinetic energy removed by damping.")
      .def_ro("branch", &StepReport::branch)
      .def_ro("alpha", &StepReport::alpha, "Blend weight of the BE partner (0 = pure IM).")
      .def_ro("velocity_scale", &StepReport::velocity_scale)
      .def_ro("event_energy", &StepReport::event_energy,
              "Energy added to H* by set_state/set_positions/set_velocities since the previous step "
              "(the jump of H they caused, booked as the user's work).")
      .def_ro("friction", &StepReport::friction,
              "Kinetic energy friction removed (taken from H*; negative when a moving collider drags "
              "particles along).")
      .def_ro("contact_projection", &StepReport::contact_projection,
              "Energy the final projection out of the colliders removed (<= 0, added to H*).")
      .def_ro("iterations", &StepReport::iterations, "Local/global iterations of all solves of the step.")
      .def_ro("energy_evaluations", &StepReport::energy_evaluations)
      .def_ro("times", &StepReport::times)
      .def("__repr__", [](const StepReport& r) {
        return "StepReport(step=" + std::to_string(r.step) + ", time=" + std::to_string(r.time) +
               ", H=" + std::to_string(r.energy.total()) + ", target=" + std::to_string(r.target) + ", branch='" +
               blendBranchName(r.branch) + "')";
      });

  nb::class_<Checkpoint>(m, "Checkpoint",
                         "A snapshot of a running simulation (Simulator.checkpoint()): time, step count, state, BDF2 "
                         "history, H* and the per-frame forcing (pin targets, external forces), not the options. "
                         "Simulator.restore() of it, into a Simulator of the same scene, options and backend, "
                         "continues bit for bit. Its bytes are a versioned format of this library version and "
                         "byte order. Immutable; picklable (through its bytes).")
      .def_prop_ro("time", &Checkpoint::time, "Simulation time of the snapshot.")
      .def_prop_ro("step_count", &Checkpoint::stepCount, "Steps taken before the snapshot.")
      .def_prop_ro(
          "bytes", [](const Checkpoint& c) { return nb::bytes(c.bytes().data(), c.bytes().size()); },
          "The serialized form (what save() writes), as a new bytes object.")
      .def_static(
          "from_bytes",
          [](nb::bytes data, const std::string& origin) {
            return Checkpoint::fromBytes(std::string(data.c_str(), data.size()), origin);
          },
          "data"_a, "origin"_a = "checkpoint",
          "A checkpoint from its bytes. Raises FileFormatError naming `origin` and the problem when "
          "they are malformed.")
      .def("save", &Checkpoint::save, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
           "Writes the bytes to a file. Raises FileFormatError when it cannot be written completely.")
      .def_static("load", &Checkpoint::load, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
                  "Reads a file written by save(). Raises FileFormatError (file) when missing or malformed.")
      .def("__getstate__", [](const Checkpoint& c) { return nb::bytes(c.bytes().data(), c.bytes().size()); })
      .def("__setstate__",
           [](Checkpoint& c, nb::bytes data) {
             new (&c) Checkpoint(Checkpoint::fromBytes(std::string(data.c_str(), data.size()), "pickled checkpoint"));
           })
      .def("__repr__", [](const Checkpoint& c) {
        return "Checkpoint(step_count=" + std::to_string(c.stepCount()) + ", time=" + std::to_string(c.time()) + ", " +
               std::to_string(c.bytes().size()) + " bytes)";
      });

  nb::class_<Simulator>(m, "Simulator",
                        "Steps a scene with one integrator. The scene is validated and copied at construction.")
      .def(nb::init<const Scene&, const SimulatorOptions&>(), "scene"_a, "options"_a = SimulatorOptions(),
           "Raises InvalidInputError for a bad scene or option, OpenCLError subtypes for the OpenCL backend.")
      .def(
          "step", [](Simulator& s) { return s.step(); }, nb::call_guard<nb::gil_scoped_release>(),
          "Advances one step and returns its report. Raises NonFiniteStateError (EnergyLimitError) when the "
          "step is refused; the simulator then keeps the last accepted state. The GIL is released while it "
          "runs, so simulators may step in parallel threads; one Simulator must not be used by two threads at once.")
      .def_prop_ro(
          "positions", [](const Simulator& s) { return rowsCopy(s.positions()); }, nb::rv_policy::move,
          "(n, 3) current positions, a C-contiguous float64 copy (x y z per particle).")
      .def_prop_ro(
          "velocities", [](const Simulator& s) { return rowsCopy(s.velocities()); }, nb::rv_policy::move,
          "(n, 3) current velocities, a C-contiguous float64 copy.")
      .def_prop_ro("time", &Simulator::time)
      .def_prop_ro("step_count", &Simulator::stepCount)
      .def_prop_ro("target", &Simulator::target, "H*, the energy the blend tracks.")
      .def("energy", &Simulator::energy, "Energies of the current state.")
      .def_prop_ro("energy_scale", &Simulator::energyScale, "E_scale of the blend tolerance.")
      .def_prop_ro(
          "scene", [](const Simulator& s) { return s.scene(); }, "A copy of the simulated scene.")
      .def_prop_ro(
          "options", [](const Simulator& s) { return s.options(); }, "A copy of the options.")
      .def_prop_ro(
          "last_report", [](const Simulator& s) { return s.lastReport(); },
          "Report of the last completed step (a copy; zeros before the first).")
      .def_prop_ro("backend_description", &Simulator::backendDescription)
      // Per-frame input (docs/method.md, "Per-frame input"): every call validates first and a
      // rejected one (InvalidInputError naming the problem) changes nothing.
      .def("set_pin_target", &Simulator::setPinTarget, "pin"_a, "target"_a,
           "Pin `pin` (an index into scene.pins) moves linearly from its current target to `target` (3,) over the "
           "next step and stays there; its scripted law is no longer used. Call it every frame with the hand's "
           "position to drag; the work is booked in H* like a scripted pin's. Raises InvalidInputError for a pin "
           "out of range or a non-finite target.")
      .def(
          "set_pin_target",
          [](Simulator& s, int pin, const std::array<double, 3>& target) {
            s.setPinTarget(pin, Eigen::Vector3d(target[0], target[1], target[2]));
          },
          "pin"_a, "target"_a, "The same with the target as a sequence of three numbers, e.g. (x, y, z).")
      .def("pin_target", &Simulator::pinTarget, "pin"_a,
           "(3,) current target of pin `pin` (its law's or the last set value at the current time), a copy.")
      .def("set_collider_position", &Simulator::setColliderPosition, "collider"_a, "position"_a,
           "Collider `collider` (an index into scene.colliders) translates linearly from where it is to "
           "`position` (3,) over the next step and stays there; `position` is where its reference point "
           "(Collider.center) goes, the rest of its shape moves with it. Call it every frame with a tool's or the "
           "mouse's position; the collider's work is booked in H* like a dragged pin's. Raises InvalidInputError "
           "for a collider out of range or a position that is not finite (nothing changes).")
      .def(
          "set_collider_position",
          [](Simulator& s, int collider, const std::array<double, 3>& p) {
            s.setColliderPosition(collider, Eigen::Vector3d(p[0], p[1], p[2]));
          },
          "collider"_a, "position"_a, "The same with the position as a sequence of three numbers.")
      .def("set_collider_velocity", &Simulator::setColliderVelocity, "collider"_a, "velocity"_a,
           "Collider `collider` translates with `velocity` (3,) m/s (zeros stop it) from where it is now on, "
           "until the next set_collider_position or set_collider_velocity. Booked as set_collider_position.")
      .def(
          "set_collider_velocity",
          [](Simulator& s, int collider, const std::array<double, 3>& v) {
            s.setColliderVelocity(collider, Eigen::Vector3d(v[0], v[1], v[2]));
          },
          "collider"_a, "velocity"_a, "The same with the velocity as a sequence of three numbers.")
      .def("collider_position", &Simulator::colliderPosition, "collider"_a,
           "(3,) where collider `collider`'s reference point (Collider.center) is now, a copy.")
      .def("collider_velocity", &Simulator::colliderVelocity, "collider"_a,
           "(3,) the collider's velocity over the last step (its set or scene velocity when it moves on), a copy.")
      .def("set_external_forces", &Simulator::setExternalForces, "forces"_a,
           "(n, 3) per-particle forces in newtons, on top of gravity and force fields: they ramp from their "
           "current value to `forces` over the next step and persist until the next call (pass zeros to remove "
           "them). Booked in H* by the forcing rule.")
      .def("set_state", &Simulator::setState, "positions"_a, "velocities"_a,
           "Replaces positions and velocities ((n, 3) each, finite): teleport, reset. H* moves by the jump of H "
           "(the next report's event_energy) and BDF2 restarts from this state, as a fresh simulator would.")
      .def("set_positions", &Simulator::setPositions, "positions"_a,
           "Replaces the positions ((n, 3), finite), keeping the velocities; booked as set_state.")
      .def("set_velocities", &Simulator::setVelocities, "velocities"_a,
           "Replaces the velocities ((n, 3), finite), keeping the positions; booked as set_state.")
      .def("set_iterations", &Simulator::setIterations, "iterations"_a,
           "Local/global iteration budget of every later step (>= 1); time, state and H* are kept, "
           "options.iterations follows.")
      .def("grab", &Simulator::grab, "vertex"_a, "stiffness"_a,
           "Attaches a handle to particle `vertex`: a new pin of `stiffness` (> 0) whose target is the particle's "
           "current position (no energy jump). Returns its pin index, for set_pin_target and release. The global "
           "factors get a rank-1 update instead of a refactorization.")
      .def("release", &Simulator::release, "pin"_a,
           "Detaches pin `pin` (a handle or a scene pin): its stiffness becomes 0 and its index stays valid; the "
           "pin's energy leaves H and H* alike (the next report's event_energy).")
      .def("set_element_stiffness",
           nb::overload_cast<ElementKind, const std::vector<int>&, double>(&Simulator::setElementStiffness), "kind"_a,
           "indices"_a, "stiffness"_a,
           "Elements `indices` of `kind` get `stiffness` (finite, >= 0; kept by disabled elements). A discontinuous "
           "event: the energy jump enters H and H* alike (the next report's event_energy); the global factors get "
           "rank updates. All indices are checked first: InvalidInputError changes nothing.")
      .def("set_element_stiffness", nb::overload_cast<ElementKind, int, double>(&Simulator::setElementStiffness),
           "kind"_a, "index"_a, "stiffness"_a, "One element; see the list form.")
      .def("set_element_enabled",
           nb::overload_cast<ElementKind, const std::vector<int>&, bool>(&Simulator::setElementEnabled), "kind"_a,
           "indices"_a, "enabled"_a,
           "Disables (weight 0, stiffness kept) or enables elements `indices` of `kind`; booked as "
           "set_element_stiffness.")
      .def("set_element_enabled", nb::overload_cast<ElementKind, int, bool>(&Simulator::setElementEnabled), "kind"_a,
           "index"_a, "enabled"_a, "One element; see the list form.")
      .def("element_enabled", &Simulator::elementEnabled, "kind"_a, "index"_a)
      .def("checkpoint", &Simulator::checkpoint, nb::call_guard<nb::gil_scoped_release>(),
           "A Checkpoint of the current simulation (the GIL is released while it is written).")
      .def("restore", &Simulator::restore, "checkpoint"_a, nb::call_guard<nb::gil_scoped_release>(),
           "Continues from a Checkpoint of a Simulator of the same scene: time, step count, state, H* and the "
           "per-frame forcing come back; options stay this simulator's. Raises InvalidInputError (nothing "
           "changed) when it belongs to another scene (particle or pin count, masses or rest shape differ).");
}

// Scripted events (include/stabint/events.hpp, docs/scene-format.md "Events").
void bindEvents(nb::module_& m) {
  nb::class_<PathKey>(m, "PathKey", "A keyframe of a path: the position at the end of step `frame - 1`.")
      .def(nb::init<>())
      .def(
          "__init__",
          [](PathKey* k, int frame, const Eigen::Vector3d& position) {
            new (k) PathKey{frame, position};
          },
          "frame"_a, "position"_a)
      .def(
          "__init__",
          [](PathKey* k, int frame, const std::array<double, 3>& p) {
            new (k) PathKey{frame, Eigen::Vector3d(p[0], p[1], p[2])};
          },
          "frame"_a, "position"_a, "The same with the position as a sequence of three numbers.")
      .def_rw("frame", &PathKey::frame)
      .def_rw("position", &PathKey::position);
  nb::class_<GrabEvent>(m, "GrabEvent", "Grab particle `vertex` with a handle of `stiffness`, dragged along `path`.")
      .def(nb::init<>())
      .def_rw("id", &GrabEvent::id)
      .def_rw("vertex", &GrabEvent::vertex)
      .def_rw("stiffness", &GrabEvent::stiffness)
      .def_rw("path", &GrabEvent::path);
  nb::class_<ReleaseEvent>(m, "ReleaseEvent", "Release the grab `id`, or (id empty) the last handle on `vertex`.")
      .def(nb::init<>())
      .def_rw("id", &ReleaseEvent::id)
      .def_rw("vertex", &ReleaseEvent::vertex);
  nb::class_<ImpulseEvent>(m, "ImpulseEvent", "Add `velocity` to the velocities of `vertices`.")
      .def(nb::init<>())
      .def_rw("vertices", &ImpulseEvent::vertices)
      .def_rw("velocity", &ImpulseEvent::velocity);
  nb::class_<ElementEvent>(m, "ElementEvent", "Set the stiffness and/or the enabled flag of elements of `kind`.")
      .def(nb::init<>())
      .def_rw("kind", &ElementEvent::kind)
      .def_rw("indices", &ElementEvent::indices)
      .def_rw("stiffness", &ElementEvent::stiffness)
      .def_rw("enabled", &ElementEvent::enabled);
  nb::class_<ColliderEvent>(m, "ColliderEvent",
                            "Move collider `collider` along `path` (Simulator.set_collider_position each frame) or "
                            "with `velocity` (Simulator.set_collider_velocity); exactly one of the two.")
      .def(nb::init<>())
      .def_rw("collider", &ColliderEvent::collider)
      .def_rw("path", &ColliderEvent::path)
      .def_rw("velocity", &ColliderEvent::velocity);
  nb::class_<ScriptedEvent>(m, "ScriptedEvent", "An action applied before step `frame` (0: before the first).")
      .def(nb::init<>())
      .def(
          "__init__",
          [](ScriptedEvent* e, int frame, const EventAction& action) {
            new (e) ScriptedEvent{frame, action};
          },
          "frame"_a, "action"_a)
      .def_rw("frame", &ScriptedEvent::frame)
      .def_rw("action", &ScriptedEvent::action,
              "A GrabEvent, ReleaseEvent, ImpulseEvent, ElementEvent or ColliderEvent (a copy: assign it back).");
  nb::class_<EventScript>(m, "EventScript",
                          "Plays timed events on a simulator: call apply(sim) before every sim.step(). Its progress "
                          "(events applied, handles held, collider paths under way) is not part of a Checkpoint: "
                          "copy the script (copy.copy) with the checkpoint and play the copy after restoring it.")
      .def(nb::init<>())
      .def(nb::init<std::vector<ScriptedEvent>>(), "events"_a,
           "Raises InvalidInputError naming the event for frames out of order, a release of no held grab, "
           "bad paths or values.")
      .def_prop_ro("events", &EventScript::events, "The events (a copy).")
      .def("empty", &EventScript::empty)
      .def("__len__", [](const EventScript& e) { return e.events().size(); })
      .def("apply", &EventScript::apply, "sim"_a,
           "Applies every event not applied yet whose frame is at most sim.step_count, then sets the held "
           "handles' targets and the moving colliders' positions for the end of the coming step.")
      .def("handle_pin", &EventScript::handlePin, "id"_a, "Pin index of the held handle of grab `id` (-1: none).")
      .def("__copy__", [](const EventScript& e) { return EventScript(e); })
      .def(
          "__deepcopy__", [](const EventScript& e, nb::handle) { return EventScript(e); }, "memo"_a);
  m.def(
      "load_scene_file_with_events",
      [](const std::string& path) {
        SceneFile file = loadSceneFileWithEvents(path);
        return std::make_pair(std::move(file.scene), std::move(file.events));
      },
      "path"_a, "A JSON scene file and its \"events\" as (Scene, EventScript); errors name the event's JSON path.");
  m.def("save_scene_file_with_events", &saveSceneFileWithEvents, "scene"_a, "events"_a, "path"_a,
        "Writes a scene file with events that load_scene_file_with_events reads back exactly.");
}

void bindBatch(nb::module_& m) {
  nb::class_<BatchStepReport>(m, "BatchStepReport", "What one BatchSimulator.step did, scene by scene.")
      .def_ro("scenes", &BatchStepReport::scenes,
              "One StepReport per scene, as its own Simulator.step would report it (a refused or inactive "
              "scene's describes its kept state).")
      .def_ro("refusals", &BatchStepReport::refusals,
              "Per scene: '' when it stepped, else why its step was refused (the message its own Simulator "
              "would have raised) or that it is inactive since a refused step.");
  nb::class_<BatchSimulator>(m, "BatchSimulator",
                             "Steps many independent scenes with one set of options: one solve and one block-diagonal "
                             "factor for all, and per scene its own energies, target, blend decisions and refusals "
                             "(docs/method.md, \"Batches\"). The scenes are validated and copied at construction.")
      .def(nb::init<const std::vector<Scene>&, const SimulatorOptions&>(), "scenes"_a, "options"_a = SimulatorOptions(),
           "Raises InvalidInputError naming the scene (\"scene 3: ...\") for a bad scene, scenes with different "
           "gravity or with colliders, or options a batch does not support (a tolerance stop, Chebyshev or Anderson "
           "acceleration, CG).")
      .def(
          "step", [](BatchSimulator& b) { return b.step(); }, nb::call_guard<nb::gil_scoped_release>(),
          "Advances every active scene one step and returns the BatchStepReport. Never raises for a scene that "
          "blows up: its step is refused (report.refusals), its state kept, and it stays inactive until set_state.")
      .def("__len__", &BatchSimulator::size)
      .def_prop_ro("size", &BatchSimulator::size, "Number of scenes.")
      .def("active", &BatchSimulator::active, "scene"_a, "False once a step of the scene was refused.")
      .def(
          "positions", [](const BatchSimulator& b, int s) { return rowsCopy(b.positions(s)); }, "scene"_a,
          nb::rv_policy::move, "(n_s, 3) positions of one scene (a copy).")
      .def(
          "velocities", [](const BatchSimulator& b, int s) { return rowsCopy(b.velocities(s)); }, "scene"_a,
          nb::rv_policy::move, "(n_s, 3) velocities of one scene (a copy).")
      .def_prop_ro(
          "all_positions", [](const BatchSimulator& b) { return rowsCopy(b.allPositions()); }, nb::rv_policy::move,
          "Every scene's positions one after another (a copy); scene s's rows start at first_particle(s).")
      .def("first_particle", &BatchSimulator::firstParticle, "scene"_a)
      .def("num_particles", &BatchSimulator::numParticles, "scene"_a)
      .def_prop_ro("time", nb::overload_cast<>(&BatchSimulator::time, nb::const_), "The batch's time.")
      .def("scene_time", nb::overload_cast<int>(&BatchSimulator::time, nb::const_), "scene"_a,
           "Time of the scene's last accepted state.")
      .def("step_count", &BatchSimulator::stepCount, "scene"_a)
      .def("target", &BatchSimulator::target, "scene"_a, "H* of the scene.")
      .def("energy", &BatchSimulator::energy, "scene"_a, "Energies of the scene's current state.")
      .def("energy_scale", &BatchSimulator::energyScale, "scene"_a, "E_scale of the scene alone.")
      .def_prop_ro(
          "options", [](const BatchSimulator& b) { return b.options(); }, "A copy of the options.")
      .def_prop_ro("backend_description", &BatchSimulator::backendDescription)
      .def("set_state", &BatchSimulator::setState, "scene"_a, "positions"_a, "velocities"_a,
           "Replaces one scene's positions and velocities ((n_s, 3) each, finite), booked in that scene's H* "
           "only; a refused scene steps again. Raises InvalidInputError naming the scene for bad input.")
      .def(
          "set_pin_target",
          [](BatchSimulator& b, int scene, int pin, const std::array<double, 3>& target) {
            b.setPinTarget(scene, pin, Eigen::Vector3d(target[0], target[1], target[2]));
          },
          "scene"_a, "pin"_a, "target"_a,
          "Pin `pin` of scene `scene` (an index into that scene's pins) moves linearly to `target` (x, y, z) over "
          "the next step and stays there, as Simulator.set_pin_target: its work is booked in that scene's H* only.");
}

}  // namespace

NB_MODULE(_stabint, m) {
  m.doc() = "stabint: stabilizing integrators for real-time deformable bodies (C++ extension).";
  bindErrors(m);
  bindEnums(m);
  bindElements(m);
  bindScene(m);
  bindSimulator(m);
  bindBatch(m);
  bindEvents(m);
}
