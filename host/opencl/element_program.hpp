#pragma once
// The OpenCL program of the backend, generated from the table of element types: the fixed kernel
// files, each type's kernels/<identifier>.cl with its instance of kernels/element_pass.cl, and
// the element_pass kernel that hands each work-group to one type (or to the vertices).
#include <string>

namespace stabint::ocl {

/// Source of the whole program. element_pass's arguments are, in order: x, n, flags, f_ext,
/// contributions, partials, per-element energies, local scratch, the first group of the vertex
/// segment, then for each element type in the order of elementTypes(): its segment (int4: first
/// group, end group, elements, first contribution), vertices, coefficients and params.
std::string elementProgramSource();

}  // namespace stabint::ocl
