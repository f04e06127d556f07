// Failure paths and device selection of the OpenCL layer on a machine with a device: selectors
// that match nothing, environment-variable selection, kernel build errors with their log, the
// fp64 capability check, and the program cache.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "opencl/cl_runtime.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace stabint {
namespace {

// Sets an environment variable for one scope and restores the previous value.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

class OpenCLErrorsTest : public ::testing::Test {
 protected:
  void SetUp() override { STABINT_SKIP_WITHOUT_OPENCL(Precision::Float); }
};

TEST_F(OpenCLErrorsTest, ListedDevicesHaveNames) {
  const auto devices = listOpenCLDevices();
  ASSERT_FALSE(devices.empty());
  for (const auto& d : devices) {
    EXPECT_FALSE(d.platform_name.empty());
    EXPECT_FALSE(d.device_name.empty());
  }
}

TEST_F(OpenCLErrorsTest, SelectorMatchingNothingIsNoDeviceError) {
  SceneData data(makeChainPendulum({}));
  Forcing forcing(data.scene());
  OpenCLOptions options;
  options.device = "no-such-device-xyz";
  try {
    makeOpenCLBackend(data, forcing, 1, options);
    FAIL() << "expected NoOpenCLDeviceError";
  } catch (const NoOpenCLDeviceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no-such-device-xyz"), std::string::npos) << what;
    // The message lists what is available, so the user can correct the selector.
    EXPECT_NE(what.find(listOpenCLDevices().front().device_name), std::string::npos) << what;
  }
  options.device.clear();
  options.platform = "99";
  EXPECT_THROW(makeOpenCLBackend(data, forcing, 1, options), NoOpenCLDeviceError);
  // A selector is user text: its bytes outside printable ASCII are escaped, never echoed raw.
  options.platform.clear();
  options.device = "gpu\xff\x1b[2J";
  try {
    makeOpenCLBackend(data, forcing, 1, options);
    FAIL() << "expected NoOpenCLDeviceError";
  } catch (const NoOpenCLDeviceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("device selector 'gpu\\xff\\x1b[2J'"), std::string::npos) << what;
    EXPECT_EQ(what.find('\x1b'), std::string::npos) << what;
  }
}

TEST_F(OpenCLErrorsTest, EnvironmentVariablesSelectTheDevice) {
  const OpenCLDeviceInfo first = listOpenCLDevices().front();
  SceneData data(makeChainPendulum({}));
  Forcing forcing(data.scene());
  {
    ScopedEnv platform("STABINT_OPENCL_PLATFORM", std::to_string(first.platform_index).c_str());
    // A case-changed substring of the name selects by name.
    std::string part = first.device_name.substr(0, std::min<std::size_t>(6, first.device_name.size()));
    for (char& ch : part) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    ScopedEnv device("STABINT_OPENCL_DEVICE", part.c_str());
    auto backend = makeOpenCLBackend(data, forcing, 1, testing::openclOptions(Precision::Float));
    EXPECT_NE(backend->description().find(first.device_name), std::string::npos);
  }
  {
    ScopedEnv device("STABINT_OPENCL_DEVICE", "no-such-device-xyz");
    EXPECT_THROW(makeOpenCLBackend(data, forcing, 1, testing::openclOptions(Precision::Float)), NoOpenCLDeviceError);
    // Options take precedence over the environment.
    OpenCLOptions options = testing::openclOptions(Precision::Float);
    options.device = std::to_string(first.device_index);
    EXPECT_NO_THROW(makeOpenCLBackend(data, forcing, 1, options));
  }
}

TEST_F(OpenCLErrorsTest, SyntaxErrorGivesKernelBuildErrorWithLog) {
  const ocl::SelectedDevice device = ocl::selectDevice(OpenCLOptions{});
  const cl::Context context = ocl::sharedContext(device.device);
  const std::string source = "__kernel void broken(__global float* x) { x[0] = undeclared_name; }";
  try {
    ocl::buildProgram(context, device.device, source, "-cl-std=CL1.2");
    FAIL() << "expected KernelBuildError";
  } catch (const KernelBuildError& e) {
    EXPECT_FALSE(e.buildLog().empty());
    EXPECT_NE(e.buildLog().find("undeclared_name"), std::string::npos) << e.buildLog();
    const std::string what = e.what();
    EXPECT_NE(what.find("clBuildProgram"), std::string::npos) << what;
    EXPECT_NE(what.find(e.buildLog()), std::string::npos) << what;
  }
  // A build error is an OpenCLError, hence a stabint::Error.
  EXPECT_THROW(ocl::cachedProgram(context, device.device, source, "-cl-std=CL1.2"), Error);
}

TEST_F(OpenCLErrorsTest, ApiErrorsNameTheCallAndCode) {
  try {
    ocl::check(CL_OUT_OF_RESOURCES, "clEnqueueNDRangeKernel");
    FAIL();
  } catch (const OpenCLError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("clEnqueueNDRangeKernel"), std::string::npos) << what;
    EXPECT_NE(what.find("CL_OUT_OF_RESOURCES"), std::string::npos) << what;
    EXPECT_NE(what.find("-5"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(ocl::check(CL_SUCCESS, "clFinish"));
}

// PoCL has fp64, so the capability check is exercised with a fake flag.
TEST_F(OpenCLErrorsTest, DoubleWithoutFp64IsUnsupportedPrecision) {
  try {
    ocl::checkPrecisionSupported(Precision::Double, /*device_has_fp64=*/false, "fake device");
    FAIL() << "expected UnsupportedPrecisionError";
  } catch (const UnsupportedPrecisionError& e) {
    EXPECT_NE(std::string(e.what()).find("fake device"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("cl_khr_fp64"), std::string::npos);
  }
  EXPECT_NO_THROW(ocl::checkPrecisionSupported(Precision::Float, false, "fake device"));
  EXPECT_NO_THROW(ocl::checkPrecisionSupported(Precision::Double, true, "fake device"));
  // And the real device's flag agrees with what the listing says.
  const ocl::SelectedDevice device = ocl::selectDevice(OpenCLOptions{});
  EXPECT_EQ(device.fp64, listOpenCLDevices().front().fp64);
}

TEST_F(OpenCLErrorsTest, ProgramsAreBuiltOncePerContextDeviceAndOptions) {
  const ocl::SelectedDevice device = ocl::selectDevice(OpenCLOptions{});
  const cl::Context context = ocl::sharedContext(device.device);
  EXPECT_EQ(context(), ocl::sharedContext(device.device)());
  const std::string source = "__kernel void k(__global float* x) { x[0] = 1.0f; }";
  const cl::Program a = ocl::cachedProgram(context, device.device, source, "-cl-std=CL1.2");
  const cl::Program b = ocl::cachedProgram(context, device.device, source, "-cl-std=CL1.2");
  const cl::Program c = ocl::cachedProgram(context, device.device, source, "-cl-std=CL1.2 -DX=1");
  EXPECT_EQ(a(), b());
  EXPECT_NE(a(), c());
}

}  // namespace
}  // namespace stabint
