// BackendKind::Auto: an OpenCL GPU (with fast fp64 for double precision) when there is one and
// an iteration of the scene is estimated to cost less there, else the CPU reference, also when an
// OpenCL CPU device exists (docs/method.md "Backend choice"). The rule on given device lists,
// then on this machine's devices.
#include "backend/device_profiles.hpp"
#include "driver/backend_choice.hpp"
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

// Far above every GPU row's costs (a million tets), and the smallest scene.
constexpr SceneSize kLarge{200000, 1000000, 52e9};
constexpr SceneSize kTiny{2, 1, 6.0};

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
  const BackendSelection d = chooseBackend(autoOptions(Precision::Double), {cpu, gpu_fp32, gpu_fp64}, kLarge);
  EXPECT_EQ(d.kind, BackendKind::OpenCL);
  EXPECT_EQ(d.opencl.platform, "1");
  EXPECT_EQ(d.opencl.device, "1");  // the fp32-only GPU cannot run double
  EXPECT_EQ(d.reason, "auto: a GPU");
  const BackendSelection f = chooseBackend(autoOptions(Precision::Float), {cpu, gpu_fp32, gpu_fp64}, kLarge);
  EXPECT_EQ(f.kind, BackendKind::OpenCL);
  EXPECT_EQ(f.opencl.device, "0");
  EXPECT_EQ(f.opencl.precision, Precision::Float);
}

// The boundary of the rule: one device more or less, of the other type or precision.
TEST(AutoBackend, NeverTakesAnOpenCLCpuDevice) {
  const std::string no_gpu = "auto: no GPU; the OpenCL CPU device is no faster than the CPU reference";
  for (Precision p : {Precision::Double, Precision::Float}) {
    const BackendSelection s =
        chooseBackend(autoOptions(p), {device(0, 0, false, true), device(0, 1, false, true)}, kLarge);
    EXPECT_EQ(s.kind, BackendKind::CpuReference);
    EXPECT_EQ(s.reason, no_gpu);
  }
  // A GPU without fp64 does not count for double, but does for float.
  const std::vector<OpenCLDeviceInfo> cpu_and_fp32_gpu{device(0, 0, false, true), device(1, 0, true, false)};
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), cpu_and_fp32_gpu, kLarge).reason, no_gpu);
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), cpu_and_fp32_gpu, kLarge).kind, BackendKind::OpenCL);
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {}, kLarge).reason, "auto: no OpenCL device with fp64");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {device(0, 0, false, false)}, kLarge).reason,
            "auto: no OpenCL device with fp64");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), {}, kLarge).reason, "auto: no OpenCL device");
}

TEST(AutoBackend, LeavesAnExplicitBackendAlone) {
  SimulatorOptions o;
  o.backend = BackendKind::OpenCL;
  o.opencl.device = "pthread";
  const BackendSelection s = chooseBackend(o, {device(0, 0, true, true)}, kTiny);
  EXPECT_EQ(s.kind, BackendKind::OpenCL);
  EXPECT_EQ(s.opencl.device, "pthread");
  EXPECT_EQ(s.reason, "");
  o.backend = BackendKind::CpuReference;
  EXPECT_EQ(chooseBackend(o, {device(0, 0, true, true)}, kTiny).kind, BackendKind::CpuReference);
}

OpenCLDeviceInfo namedGpu(const std::string& vendor, const std::string& name) {
  OpenCLDeviceInfo d = device(0, 0, true, true);
  d.vendor = vendor;
  d.device_name = name;
  return d;
}

// The cost rule on the scenes whose crossing was measured on an H200 (docs/benchmarks.md "GPU
// report": one BE iteration, OpenCL double against the CPU reference on the same machine): the
// GPU where it won by more than the machine's noise, the CPU reference where it lost or tied; the
// scenes nearest the crossing (the 425-particle tet bar: 0.86) are left out, as a faster CPU pass
// may move it.
TEST(AutoBackend, TakesAGpuWhereAnIterationCostsLessThere) {
  const OpenCLDeviceInfo gpu = namedGpu("NVIDIA Corporation", "NVIDIA H100 80GB HBM3");
  ASSERT_TRUE(deviceProfile(gpu).measured);
  const auto kind = [&](const Scene& scene, GlobalSolve solve = GlobalSolve::Factor) {
    SimulatorOptions o = autoOptions(Precision::Double);
    o.global_solve = solve;
    o.cg_iterations = 10;
    return chooseBackend(o, {gpu}, sceneSize(scene)).kind;
  };
  const auto tetBar = [](int nx, int nyz) {
    TetBarParams p;
    p.nx = nx;
    p.ny = p.nz = nyz;
    return makeTetBar(p);
  };
  const auto cloth = [](int side, ClothModel model) {
    ClothGridParams p;
    p.nx = p.ny = side;
    p.model = model;
    return makeClothGrid(p);
  };
  EXPECT_EQ(kind(tetBar(8, 2)), BackendKind::CpuReference);                     // 81 particles: the GPU 4.5x slower
  EXPECT_EQ(kind(tetBar(25, 5)), BackendKind::OpenCL);                          // 936: 0.73 of the CPU reference
  EXPECT_EQ(kind(tetBar(49, 9)), BackendKind::OpenCL);                          // 5,000: 0.81
  EXPECT_EQ(kind(cloth(35, ClothModel::Triangles)), BackendKind::OpenCL);       // 0.56
  EXPECT_EQ(kind(cloth(20, ClothModel::Springs)), BackendKind::CpuReference);   // 2.27
  EXPECT_EQ(kind(cloth(100, ClothModel::Springs)), BackendKind::CpuReference);  // 0.92: a tie
  // The device CG reads nothing back per iteration, and the host CG costs a K_c product each.
  EXPECT_EQ(kind(tetBar(8, 2), GlobalSolve::ConjugateGradient), BackendKind::CpuReference);              // 4.3
  EXPECT_EQ(kind(tetBar(25, 5), GlobalSolve::ConjugateGradient), BackendKind::OpenCL);                   // 0.31
  EXPECT_EQ(kind(cloth(50, ClothModel::Springs), GlobalSolve::ConjugateGradient), BackendKind::OpenCL);  // 0.14
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), {gpu}, kTiny).reason,
            "auto: the scene (2 particles, 1 elements) costs about 0 us per iteration on the CPU reference beyond the "
            "global solve, and 60 us on the GPU (device profile nvidia-datacenter-gpu): its launches, waits and "
            "transfers would cost more");
  // A CPU device beside it changes nothing, at any size.
  const OpenCLDeviceInfo cpu = device(1, 0, false, true);
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {cpu, gpu}, kLarge).opencl.platform, "0");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {cpu}, kLarge).kind, BackendKind::CpuReference);
}

// fp64 policy: Auto does not take a GPU with slow fp64 for double (it takes it for float); an
// explicit OpenCL backend is left alone.
TEST(AutoBackend, SkipsSlowFp64GpusForDouble) {
  const OpenCLDeviceInfo geforce = namedGpu("NVIDIA Corporation", "NVIDIA GeForce RTX 4090");
  const OpenCLDeviceInfo h100 = namedGpu("NVIDIA Corporation", "NVIDIA H100 80GB HBM3");
  EXPECT_FALSE(deviceProfile(geforce).fast_fp64);
  const BackendSelection d = chooseBackend(autoOptions(Precision::Double), {geforce}, kLarge);
  EXPECT_EQ(d.kind, BackendKind::CpuReference);
  EXPECT_EQ(d.reason,
            "auto: the GPU's fp64 is slow (device profile nvidia-gpu); Precision::Float, or "
            "BackendKind::OpenCL, runs on it");
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Float), {geforce}, kLarge).kind, BackendKind::OpenCL);
  OpenCLDeviceInfo second_h100 = h100;
  second_h100.device_index = 1;
  EXPECT_EQ(chooseBackend(autoOptions(Precision::Double), {geforce, second_h100}, kLarge).opencl.device, "1");
  SimulatorOptions explicit_double = autoOptions(Precision::Double);
  explicit_double.backend = BackendKind::OpenCL;
  EXPECT_EQ(chooseBackend(explicit_double, {geforce}, kTiny).kind, BackendKind::OpenCL);
}

// The rows of the device table: PoCL (any CPU device) keeps the sizes it was tuned with, which
// the cross-backend tests' 1e-9 agreement was measured on; GPUs by vendor and model, whole words.
TEST(DeviceProfiles, RowsByTypeVendorAndModel) {
  const DeviceProfile& pocl = deviceProfile(false, "GenuineIntel", "cpu-haswell-Intel(R) Xeon(R) CPU @ 2.00GHz");
  EXPECT_STREQ(pocl.name, "cpu");
  EXPECT_TRUE(pocl.measured);
  EXPECT_EQ(pocl.element_local_size, 256);
  EXPECT_EQ(pocl.reduce_local_size, 128);
  EXPECT_EQ(pocl.max_reduce_groups, 64);
  EXPECT_EQ(pocl.min_terms_per_work_item, 4);
  EXPECT_EQ(pocl.auto_launch_us, DeviceProfile::kNever);
  EXPECT_STREQ(deviceProfile(true, "NVIDIA Corporation", "Tesla V100-SXM2-16GB").name, "nvidia-datacenter-gpu");
  EXPECT_STREQ(deviceProfile(true, "NVIDIA Corporation", "NVIDIA A30").name, "nvidia-datacenter-gpu");
  EXPECT_STREQ(deviceProfile(true, "NVIDIA Corporation", "NVIDIA RTX A3000 Laptop GPU").name, "nvidia-gpu");
  EXPECT_STREQ(deviceProfile(true, "Advanced Micro Devices, Inc.", "gfx90a:sramecc+:xnack-").name, "amd-instinct-gpu");
  EXPECT_STREQ(deviceProfile(true, "Advanced Micro Devices, Inc.", "gfx1100").name, "amd-gpu");
  EXPECT_STREQ(deviceProfile(true, "Intel(R) Corporation", "Intel(R) Arc(TM) A770 Graphics").name, "intel-gpu");
  EXPECT_STREQ(deviceProfile(true, "", "").name, "gpu");
  for (bool gpu : {false, true}) {
    const DeviceProfile& row = deviceProfile(gpu, "", "");
    for (int size : {row.element_local_size, row.reduce_local_size}) EXPECT_EQ(size & (size - 1), 0) << row.name;
  }
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

// On this machine, scenes either side of the GPU rows' crossing, with tets, triangle strain and
// springs: without a GPU all take the CPU reference; with one the tets and triangles take it.
TEST(AutoBackend, ChoosesByDeviceAndSizeOnThisMachine) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  TetBarParams small;  // 8 x 2 x 2 cells, six tets each: 192 tets
  TetBarParams large;  // 35 x 7 x 7 cells: 10,290 tets
  large.nx = 35;
  large.ny = large.nz = 7;
  ClothGridParams springs;
  springs.nx = springs.ny = 50;
  ClothGridParams triangles = springs;  // 4,802 triangle strains
  triangles.model = ClothModel::Triangles;
  ClothGridParams big_springs;  // 10,000 particles: a tie with a GPU, so the CPU reference
  big_springs.nx = big_springs.ny = 100;
  const std::vector<OpenCLDeviceInfo> devices = listOpenCLDevices();
  const bool gpu = hasGpu();
  for (const Scene& scene : {makeTetBar(small), makeTetBar(large), makeClothGrid(springs), makeClothGrid(triangles),
                             makeClothGrid(big_springs)}) {
    const std::string d = autoDescription(scene);
    const BackendSelection expected = chooseBackend(autoOptions(Precision::Double), devices, sceneSize(scene));
    if (expected.kind == BackendKind::OpenCL) {
      EXPECT_TRUE(gpu);
      EXPECT_EQ(d.rfind("OpenCL: ", 0), 0u) << d;
      EXPECT_NE(d.find("[auto: a GPU]"), std::string::npos) << d;
    } else {
      EXPECT_EQ(d, "CPU reference (double) [" + expected.reason + "]");
      if (!gpu) {
        EXPECT_EQ(expected.reason, "auto: no GPU; the OpenCL CPU device is no faster than the CPU reference");
      }
    }
  }
}

}  // namespace
}  // namespace stabint
