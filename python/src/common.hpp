// Shared by the source files of the Python extension stabint._stabint (nanobind): the includes,
// the opaque element lists, the array copies and the binding functions each file defines
// (module.cpp calls them in order: errors and enums first, since later defaults are cast to them).
//
// Copies and views: every numpy array this module returns (positions, velocities, masses,
// triangles, gravity) is a fresh copy that the caller owns: a view into a Simulator's state
// would change under the caller at the next step(), and one into a Scene would dangle when the
// scene is reassigned. Element lists (scene.springs, scene.pins, ...) are the opposite: opaque
// list-like views into the scene, so scene.springs.append(...) edits the scene.
#pragma once

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

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

// The public enums Python sees, `X(Enum, LIST, nameOf, parse, doc)`: module.cpp binds each with
// the values of its LIST (stabint/types.hpp, stabint/scene.hpp) and its doc, and wherever Python
// passes one (an argument, a field of an options struct or a scene part), the caster below also
// takes its name as a str, the names the library's parser takes (the CLI's and scene files').
#define STABINT_PY_ENUMS(X)                                                                                           \
  X(Integrator, STABINT_INTEGRATORS, integratorName, parseIntegrator,                                                 \
    "The six integrators (docs/method.md sections 2 and 3).")                                                         \
  X(BackendKind, STABINT_BACKENDS, backendName, parseBackend, "Where the local step and the energies run.")           \
  X(Precision, STABINT_PRECISIONS, precisionName, parsePrecision, "Floating-point precision of the OpenCL backend.")  \
  X(Acceleration, STABINT_ACCELERATIONS, accelerationName, parseAcceleration,                                         \
    "Acceleration of the local/global iterations (None_: 'None' is a Python keyword).")                               \
  X(GlobalSolve, STABINT_GLOBAL_SOLVES, globalSolveName, parseGlobalSolve, "How the global step solves K_c x = rhs.") \
  X(BlendBranch, STABINT_BLEND_BRANCHES, blendBranchName, parseBlendBranch,                                           \
    "What the blend did with the IM candidate (None_: 'None' is a Python keyword).")                                  \
  X(ColliderShape, STABINT_COLLIDER_SHAPE_VALUES, colliderShapeName, parseColliderShape, "Shape of a Collider.")      \
  X(ClothModel, STABINT_CLOTH_MODELS, clothModelName, parseClothModel, "How a cloth resists deformation.")            \
  X(ElementKind, STABINT_ELEMENT_KINDS, elementKindName, parseElementKind,                                            \
    "An element list of a Scene, for set_element_stiffness and set_element_enabled.")

namespace stabint::py {

// An enum's name as the library prints it (integratorName, ...): what pickled options hold.
#define STABINT_PY_ENUM_NAME(Enum, LIST, nameOf, parse, doc) \
  inline const char* enumName(Enum value) { return nameOf(value); }
STABINT_PY_ENUMS(STABINT_PY_ENUM_NAME)
#undef STABINT_PY_ENUM_NAME

// The value of enum E named `name`: a name the library's parser takes (any case: "BE", "blend",
// "lbfgs", "cpu"), else the Python enumerator's name ("EnergyBlend", "CpuReference", as
// stabint.distributed's option dicts hold them). Neither: the parser's InvalidInputError, which
// lists the names ("unknown integrator 'x' (expected FE, SE, BE, BDF2, IM or blend)").
template <class E>
E enumFromName(const std::string& name);
#define STABINT_PY_ENUM_PARSER(Enum, LIST, nameOf, parse, doc) \
  template <>                                                  \
  Enum enumFromName<Enum>(const std::string& name);
STABINT_PY_ENUMS(STABINT_PY_ENUM_PARSER)
#undef STABINT_PY_ENUM_PARSER

}  // namespace stabint::py

// The enums' caster: nanobind's (an instance of the Python enum), or a str naming a value. A str
// that names none raises the parser's InvalidInputError from the call, rather than nanobind's
// "incompatible function arguments" listing every overload. Declared for every enum of the list
// before any binding uses one, in every file (this header), so that all agree.
namespace nanobind::detail {
// "stabint._stabint.Integrator | str" as an argument, the enum alone as a result (io_name: its
// types are text, since the signature renderer resolves no type inside one).
template <class E>
struct stabint_enum_name;
#define STABINT_PY_ENUM_CASTER_NAME(Enum, LIST, nameOf, parse, doc)                                      \
  template <>                                                                                            \
  struct stabint_enum_name<stabint::Enum> {                                                              \
    static constexpr auto name = io_name("stabint._stabint." #Enum " | str", "stabint._stabint." #Enum); \
  };
STABINT_PY_ENUMS(STABINT_PY_ENUM_CASTER_NAME)
#undef STABINT_PY_ENUM_CASTER_NAME

template <class E>
struct stabint_enum_caster {
  NB_TYPE_CASTER(E, stabint_enum_name<E>::name)

  bool from_python(handle src, uint32_t flags, cleanup_list* cleanup) {
    int64_t result;
    if (NB_CALL(enum_from_python)(NB_CTX_C(cleanup), &typeid(E), src.ptr(), &result, flags)) {
      value = static_cast<E>(result);
      return true;
    }
    if (!PyUnicode_Check(src.ptr())) return false;
    Py_ssize_t size = 0;
    const char* text = PyUnicode_AsUTF8AndSize(src.ptr(), &size);
    if (text == nullptr) {
      PyErr_Clear();
      return false;
    }
    value = stabint::py::enumFromName<E>(std::string(text, static_cast<size_t>(size)));
    return true;
  }
  static handle from_cpp(E src, rv_policy, cleanup_list* cleanup) noexcept {
    return NB_CALL(enum_from_cpp)(NB_CTX_C(cleanup), &typeid(E), static_cast<int64_t>(src));
  }
};
#define STABINT_PY_ENUM_CASTER(Enum, LIST, nameOf, parse, doc) \
  template <>                                                  \
  struct type_caster<stabint::Enum> : stabint_enum_caster<stabint::Enum> {};
STABINT_PY_ENUMS(STABINT_PY_ENUM_CASTER)
#undef STABINT_PY_ENUM_CASTER
}  // namespace nanobind::detail

// The lists of a Scene that Python sees as views (in every file, so that all agree on the
// conversion): one per element type, from the element types' list, and the others.
#define STABINT_PY_OPAQUE_LIST(kind, name) NB_MAKE_OPAQUE(std::vector<stabint::kind>)
STABINT_ELEMENT_KINDS(STABINT_PY_OPAQUE_LIST)
#undef STABINT_PY_OPAQUE_LIST
NB_MAKE_OPAQUE(std::vector<stabint::ForceField>)
NB_MAKE_OPAQUE(std::vector<stabint::Body>)
NB_MAKE_OPAQUE(std::vector<stabint::Collider>)

namespace stabint::py {

namespace nb = nanobind;

using Rows3d = nb::ndarray<nb::numpy, double, nb::shape<-1, 3>, nb::c_contig>;
using Rows3i = nb::ndarray<nb::numpy, int32_t, nb::shape<-1, 3>, nb::c_contig>;
using Triangles = std::vector<std::array<int, 3>>;
using TrianglesIn = nb::ndarray<const int32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;

// An n by 3 matrix as a new C-contiguous (n, 3) array: x y z per row, interleaved.
inline Rows3d rowsCopy(const Eigen::MatrixX3d& m) {
  const size_t n = static_cast<size_t>(m.rows());
  double* data = new double[3 * n];
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(data, m.rows(), 3) = m;
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<double*>(p); });
  return Rows3d(data, {n, 3}, owner);
}

inline Rows3i trianglesCopy(const Triangles& triangles) {
  const size_t n = triangles.size();
  int32_t* data = new int32_t[3 * n];
  for (size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) data[3 * t + k] = triangles[t][k];
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<int32_t*>(p); });
  return Rows3i(data, {n, 3}, owner);
}

inline Triangles trianglesFrom(TrianglesIn a) {
  Triangles triangles(a.shape(0));
  for (size_t t = 0; t < a.shape(0); ++t)
    for (size_t k = 0; k < 3; ++k) triangles[t][k] = a(t, k);
  return triangles;
}

// A C++ name as Python's: a Python keyword gets a trailing '_' (BlendBranch::None is None_,
// PhaseTimes::global is global_); other names are returned as they are. Static storage.
const char* pythonName(const char* name);

void bindErrors(nb::module_& m);     // module.cpp
void bindEnums(nb::module_& m);      // module.cpp
void bindScene(nb::module_& m);      // scene.cpp: the elements, Scene, builders and loaders
void bindSimulator(nb::module_& m);  // simulator.cpp: options, reports, Checkpoint, Simulator
void bindBatch(nb::module_& m);      // batch.cpp
void bindEvents(nb::module_& m);     // events.cpp

}  // namespace stabint::py
