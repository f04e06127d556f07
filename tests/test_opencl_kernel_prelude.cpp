// The prelude (host/common/kernel_constants.hpp) from the kernels' side: no kernel file defines one of
// its names (each constant is declared once, on the host), and a program built the way the
// backends build theirs (ocl::buildProgram, ocl::programOptions) sees exactly the host's values,
// in double and in float.
#include "elements/element_type.hpp"
#include "common/kernel_constants.hpp"
#include "opencl/cl_runtime.hpp"
#include "opencl/embedded_kernels.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>
#include <vector>

namespace stabint {
namespace {

std::vector<std::string> preludeNames() {
  std::vector<std::string> names;
#define STABINT_NAME(kernel_name, host, value) names.push_back(#kernel_name);
  STABINT_KERNEL_INTS(STABINT_NAME)
  STABINT_KERNEL_REALS(STABINT_NAME)
#undef STABINT_NAME
  return names;
}

// Needs no device: the kernel files are embedded in the library.
TEST(OpenCLKernelPrelude, NoKernelFileDefinesAPreludeName) {
  ASSERT_GT(ocl::kNumEmbeddedKernelFiles, 0u);
  for (const std::string& name : preludeNames()) {
    const std::regex defined("#[ \\t]*(define|undef)[ \\t]+" + name + "\\b");
    for (std::size_t i = 0; i < ocl::kNumEmbeddedKernelFiles; ++i)
      EXPECT_FALSE(std::regex_search(ocl::kEmbeddedKernelFiles[i].source, defined))
          << ocl::kEmbeddedKernelFiles[i].name << " defines " << name
          << ", which host/common/kernel_constants.hpp declares";
  }
}

// A kernel that writes every entry of the lists to a buffer, in list order.
std::string valuesKernel() {
  std::string body;
  int i = 0, r = 0;
#define STABINT_STORE_INT(kernel_name, host, value) body += "  ints[" + std::to_string(i++) + "] = " #kernel_name ";\n";
#define STABINT_STORE_REAL(kernel_name, host, value) \
  body += "  reals[" + std::to_string(r++) + "] = " #kernel_name ";\n";
  STABINT_KERNEL_INTS(STABINT_STORE_INT)
  STABINT_KERNEL_REALS(STABINT_STORE_REAL)
#undef STABINT_STORE_INT
#undef STABINT_STORE_REAL
  return ocl::embeddedKernel("real.cl") +
         "\n__kernel void prelude_values(__global int* ints, __global real* reals) {\n" + body + "}\n";
}

template <typename Real>
void expectDeviceValues(const ocl::SelectedDevice& device, Precision precision) {
  SCOPED_TRACE(precisionName(precision));
  const cl::Context context = ocl::sharedContext(device.device);
  const cl::Program program = ocl::buildProgram(context, device.device, valuesKernel(), ocl::programOptions(precision));
  std::vector<cl_int> ints;
  std::vector<Real> reals;
#define STABINT_COUNT_INT(kernel_name, host, value) ints.push_back(-1);
#define STABINT_COUNT_REAL(kernel_name, host, value) reals.push_back(Real(-1));
  STABINT_KERNEL_INTS(STABINT_COUNT_INT)
  STABINT_KERNEL_REALS(STABINT_COUNT_REAL)
#undef STABINT_COUNT_INT
#undef STABINT_COUNT_REAL
  cl_int err = CL_SUCCESS;
  cl::CommandQueue queue(context, device.device, 0, &err);
  ocl::check(err, "clCreateCommandQueue");
  cl::Buffer int_buffer(context, CL_MEM_WRITE_ONLY, ints.size() * sizeof(cl_int), nullptr, &err);
  ocl::check(err, "clCreateBuffer");
  cl::Buffer real_buffer(context, CL_MEM_WRITE_ONLY, reals.size() * sizeof(Real), nullptr, &err);
  ocl::check(err, "clCreateBuffer");
  cl::Kernel kernel(program, "prelude_values", &err);
  ocl::check(err, "clCreateKernel");
  ocl::check(kernel.setArg(0, int_buffer), "clSetKernelArg");
  ocl::check(kernel.setArg(1, real_buffer), "clSetKernelArg");
  ocl::check(queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(1), cl::NullRange),
             "clEnqueueNDRangeKernel");
  ocl::check(queue.enqueueReadBuffer(int_buffer, CL_TRUE, 0, ints.size() * sizeof(cl_int), ints.data()),
             "clEnqueueReadBuffer");
  ocl::check(queue.enqueueReadBuffer(real_buffer, CL_TRUE, 0, reals.size() * sizeof(Real), reals.data()),
             "clEnqueueReadBuffer");
  std::size_t i = 0, r = 0;
#define STABINT_EXPECT_INT(kernel_name, host, value) EXPECT_EQ(ints[i++], static_cast<cl_int>(host)) << #kernel_name;
  // A float program rounds the literal to float: the host's double rounded to float.
#define STABINT_EXPECT_REAL(kernel_name, host, value) EXPECT_EQ(reals[r++], static_cast<Real>(host)) << #kernel_name;
  STABINT_KERNEL_INTS(STABINT_EXPECT_INT)
  STABINT_KERNEL_REALS(STABINT_EXPECT_REAL)
#undef STABINT_EXPECT_INT
#undef STABINT_EXPECT_REAL
}

TEST(OpenCLKernelPrelude, DeviceSeesTheHostValues) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  const ocl::SelectedDevice device = ocl::selectDevice(OpenCLOptions{});
  expectDeviceValues<float>(device, Precision::Float);
  if (device.fp64)
    expectDeviceValues<double>(device, Precision::Double);
  else
    std::printf("  double skipped: %s has no cl_khr_fp64\n", device.device_name.c_str());
}

}  // namespace
}  // namespace stabint
