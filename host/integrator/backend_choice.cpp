#include "integrator/backend_choice.hpp"

#include "scene/validation.hpp"

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"

namespace stabint {

// A GPU wins on any scene. An OpenCL CPU device (PoCL) is no faster than the CPU reference at any
// scene size measured on the 2-core VM: since the tet and triangle-strain rotations became
// Newton polar iterations, the CPU reference's local step is about as fast as PoCL's, and PoCL
// adds launches, transfers and a host solve slowed by its waiting threads, so small scenes lose
// and large ones tie (docs/bench_summary.md "Auto backend rule"). A tie goes to the CPU
// reference (double, no program build, one core); BackendKind::OpenCL still selects PoCL.
BackendSelection chooseBackend(const SimulatorOptions& o, const std::vector<OpenCLDeviceInfo>& devices) {
  if (o.backend != BackendKind::Auto) return {o.backend, o.opencl, ""};
  const bool need_fp64 = o.opencl.precision == Precision::Double;
  bool cpu_device = false;
  for (const OpenCLDeviceInfo& d : devices) {
    if (need_fp64 && !d.fp64) continue;
    if (d.gpu) {
      OpenCLOptions chosen = o.opencl;
      chosen.platform = std::to_string(d.platform_index);
      chosen.device = std::to_string(d.device_index);
      return {BackendKind::OpenCL, chosen, "auto: a GPU"};
    }
    cpu_device = true;
  }
  if (!cpu_device)
    return {BackendKind::CpuReference, o.opencl, "auto: no OpenCL device" + std::string(need_fp64 ? " with fp64" : "")};
  return {BackendKind::CpuReference, o.opencl,
          "auto: no GPU; the OpenCL CPU device is no faster than the CPU reference"};
}

BackendSelection selectBackend(const SimulatorOptions& o) {
  return chooseBackend(o, o.backend == BackendKind::Auto ? listOpenCLDevices() : std::vector<OpenCLDeviceInfo>{});
}

std::unique_ptr<Backend> makeBackend(const SceneData& scene, int num_slots, const BackendSelection& selection) {
  return selection.kind == BackendKind::OpenCL ? makeOpenCLBackend(scene, num_slots, selection.opencl)
                                               : makeCpuBackend(scene, num_slots);
}

double inputLimit(const BackendSelection& selection) {
  return selection.kind == BackendKind::OpenCL && selection.opencl.precision == Precision::Float
             ? validation::kMaxMagnitudeFloat
             : validation::kMaxMagnitude;
}

}  // namespace stabint
