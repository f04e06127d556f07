#pragma once
// Behaviour suites that run on every backend from one test body: the CPU reference, OpenCL in
// double and OpenCL in float. A suite derives its fixture from BackendTest (or takes a
// BackendUnderTest as the first element of a tuple parameter) and instantiates itself with
// STABINT_ON_EVERY_BACKEND. The instances are named Cpu/... and OpenCL/...; tests/CMakeLists.txt
// gives OpenCL/... the ctest label `opencl` and everything else `cpu`, and the OpenCL instances
// report themselves skipped when no device with the precision exists (as the test_opencl_* files
// do), so `ctest -L cpu` and the STABINT_WITH_OPENCL=OFF build run the CPU reference only.
//
// Tolerances: each test states its double and its float tolerance. On OpenCL in float the state
// slots, the local step and the energy reductions are float (the global solve stays double), so
// every step rounds the state to unitRoundoff() = 2^-24 ~ 6e-8 relative and every energy is
// evaluated to a few of those relative to the size of its terms.
#include "test_opencl_support.hpp"

#include <stabint/simulator.hpp>

#include <gtest/gtest.h>

#include <string>
#include <tuple>

namespace stabint::testing {

struct BackendUnderTest {
  BackendKind kind = BackendKind::CpuReference;
  Precision precision = Precision::Double;

  bool isFloat() const { return kind == BackendKind::OpenCL && precision == Precision::Float; }
  /// Unit round-off of the state and energies: 2^-53 in double, 2^-24 in float.
  double unitRoundoff() const { return isFloat() ? 0x1p-24 : 0x1p-53; }
  /// The options with this backend selected.
  SimulatorOptions apply(SimulatorOptions options) const {
    options.backend = kind;
    options.opencl.precision = precision;
    return options;
  }
  /// "cpu", "double" (OpenCL) or "float" (OpenCL): the last part of the test names.
  std::string name() const { return kind == BackendKind::CpuReference ? "cpu" : precisionName(precision); }
  /// Why this backend cannot run here, or "" when it can.
  std::string skipReason() const { return kind == BackendKind::OpenCL ? openclSkipReason(precision) : ""; }
};

inline void PrintTo(const BackendUnderTest& b, std::ostream* os) { *os << b.name(); }

inline const BackendUnderTest kCpuReference{BackendKind::CpuReference, Precision::Double};
inline const BackendUnderTest kOpenCLDouble{BackendKind::OpenCL, Precision::Double};
inline const BackendUnderTest kOpenCLFloat{BackendKind::OpenCL, Precision::Float};

/// Fixture of a suite parameterized by the backend alone.
class BackendTest : public ::testing::TestWithParam<BackendUnderTest> {
 protected:
  void SetUp() override {
    const std::string reason = backend().skipReason();
    if (!reason.empty()) GTEST_SKIP() << reason;
  }
  const BackendUnderTest& backend() const { return GetParam(); }
  SimulatorOptions options(SimulatorOptions o = {}) const { return backend().apply(o); }
};

struct BackendParamName {
  std::string operator()(const ::testing::TestParamInfo<BackendUnderTest>& info) const { return info.param.name(); }
};

}  // namespace stabint::testing

/// Instantiates `suite` (a BackendTest) as Cpu/<suite>.<test>/cpu and
/// OpenCL/<suite>.<test>/{double,float}.
#define STABINT_ON_EVERY_BACKEND(suite)                                                                            \
  INSTANTIATE_TEST_SUITE_P(Cpu, suite, ::testing::Values(::stabint::testing::kCpuReference),                       \
                           ::stabint::testing::BackendParamName());                                                \
  INSTANTIATE_TEST_SUITE_P(OpenCL, suite,                                                                          \
                           ::testing::Values(::stabint::testing::kOpenCLDouble, ::stabint::testing::kOpenCLFloat), \
                           ::stabint::testing::BackendParamName())
