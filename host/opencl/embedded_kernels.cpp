#include "opencl/embedded_kernels.hpp"

#include <stabint/errors.hpp>

#include <cstring>

namespace stabint::ocl {

std::string embeddedKernel(const std::string& file_name) {
  for (std::size_t i = 0; i < kNumEmbeddedKernelFiles; ++i)
    if (file_name == kEmbeddedKernelFiles[i].name) return kEmbeddedKernelFiles[i].source;
  throw Error("kernel file '" + file_name + "' is not embedded in the library");
}

}  // namespace stabint::ocl
