#pragma once
// The OpenCL program of the backend, generated from element types (those of the scene): the fixed
// kernel files, each type's kernels/<identifier>.cl with its instance of kernels/element_pass.cl,
// and the element_pass kernel that hands each work-group to one type (or to the vertices).
// ocl::buildProgram puts the prelude of shared constants (host/common/kernel_constants.hpp: PASS_*, ...)
// before it.
#include <string>
#include <vector>

namespace stabint {
class ElementType;
}

namespace stabint::ocl {

/// Source of the program for `types` (a subsequence of elementTypes(): a scene without tets does
/// not compile the tet's rotation). element_pass's arguments are, in order: x, n, flags, the
/// launch's first group, f_ext, contributions, partials, per-element energies, local scratch, the
/// first group of the vertex segment, then for each of `types` in order: its segment (int4: first group, end group,
/// elements, first contribution), vertices, coefficients and params.
std::string elementProgramSource(const std::vector<const ElementType*>& types);

}  // namespace stabint::ocl
