// A library built with STABINT_WITH_OPENCL=OFF (CPU reference only: no OpenCL headers or ICD
// loader needed): there are no devices, and asking for the OpenCL backend is the documented
// NoOpenCLDeviceError, so code written for both backends runs unchanged. Compiled instead of
// host/opencl/ (CMakeLists.txt).
#include "opencl/opencl_backend.hpp"

#include <stabint/errors.hpp>

namespace stabint {

std::unique_ptr<Backend> makeOpenCLBackend(const SceneData&, const Forcing&, int, const OpenCLOptions&) {
  throw NoOpenCLDeviceError(
      "this stabint was built without OpenCL (STABINT_WITH_OPENCL=OFF): "
      "use BackendKind::CpuReference or Auto");
}

std::vector<OpenCLDeviceInfo> listOpenCLDevices() { return {}; }

}  // namespace stabint
