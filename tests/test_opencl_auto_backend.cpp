// BackendKind::Auto with the OpenCL devices of this machine: a GPU when there is one; otherwise
// the OpenCL CPU device only for scenes with at least 2,000 rotation elements (tets, triangle
// strain), the CPU reference below that; the description names the choice and its reason.
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace stabint {
namespace {

bool hasGpu() {
  const std::vector<OpenCLDeviceInfo> devices = listOpenCLDevices();
  return std::any_of(devices.begin(), devices.end(), [](const OpenCLDeviceInfo& d) { return d.gpu && d.fp64; });
}

std::string autoDescription(const Scene& scene) {
  SimulatorOptions o;
  o.backend = BackendKind::Auto;
  Simulator sim(scene, o);
  sim.step();
  EXPECT_EQ(sim.options().backend, BackendKind::Auto);
  return sim.backendDescription();
}

TEST(AutoBackend, ChoosesByDeviceAndSceneSize) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  TetBarParams big;  // 20 x 4 x 4 cells, six tets each: 1,920 tets
  big.nx = 20;
  big.ny = big.nz = 4;
  TetBarParams bigger = big;  // 2,400 tets
  bigger.nx = 25;
  ClothGridParams cloth;
  cloth.nx = cloth.ny = 50;  // springs only
  const std::string small_bar = autoDescription(makeTetBar(big));
  const std::string large_bar = autoDescription(makeTetBar(bigger));
  const std::string springs = autoDescription(makeClothGrid(cloth));
  if (hasGpu()) {
    for (const std::string& d : {small_bar, large_bar, springs}) {
      EXPECT_EQ(d.rfind("OpenCL: ", 0), 0u) << d;
      EXPECT_NE(d.find("[auto: a GPU]"), std::string::npos) << d;
    }
    return;
  }
  EXPECT_EQ(small_bar, "CPU reference (double) [auto: no GPU; 1920 rotation elements (fewer than 2000) run faster on "
                       "the CPU reference]");
  EXPECT_EQ(springs, "CPU reference (double) [auto: no GPU; 0 rotation elements (fewer than 2000) run faster on "
                     "the CPU reference]");
  EXPECT_EQ(large_bar.rfind("OpenCL: ", 0), 0u) << large_bar;
  EXPECT_NE(large_bar.find("[auto: no GPU; 2400 rotation elements (at least 2000) pay for the OpenCL CPU device]"),
            std::string::npos)
      << large_bar;
}

}  // namespace
}  // namespace stabint
