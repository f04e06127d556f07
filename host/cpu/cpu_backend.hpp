#pragma once
// CPU reference backend: the same operations as the OpenCL backend in plain double-precision
// C++ over Eigen arrays. It is the oracle every OpenCL result is checked against.
#include "backend.hpp"

#include <memory>

namespace stabint {

std::unique_ptr<Backend> makeCpuBackend(const SceneData& scene, int num_slots);

}  // namespace stabint
