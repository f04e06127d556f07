// BackendKind::Auto: an OpenCL GPU (with fp64 for double precision) when there is one, else the
// CPU reference whatever the scene, also when an OpenCL CPU device exists (docs/method.md
// "Backend choice"). The rule on given device lists, then on this machine's devices.
#include "integrator/backend_choice.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace stabint {
namespace {

OpenCLDeviceInfo device(int platform, int index, bool gpu, bool fp64) {
  OpenCLDeviceInfo d;
  d.platform_index = platform;
  d.device_index = index;
  d.gpu = gpu;
  d.fp64 = fp64;
  return d;
}

SimulatorOptions autoOptions(Precision precision) {
  SimulatorOptions o;
  o.backend = BackendKind::Auto;
  o.opencl.precision = precision;
  return o;
}

TEST(AutoBackend, TakesTheFirstGpuWithTheRequestedPrecision) {
  const OpenCLDeviceInfo cpu = device(0, 0, false, true);
  const OpenCLDeviceInfo gpu_fp32 = device(1, 0, true, false);
  const OpenCLDeviceInfo gpu_fp64 = device(1, 1, true, true);
  const BackendSelection d = chooseBackend(autoOptions(Precision::Double), {cpu, gpu_fp32, gpu_fp64});
  EXPECT_EQ(d.kind, BackendKind::OpenCL);
  EXPECT_EQ(d.opencl.platform, "1");
  EXPECT_EQ(d.opencl.device, "1");  // the fp32-only GPU cannot run double
  EXPECT_EQ(d.reason, "auto: a GPU");
  const BackendSelection f = chooseBackend(autoOptions(Precision::Float), {cpu, gpu_fp32, gpu_fp64});
  EXPECT_EQ(f.kind, BackendKind::OpenCL);
  EXPECT_EQ(f.opencl.device, "0");
  EXPECT_EQ(f.opencl.precision, Precision::Float);
}

// The boundary of the rule: one device more or less, of the other type or precision.
TEST(AutoBackend, NeverTakesAnOpenCLCpuDevice) {
  const std::string no_gpu = "auto: no GPU; the OpenCL CPU device is no faster than the CPU reference";
  for (Precision p : {Precision::Double, Precision::Float}) {
    const BackendSelection s = chooseBackend(autoOptions(p), {device(0, 0, false, true), device(0, 1, false, true)});
    EXPECT_EQ(s.kind, BackendKind::CpuReference);
    EXPECT_EQ(s.reason, no_gpu);
  }
  // A GPU without fp64 does not count for double, but does for float.
  const std::vector<OpenCLDeviceInfo> cpu_and_fp32_gpu{device(0, 0, false, true), device(1, 0, true, false)};
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), cpu_and_fp32_gpu).reason, no_gpu);
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), cpu_and_fp32_gpu).kind, BackendKind::OpenCL);
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {}).reason, "auto: no OpenCL device with fp64");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {device(0, 0, false, false)}).reason,
            "auto: no OpenCL device with fp64");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), {}).reason, "auto: no OpenCL device");
}

TEST(AutoBackend, LeavesAnExplicitBackendAlone) {
  SimulatorOptions o;
  o.backend = BackendKind::OpenCL;
  o.opencl.device = "pthread";
  const BackendSelection s = chooseBackend(o, {device(0, 0, true, true)});
  EXPECT_EQ(s.kind, BackendKind::OpenCL);
  EXPECT_EQ(s.opencl.device, "pthread");
  EXPECT_EQ(s.reason, "");
  o.backend = BackendKind::CpuReference;
  EXPECT_EQ(chooseBackend(o, {device(0, 0, true, true)}).kind, BackendKind::CpuReference);
}

bool hasGpu() {
  const std::vector<OpenCLDeviceInfo> devices = listOpenCLDevices();
  return std::any_of(devices.begin(), devices.end(), [](const OpenCLDeviceInfo& d) { return d.gpu && d.fp64; });
}

std::string autoDescription(const Scene& scene) {
  Simulator sim(scene, autoOptions(Precision::Double));
  sim.step();
  EXPECT_EQ(sim.options().backend, BackendKind::Auto);
  return sim.backendDescription();
}

// On this machine, scenes either side of the old 2,000-rotation-element threshold, with tets,
// triangle strain and springs only, all take the same backend.
TEST(AutoBackend, ChoosesByDeviceOnThisMachine) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  TetBarParams small;  // 8 x 2 x 2 cells, six tets each: 192 tets
  TetBarParams large;  // 35 x 7 x 7 cells: 10,290 tets
  large.nx = 35;
  large.ny = large.nz = 7;
  ClothGridParams springs;
  springs.nx = springs.ny = 50;
  ClothGridParams triangles = springs;  // 4,802 triangle strains
  triangles.model = ClothModel::Triangles;
  const bool gpu = hasGpu();
  for (const Scene& scene : {makeTetBar(small), makeTetBar(large), makeClothGrid(springs), makeClothGrid(triangles)}) {
    const std::string d = autoDescription(scene);
    if (gpu) {
      EXPECT_EQ(d.rfind("OpenCL: ", 0), 0u) << d;
      EXPECT_NE(d.find("[auto: a GPU]"), std::string::npos) << d;
    } else {
      EXPECT_EQ(d,
                "CPU reference (double) [auto: no GPU; the OpenCL CPU device is no faster than the CPU "
                "reference]");
    }
  }
}

}  // namespace
}  // namespace stabint
