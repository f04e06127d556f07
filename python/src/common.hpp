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
#include <vector>

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
