#pragma once
// BackendKind::Auto's rule [project rule, docs/method.md "Backend choice"], apart from the
// simulator so that tests can give it any list of devices.
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

/// The backend `o` asks for; for BackendKind::Auto, the first GPU of `devices` (with fp64 when
/// `o.opencl.precision` is Double), else the CPU reference.
BackendSelection chooseBackend(const SimulatorOptions& o, const std::vector<OpenCLDeviceInfo>& devices);

class Backend;
class SceneData;

/// chooseBackend over this machine's devices (listed only for BackendKind::Auto).
BackendSelection chooseBackend(const SimulatorOptions& o);
/// The selected backend with `num_slots` state slots for `scene` (OpenCL errors as
/// makeOpenCLBackend throws them).
std::unique_ptr<Backend> makeBackend(const SceneData& scene, int num_slots, const BackendSelection& selection);

}  // namespace stabint
