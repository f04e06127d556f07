// Simulators built on several threads at the same moment agree bit for bit with the same runs
// made one after the other. ctest runs every test in its own process, so in the OpenCL case the
// threads' constructors are the process's first OpenCL calls: device discovery (ICD loader and
// driver initialisation) happens concurrently, which used to crash inside PoCL or report a
// spurious NoOpenCLDeviceError (an application would have taken that as "no GPU, fall back").
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace stabint {
namespace {

constexpr int kThreads = 4;
constexpr int kSteps = 5;

struct Outcome {
  Eigen::MatrixX3d x, v;
  bool no_device = false;
  std::string error;  // any other exception
};

// Thread i runs its own integrator (and, on OpenCL, precision), so that the program cache sees
// several keys at once, not only the same one.
SimulatorOptions optionsFor(int i, BackendKind backend) {
  SimulatorOptions o;
  o.backend = backend;
  const Integrator integrators[] = {Integrator::EnergyBlend, Integrator::BackwardEuler, Integrator::ImplicitMidpoint,
                                    Integrator::BDF2};
  o.integrator = integrators[i % 4];
  o.opencl.precision = i % 2 == 0 ? Precision::Double : Precision::Float;
  return o;
}

Scene sceneFor(int i) {
  ClothGridParams p;
  p.nx = 6 + i;
  p.ny = 5;
  return makeClothGrid(p);
}

Outcome simulate(int i, BackendKind backend) {
  Outcome r;
  try {
    Simulator sim(sceneFor(i), optionsFor(i, backend));
    for (int s = 0; s < kSteps; ++s) sim.step();
    r.x = sim.positions();
    r.v = sim.velocities();
  } catch (const NoOpenCLDeviceError& e) {
    r.no_device = true;
    r.error = e.what();
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

bool bitwiseEqual(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  return a.rows() == b.rows() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

// Runs work(i) on kThreads threads that all start together: each waits until every thread is
// running, so the first OpenCL calls really overlap.
template <typename Work>
void runAtOnce(const Work& work) {
  std::atomic<int> ready{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] {
      ready.fetch_add(1);
      while (ready.load() < kThreads) std::this_thread::yield();
      work(i);
    });
  }
  for (std::thread& t : threads) t.join();
}

void concurrentRunsAgreeWithSerialRuns(BackendKind backend) {
  std::vector<Outcome> concurrent(kThreads);
  runAtOnce([&](int i) { concurrent[i] = simulate(i, backend); });
  for (int i = 0; i < kThreads; ++i) {
    const Outcome serial = simulate(i, backend);
    if (serial.no_device) GTEST_SKIP() << "no OpenCL device: " << serial.error;
    if (backend == BackendKind::OpenCL && !serial.error.empty() &&
        optionsFor(i, backend).opencl.precision == Precision::Double &&
        serial.error.find("cl_khr_fp64") != std::string::npos)
      continue;  // a float-only device: the double runs are not comparable here
    ASSERT_TRUE(serial.error.empty()) << serial.error;
    EXPECT_TRUE(concurrent[i].error.empty()) << "thread " << i << ": " << concurrent[i].error;
    EXPECT_TRUE(bitwiseEqual(concurrent[i].x, serial.x)) << "thread " << i << ": positions differ";
    EXPECT_TRUE(bitwiseEqual(concurrent[i].v, serial.v)) << "thread " << i << ": velocities differ";
  }
}

TEST(Threads, CpuSimulatorsConstructedAtOnceAgreeWithSerialRuns) {
  concurrentRunsAgreeWithSerialRuns(BackendKind::CpuReference);
}

TEST(Threads, OpenCLSimulatorsConstructedAtOnceAgreeWithSerialRuns) {
  concurrentRunsAgreeWithSerialRuns(BackendKind::OpenCL);
}

// Listing is discovery too: threads that list while others construct must all see the same
// devices.
TEST(Threads, ListingDevicesWhileOthersConstruct) {
  std::vector<std::vector<OpenCLDeviceInfo>> lists(kThreads);
  std::vector<Outcome> runs(kThreads);
  std::vector<std::string> list_errors(kThreads);
  runAtOnce([&](int i) {
    if (i % 2 == 0) {
      try {
        lists[i] = listOpenCLDevices();
      } catch (const std::exception& e) {
        list_errors[i] = e.what();
      }
    } else {
      runs[i] = simulate(i, BackendKind::OpenCL);
    }
  });
  const std::vector<OpenCLDeviceInfo> serial = listOpenCLDevices();
  if (serial.empty()) GTEST_SKIP() << "no OpenCL device";
  for (int i = 0; i < kThreads; ++i) {
    if (i % 2 == 0) {
      EXPECT_TRUE(list_errors[i].empty()) << list_errors[i];
      ASSERT_EQ(lists[i].size(), serial.size()) << "thread " << i;
      for (size_t d = 0; d < serial.size(); ++d) EXPECT_EQ(lists[i][d].device_name, serial[d].device_name);
    } else {
      EXPECT_FALSE(runs[i].no_device) << "thread " << i << ": spurious " << runs[i].error;
    }
  }
}

}  // namespace
}  // namespace stabint
