#pragma once
// OpenCL backend: state slots, element data and the contribution CSR resident on the device;
// local projections, right-hand-side gather, explicit forces, energy reductions and vector
// operations run as kernels (kernels/*.cl, embedded at build time).
#include "backend/backend.hpp"

#include <memory>

namespace stabint {

/// Throws NoOpenCLDeviceError when no platform/device matches `options` (or the environment
/// variables STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE), UnsupportedPrecisionError when
/// double is requested on a device without fp64, KernelBuildError with the build log when the
/// program does not compile.
std::unique_ptr<Backend> makeOpenCLBackend(const SceneData& scene, const Forcing& forcing, int num_slots,
                                           const OpenCLOptions& options);

}  // namespace stabint
