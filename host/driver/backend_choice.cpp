#include "driver/backend_choice.hpp"

#include "common/validation.hpp"

#include "backend/device_profiles.hpp"
#include "elements/element_type.hpp"

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"

#include <cmath>
#include <string>

namespace stabint {

SceneSize sceneSize(const Scene& scene) {
  double local_step_ns = 0.0;
  for (const ElementType* type : elementTypes()) local_step_ns += type->count(scene) * type->elementCost();
  return {scene.numParticles(), elementCount(scene), local_step_ns};
}

namespace {

// The CPU reference's CG: one K_c product and the vector updates per CG iteration, about 29 ns per
// particle on one core of the 2-core VM (global_step/*/cg10/cpu: 728 us on the 2,500-particle
// cloth, 1,455 us on the 5,000-particle tet bar).
constexpr double kCpuCgParticleNs = 29.0;

// One iteration's cost that differs between the CPU reference and a device, in microseconds:
// what both pay alike (the host factor's solve, the host's vector work) is left out. On the CPU
// reference: the local step, and the CG when the global step runs CG. On the device: its
// launches and waits, plus the transfers that the host factor needs or the device CG's launches.
double cpuIterationUs(const SimulatorOptions& o, SceneSize size) {
  double us = size.local_step_ns * 1e-3;
  if (o.global_solve == GlobalSolve::ConjugateGradient)
    us += o.cg_iterations * kCpuCgParticleNs * size.particles * 1e-3;
  return us;
}

double deviceIterationUs(const SimulatorOptions& o, SceneSize size, const DeviceProfile& profile) {
  return profile.auto_launch_us + (o.global_solve == GlobalSolve::ConjugateGradient
                                       ? o.cg_iterations * profile.auto_cg_iteration_us
                                       : profile.auto_particle_ns * size.particles * 1e-3);
}

std::string microseconds(double us) { return std::to_string(static_cast<long long>(std::lround(us))) + " us"; }

}  // namespace

// A GPU pays where an iteration costs less there than on the CPU reference: its launches, waits
// and transfers (data per device class, DeviceProfile::auto_* in host/backend/device_profiles.cpp, measured
// on an H200) against the local step's element work (each element type's measured cost) and, with
// GlobalSolve::ConjugateGradient, the host CG. So tets and triangle strains, whose rotations cost
// 35-90 ns each, take a GPU from about 1,500-2,000 elements, and a spring cloth, whose 6 springs per
// particle cost about what their transfers do, stays on the CPU reference unless it solves by CG.
// A GPU whose fp64 is slow (consumer GPUs, 1/32-1/64 of fp32) is not taken for double: the CPU
// reference in double beats it; Precision::Float, or BackendKind::OpenCL explicitly, uses it.
// An OpenCL CPU device (PoCL) is never taken (its row's costs are infinite): it is no faster
// than the CPU reference at any scene size measured on the 2-core VM. Since the tet and
// triangle-strain rotations became Newton polar iterations, the CPU reference's local step is
// about as fast as PoCL's, and PoCL adds launches, transfers and a host solve slowed by its
// waiting threads, so small scenes lose and large ones tie (docs/benchmarks.md "Auto backend
// rule"). A tie goes to the CPU reference (double, no program build, one core);
// BackendKind::OpenCL still selects PoCL.
BackendSelection chooseBackend(const SimulatorOptions& o, const std::vector<OpenCLDeviceInfo>& devices,
                               SceneSize size) {
  if (o.backend != BackendKind::Auto) return {o.backend, o.opencl, ""};
  const bool need_fp64 = o.opencl.precision == Precision::Double;
  bool cpu_device = false;
  const DeviceProfile* slow_fp64_gpu = nullptr;  // the first GPU passed over for its fp64
  const DeviceProfile* slower_gpu = nullptr;     // the first GPU estimated slower than the CPU reference
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
    if (cpuIterationUs(o, size) > deviceIterationUs(o, size, profile)) {
      OpenCLOptions chosen = o.opencl;
      chosen.platform = std::to_string(d.platform_index);
      chosen.device = std::to_string(d.device_index);
      return {BackendKind::OpenCL, chosen, "auto: a GPU"};
    }
    if (!slower_gpu) slower_gpu = &profile;
  }
  if (slower_gpu)
    return {BackendKind::CpuReference, o.opencl,
            "auto: the scene (" + std::to_string(size.particles) + " particles, " + std::to_string(size.elements) +
                " elements) costs about " + microseconds(cpuIterationUs(o, size)) +
                " per iteration on the CPU reference beyond the global solve, and " +
                microseconds(deviceIterationUs(o, size, *slower_gpu)) + " on the GPU (device profile " +
                slower_gpu->name + "): its launches, waits and transfers would cost more"};
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

std::unique_ptr<Backend> makeBackend(const SceneData& scene, const Forcing& forcing, int num_slots,
                                     const BackendSelection& selection) {
  return selection.kind == BackendKind::OpenCL ? makeOpenCLBackend(scene, forcing, num_slots, selection.opencl)
                                               : makeCpuBackend(scene, forcing, num_slots);
}

double inputLimit(const BackendSelection& selection) {
  return selection.kind == BackendKind::OpenCL && selection.opencl.precision == Precision::Float
             ? validation::kMaxMagnitudeFloat
             : validation::kMaxMagnitude;
}

}  // namespace stabint
