// Behaviour without any OpenCL platform. Before anything in this process touches OpenCL, the
// ICD loader is pointed at an empty vendor directory (OCL_ICD_VENDORS), so the loader finds no
// platform regardless of what is installed: these tests run (and must pass) everywhere.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include <unistd.h>

namespace stabint {
namespace {

// Runs during static initialisation, before main and so before any OpenCL call. The loader
// reads OCL_ICD_VENDORS once, on its first use.
const std::string kEmptyVendorDir = [] {
  char pattern[] = "/tmp/stabint_no_icd_XXXXXX";
  const char* dir = ::mkdtemp(pattern);
  const std::string path = dir ? dir : "/nonexistent/stabint_no_icd";
  ::setenv("OCL_ICD_VENDORS", path.c_str(), 1);
  ::unsetenv("OCL_ICD_FILENAMES");
  return path;
}();

struct RemoveDir : ::testing::Environment {
  void TearDown() override { ::rmdir(kEmptyVendorDir.c_str()); }
};
const auto* const kRemoveDir = ::testing::AddGlobalTestEnvironment(new RemoveDir);

TEST(OpenCLNoDevice, ListIsEmptyAndDoesNotThrow) {
  std::vector<OpenCLDeviceInfo> devices;
  EXPECT_NO_THROW(devices = listOpenCLDevices());
  EXPECT_TRUE(devices.empty());
}

TEST(OpenCLNoDevice, BackendConstructionThrowsNoDeviceError) {
  SceneData data(makeChainPendulum({}));
  Forcing forcing(data.scene());
  for (Precision precision : {Precision::Double, Precision::Float}) {
    OpenCLOptions options;
    options.precision = precision;
    try {
      makeOpenCLBackend(data, forcing, 2, options);
      FAIL() << "expected NoOpenCLDeviceError";
    } catch (const NoOpenCLDeviceError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("no OpenCL platform"), std::string::npos) << what;
      EXPECT_NE(what.find("CPU reference backend"), std::string::npos) << what;
    }
  }
}

TEST(OpenCLNoDevice, SimulatorWithOpenCLBackendThrowsCatchableError) {
  SimulatorOptions options;
  options.backend = BackendKind::OpenCL;
  options.integrator = Integrator::BackwardEuler;
  // Catchable as the base OpenCL error and as stabint::Error, for a fallback to the CPU.
  EXPECT_THROW(Simulator(makeChainPendulum({}), options), NoOpenCLDeviceError);
  EXPECT_THROW(Simulator(makeChainPendulum({}), options), Error);
  options.backend = BackendKind::CpuReference;
  EXPECT_NO_THROW(Simulator(makeChainPendulum({}), options));
}

}  // namespace
}  // namespace stabint

namespace stabint {
namespace {

// Auto needs no device: it runs on the CPU reference and says why.
TEST(OpenCLNoDevice, AutoFallsBackToTheCpuReferenceAndSaysWhy) {
  SimulatorOptions o;
  o.backend = BackendKind::Auto;
  Simulator sim(makeTetBar({}), o);
  EXPECT_EQ(sim.backendDescription(), "CPU reference (double) [auto: no OpenCL device with fp64]");
  EXPECT_NO_THROW(sim.step());
}

}  // namespace
}  // namespace stabint
