#pragma once
// The kernels/*.cl files, embedded into the library at build time by cmake/EmbedKernels.cmake
// (the generated source defines kEmbeddedKernelFiles). No kernel file is read at run time.
#include <cstddef>
#include <string>

namespace stabint::ocl {

struct EmbeddedKernelFile {
  const char* name;    // file name inside kernels/, e.g. "springs.cl"
  const char* source;  // its full text
};
extern const EmbeddedKernelFile kEmbeddedKernelFiles[];
extern const std::size_t kNumEmbeddedKernelFiles;

/// Text of kernels/<file_name>; throws stabint::Error when the file was not embedded.
std::string embeddedKernel(const std::string& file_name);

}  // namespace stabint::ocl
