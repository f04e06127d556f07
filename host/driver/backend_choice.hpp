#pragma once
// BackendKind::Auto's rule [project rule, docs/method.md "Backend choice"], apart from the
// simulator so that tests can give it any list of devices.
#include "backend/backend.hpp"

#include <stabint/simulator.hpp>

#include <memory>
#include <string>
#include <vector>

namespace stabint {

struct BackendSelection {
  BackendKind kind;  // CpuReference or OpenCL, never Auto
  OpenCLOptions opencl;
  std::string reason;  // for backendDescription(); empty unless Auto chose
};

/// The bound of per-frame input values on the selected backend: validation::kMaxMagnitude, or
/// validation::kMaxMagnitudeFloat on an OpenCL device in float.
double inputLimit(const BackendSelection& selection);

/// What BackendKind::Auto weighs against a device's costs (DeviceProfile::auto_*).
struct SceneSize {
  int particles = 0;
  int elements = 0;            // elementCount(scene)
  double local_step_ns = 0.0;  // the CPU reference's local step on one core: sum of elementCost()
};
SceneSize sceneSize(const Scene& scene);

/// The backend `o` asks for; for BackendKind::Auto, the first GPU of `devices` on which an
/// iteration is estimated to cost less than on the CPU reference (its row of the device table,
/// device_profiles.hpp), with fast fp64 when
/// `o.opencl.precision` is Double; else the CPU reference.
BackendSelection chooseBackend(const SimulatorOptions& o, const std::vector<OpenCLDeviceInfo>& devices, SceneSize size);

/// chooseBackend with this machine's OpenCL devices (listed only for BackendKind::Auto).
BackendSelection selectBackend(const SimulatorOptions& o, SceneSize size);
/// The backend of a selection with `num_slots` slots for `scene` driven by `forcing` (OpenCLError
/// subtypes for OpenCL problems), for every simulator: the one place a backend is created.
std::unique_ptr<Backend> makeBackend(const SceneData& scene, const Forcing& forcing, int num_slots,
                                     const BackendSelection& selection);

}  // namespace stabint
