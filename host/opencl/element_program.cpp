#include "opencl/element_program.hpp"

#include "elements/element_type.hpp"
#include "opencl/embedded_kernels.hpp"

#include <cstdio>

namespace stabint::ocl {

namespace {

// Concatenated first, in this order (real.cl defines `real`, reduce.cl workGroupSum).
const char* const kCommonFiles[] = {"real.cl",   "reduce.cl",   "vector_ops.cl",
                                    "gather.cl", "segments.cl", "projections.cl"};

void appendFile(std::string& source, const std::string& file) {
  source += "// ---- " + file + " ----\n" + embeddedKernel(file) + "\n";
}

// A double as an OpenCL `real` literal that reads back exactly (in double).
std::string realLiteral(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "(real)(%.17g)", value);
  return text;
}

// element_pass.cl with the type's sizes and names bound.
std::string instance(const ElementType& type) {
  const ElementShape shape = type.shape();
  const std::string id = type.identifier();
  std::string s = "#define ELEMENT(f) " + id + "_##f\n";
  s += "#define EL_VERTICES " + std::to_string(shape.vertices) + "\n";
  s += "#define EL_ROWS " + std::to_string(shape.rows) + "\n";
  s += "#define EL_PARAMS " + std::to_string(shape.params) + "\n";
  if (shape.shared_coefficients) {
    s += "#define EL_SHARED_COEFFICIENTS {";
    for (double c : type.sharedCoefficients()) s += realLiteral(c) + ", ";
    s += "}\n";
  }
  s += embeddedKernel("element_pass.cl");
  s += "\n#undef ELEMENT\n#undef EL_VERTICES\n#undef EL_ROWS\n#undef EL_PARAMS\n#undef EL_SHARED_COEFFICIENTS\n";
  return s;
}

// One launch for every element of every type: each work-group serves one segment (a uniform
// branch on kernel arguments), each work-item one element, and with PASS_ENERGY the group's
// energies are summed in the same launch (one partial per group, added in group order by the
// host: deterministic). Segment s is the int4 (first group, end group, items, first
// contribution); the groups after the last type's segment serve the vertices. With
// PASS_ENERGY_PER_ELEMENT (launched over the element groups only) each element's energy goes to
// element_energies[its global id] for the per-scene sums of segments.cl. A launch may cover some
// groups only, from first_group on (one scene's elements): group g of the launch is group
// first_group + g of the whole pass, with the same elements and results.
std::string dispatcher(const std::vector<const ElementType*>& types) {
  std::string args, branches;
  for (const ElementType* type : types) {
    const std::string id = type->identifier();
    args += ",\n                           const int4 " + id + "_segment, __global const int* " + id +
            "_vertices,\n                           __global const real* " + id +
            "_coefficients, __global const real* " + id + "_params";
    branches += "  if (group < " + id +
                "_segment.y) {\n"
                "    const int e = (group - " +
                id +
                "_segment.x) * local_size + lid;\n"
                "    if (e < " +
                id +
                "_segment.z)\n"
                "      energy = " +
                id + "_element(x, n, e, flags, " + id + "_segment.w, " + id + "_vertices, " + id +
                "_coefficients,\n                               " + id +
                "_params, contrib);\n"
                "  } else ";
  }
  return "__kernel void element_pass(__global const real* x, const int n, const int flags,\n"
         "                           const int first_group,\n"
         "                           __global const real* fext, __global real* contrib,\n"
         "                           __global real* partials, __global real* element_energies,\n"
         "                           __local real* scratch,\n"
         "                           const int vertex_first_group" +
         args +
         ") {\n"
         "  const int group = first_group + get_group_id(0), lid = get_local_id(0),\n"
         "            local_size = get_local_size(0);\n"
         "  real energy = 0;\n" +
         branches +
         "{\n"
         "    const int j = (group - vertex_first_group) * local_size + lid;\n"
         "    if (j < n && (flags & PASS_ENERGY)) energy = externalEnergyAt(n, x, fext, j);\n"
         "  }\n"
         "  if ((flags & PASS_ENERGY_PER_ELEMENT) && group < vertex_first_group)\n"
         "    element_energies[group * local_size + lid] = energy;\n"
         "  if (flags & PASS_ENERGY) {\n"
         "    energy = workGroupSum(energy, scratch);\n"
         "    if (lid == 0) partials[group] = energy;\n"
         "  }\n"
         "}\n";
}

}  // namespace

std::string elementProgramSource(const std::vector<const ElementType*>& types) {
  std::string source;
  for (const char* file : kCommonFiles) appendFile(source, file);
  for (const ElementType* type : types) {
    appendFile(source, std::string(type->identifier()) + ".cl");
    source += instance(*type);
  }
  source += "// ---- element_pass (generated from the element types) ----\n" + dispatcher(types);
  return source;
}

}  // namespace stabint::ocl
