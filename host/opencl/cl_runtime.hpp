#pragma once
// Thin layer over the OpenCL C++ bindings: error checking that names the API call and the error
// code, device selection (options, then environment), one shared context per device, and the
// in-process program cache. Internal to the library (and its tests); no OpenCL type leaks into
// include/stabint/.
#include <CL/opencl.hpp>

#include "backend/device_profiles.hpp"

#include <stabint/errors.hpp>
#include <stabint/types.hpp>

#include <string>

namespace stabint::ocl {

/// Symbolic name of an OpenCL error code ("CL_OUT_OF_RESOURCES"), "CL_UNKNOWN_ERROR" otherwise.
const char* errorName(cl_int code);

/// Throws OpenCLError "<call> failed: <name> (<code>)".
[[noreturn]] void throwError(cl_int code, const char* call);

/// Throws OpenCLError naming `call` when `code` is not CL_SUCCESS.
inline void check(cl_int code, const char* call) {
  if (code != CL_SUCCESS) throwError(code, call);
}

/// The device a backend runs on.
struct SelectedDevice {
  cl::Platform platform;
  cl::Device device;
  int platform_index = 0;
  int device_index = 0;
  std::string platform_name;
  std::string device_name;
  std::string vendor;
  bool gpu = false;
  bool fp64 = false;
  const DeviceProfile* profile = nullptr;  // launch sizes and policies (device_profiles.hpp)
};

/// Picks a device from `options` (platform / device selectors), falling back to the environment
/// variables STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE, then to the first device of the
/// first platform that has one. A selector is an index or a case-insensitive name substring.
/// Its profile is the device's row of the device table, or the row STABINT_OPENCL_PROFILE names.
/// Throws NoOpenCLDeviceError when nothing matches (the message lists what exists).
SelectedDevice selectDevice(const OpenCLOptions& options);

/// Throws UnsupportedPrecisionError when `precision` is Double and the device lacks cl_khr_fp64.
void checkPrecisionSupported(Precision precision, bool device_has_fp64, const std::string& device_name);

/// One context per device for the whole process, so that programs built for it are shared by
/// every backend (the cache below is keyed by context).
cl::Context sharedContext(const cl::Device& device);

/// The options the library's programs are built with: OpenCL C 1.2 and the precision
/// kernels/real.cl switches on ("-DSTABINT_DOUBLE" or "-DSTABINT_FLOAT").
std::string programOptions(Precision precision);

/// Compiles kernelPrelude() (host/common/kernel_constants.hpp: the constants host and kernels share)
/// followed by `source` for `device` (uncached), so every program sees the host's values and no
/// kernel file defines them. Throws KernelBuildError carrying the build log.
cl::Program buildProgram(const cl::Context& context, const cl::Device& device, const std::string& source,
                         const std::string& options);

/// buildProgram through an in-process cache keyed by (context, device, options, source).
cl::Program cachedProgram(const cl::Context& context, const cl::Device& device, const std::string& source,
                          const std::string& options);

}  // namespace stabint::ocl
