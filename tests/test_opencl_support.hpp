#pragma once
// Shared helpers of the OpenCL tests: device availability, random scenes and states, and the
// relative error used by the equivalence checks.
#include <stabint/builders.hpp>
#include <stabint/scene.hpp>
#include <stabint/simulator.hpp>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>
#include <cstdio>
#include <string>
#include <vector>

namespace stabint::testing {

/// Why an OpenCL test cannot run here, or "" when it can (a device with the precision exists).
inline std::string openclSkipReason(Precision precision) {
  static const std::vector<OpenCLDeviceInfo> devices = listOpenCLDevices();
  if (devices.empty()) return "no OpenCL platform/device available";
  if (precision == Precision::Double &&
      std::none_of(devices.begin(), devices.end(), [](const OpenCLDeviceInfo& d) { return d.fp64; }))
    return "no OpenCL device with cl_khr_fp64";
  return "";
}

#define STABINT_SKIP_WITHOUT_OPENCL(precision)                                  \
  do {                                                                          \
    const std::string reason = ::stabint::testing::openclSkipReason(precision); \
    if (!reason.empty()) GTEST_SKIP() << reason;                                \
  } while (0)

inline OpenCLOptions openclOptions(Precision precision) {
  OpenCLOptions o;
  o.precision = precision;
  return o;
}

/// The precisions an OpenCL device here runs (double, then float), for tests that loop over
/// them; each missing one is reported as skipped on stdout.
inline std::vector<Precision> availablePrecisions() {
  std::vector<Precision> available;
  for (Precision precision : {Precision::Double, Precision::Float}) {
    const std::string skip = openclSkipReason(precision);
    if (skip.empty())
      available.push_back(precision);
    else
      std::printf("  %s skipped: %s\n", precisionName(precision), skip.c_str());
  }
  return available;
}

// The integrators a scene is compared on across backends: the blend's branch decisions compare
// energies against its tolerance and may differ from the CPU's in float, so float is checked on
// the integrators without decisions.
inline std::vector<Integrator> crossBackendIntegrators(Precision p) {
  if (p == Precision::Double) return {Integrator::BackwardEuler, Integrator::BDF2, Integrator::EnergyBlend};
  return {Integrator::BackwardEuler, Integrator::BDF2};
}

// The tolerances of test_opencl_integrators. With plain iterations 1e-9 relative in double and
// 1e-3 in float. With a solver whose steps depend on the iterates' dot products and decisions
// (L-BFGS, the default; Anderson; Chebyshev's safeguard) 1e-8 in double: such a solver amplifies
// round-off far more than a plain iteration, which is a contraction (measured on the CPU
// reference alone: a 1e-15 change of one coordinate of the cloth on colliders grows to 2e-9 over
// 30 BDF2 steps with L-BFGS, to 2e-12 with plain iterations); and 1e-2 in float, where an
// objective's round-off can exceed an iteration's decrease, so float and double may keep
// different iterates (docs/method.md, "Acceleration").
inline double crossBackendTolerance(Precision p, Acceleration a = SimulatorOptions{}.acceleration) {
  if (p == Precision::Double) return a == Acceleration::None ? 1e-9 : 1e-8;
  return a == Acceleration::None ? 1e-3 : 1e-2;
}

/// max |a - b| / max |b|: the error relative to the size of the reference result, so entries
/// that cancel to near zero are judged against the whole array's scale.
inline double relativeError(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

/// A scene with every element kind and time-dependent forcing: `n` particles in a unit cube,
/// springs between random pairs, tets from random quadruples of nearby particles (oriented to a
/// positive rest volume), pins with moving targets and a time-dependent force field.
inline Scene randomScene(unsigned seed, int n, int springs, int tets, int pins) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scene s;
  s.name = "random";
  s.rest_positions = Eigen::MatrixX3d::NullaryExpr(n, 3, [&]() { return u(rng); });
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(n, 3);
  s.masses = Eigen::VectorXd::NullaryExpr(n, [&]() { return 0.5 + 1.5 * u(rng); });
  std::uniform_int_distribution<int> vertex(0, n - 1);
  for (int i = 0; i < springs; ++i) {
    int a = vertex(rng), b = vertex(rng);
    while (b == a) b = vertex(rng);
    const double len = (s.rest_positions.row(a) - s.rest_positions.row(b)).norm();
    s.springs.push_back(Spring{a, b, len * (0.8 + 0.4 * u(rng)), 10.0 + 1e3 * u(rng)});
  }
  while (static_cast<int>(s.tets.size()) < tets) {
    Tet t;
    for (int& v : t.vertices) v = vertex(rng);
    const auto& v = t.vertices;
    if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] || v[2] == v[3]) continue;
    double vol = signedVolume(s.rest_positions, t.vertices);
    if (std::abs(vol) < 1e-3) continue;  // keep rest shapes well conditioned
    if (vol < 0) std::swap(t.vertices[2], t.vertices[3]);
    t.stiffness = 1e2 + 1e4 * u(rng);
    s.tets.push_back(t);
  }
  for (int i = 0; i < pins; ++i) {
    Pin p;
    p.vertex = vertex(rng);
    p.stiffness = 1e2 + 1e4 * u(rng);
    p.target.position = s.rest_positions.row(p.vertex).transpose();
    p.target.velocity = Eigen::Vector3d(0.1, 0.0, -0.2);
    p.target.amplitude = Eigen::Vector3d(0.0, 0.05, 0.0);
    p.target.frequency = 1.5;
    s.pins.push_back(p);
  }
  ForceField wind;
  wind.force = Eigen::Vector3d(0.3, 0.0, 0.1);
  wind.amplitude = Eigen::Vector3d(0.0, 0.0, 0.2);
  wind.frequency = 0.7;
  s.force_fields.push_back(wind);
  ForceField push;
  push.particles = {0, 1, 2};
  push.force = Eigen::Vector3d(-1.0, 2.0, 0.5);
  s.force_fields.push_back(push);
  validateScene(s);
  return s;
}

/// Rest positions plus uniform noise of amplitude `noise` per coordinate.
inline Eigen::MatrixX3d perturbed(const Eigen::MatrixX3d& x, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return x + Eigen::MatrixX3d::NullaryExpr(x.rows(), 3, [&]() { return noise * u(rng); });
}

/// Neumaier's compensated sum.
template <class Range>
double compensatedSum(const Range& values) {
  double sum = 0.0, c = 0.0;
  for (double v : values) {
    const double t = sum + v;
    c += std::abs(sum) >= std::abs(v) ? (sum - t) + v : (v - t) + sum;
    sum = t;
  }
  return sum + c;
}

}  // namespace stabint::testing
