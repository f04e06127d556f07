#include "integrator/backend_choice.hpp"

#include "scene/validation.hpp"

#include "device_profiles.hpp"

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"

namespace stabint {

SceneSize sceneSize(const Scene& scene) { return {scene.numParticles(), elementCount(scene)}; }

// A GPU pays from a scene size on: below it a step's launches and blocking waits (about 30 and 16
// for a blend step) cost more than the CPU reference's whole step. The size is data, per device
// class (DeviceProfile::auto_min_particles / auto_min_elements in host/device_profiles.cpp).
// A GPU whose fp64 is slow (consumer GPUs, 1/32-1/64 of fp32) is not taken for double: the CPU
// reference in double beats it; Precision::Float, or BackendKind::OpenCL explicitly, uses it.
// An OpenCL CPU device (PoCL) is never taken (its row's threshold is kNever): it is no faster
// than the CPU reference at any scene size measured on the 2-core VM. Since the tet and
// triangle-strain rotations became Newton polar iterations, the CPU reference's local step is
// about as fast as PoCL's, and PoCL adds launches, transfers and a host solve slowed by its
// waiting threads, so small scenes lose and large ones tie (docs/bench_summary.md "Auto backend
// rule"). A tie goes to the CPU reference (double, no program build, one core);
// BackendKind::OpenCL still selects PoCL.
BackendSelection chooseBackend(const SimulatorOptions& o, const std::vector<OpenCLDeviceInfo>& devices,
                               SceneSize size) {
  if (o.backend != BackendKind::Auto) return {o.backend, o.opencl, ""};
  const bool need_fp64 = o.opencl.precision == Precision::Double;
  bool cpu_device = false;
  const DeviceProfile* slow_fp64_gpu = nullptr;  // the first GPU passed over for its fp64
  const DeviceProfile* small_for_gpu = nullptr;  // the first GPU the scene is too small for
  for (const OpenCLDeviceInfo& d : devices) {
    if (need_fp64 && !d.fp64) continue;
    const DeviceProfile& profile = deviceProfile(d);
    if (!d.gpu) {
      cpu_device = true;
      continue;
    }
    if (need_fp64 && !profile.fast_fp64) {
      if (!slow_fp64_gpu) slow_fp64_gpu = &profile;
      continue;
    }
    if (size.particles >= profile.auto_min_particles || size.elements >= profile.auto_min_elements) {
      OpenCLOptions chosen = o.opencl;
      chosen.platform = std::to_string(d.platform_index);
      chosen.device = std::to_string(d.device_index);
      return {BackendKind::OpenCL, chosen, "auto: a GPU"};
    }
    if (!small_for_gpu) small_for_gpu = &profile;
  }
  if (small_for_gpu)
    return {BackendKind::CpuReference, o.opencl,
            "auto: the scene (" + std::to_string(size.particles) + " particles, " + std::to_string(size.elements) +
                " elements) is below the GPU's threshold (" + std::to_string(small_for_gpu->auto_min_particles) +
                " particles or " + std::to_string(small_for_gpu->auto_min_elements) + " elements, device profile " +
                small_for_gpu->name + "): launches and waits would cost more than the CPU reference's step"};
  if (slow_fp64_gpu)
    return {BackendKind::CpuReference, o.opencl,
            std::string("auto: the GPU's fp64 is slow (device profile ") + slow_fp64_gpu->name +
                "); Precision::Float, or BackendKind::OpenCL, runs on it"};
  if (!cpu_device)
    return {BackendKind::CpuReference, o.opencl, "auto: no OpenCL device" + std::string(need_fp64 ? " with fp64" : "")};
  return {BackendKind::CpuReference, o.opencl,
          "auto: no GPU; the OpenCL CPU device is no faster than the CPU reference"};
}

BackendSelection selectBackend(const SimulatorOptions& o, SceneSize size) {
  return chooseBackend(o, o.backend == BackendKind::Auto ? listOpenCLDevices() : std::vector<OpenCLDeviceInfo>{}, size);
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
