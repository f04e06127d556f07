// Linear oscillator (docs/method.md section 9): one particle on a zero-rest-length spring (a pin) to
// the origin, omega^2 = k/m, no gravity. The local step's projection is the constant pin
// target, so one local/global iteration solves each implicit step exactly and every integrator
// must match its closed form to round-off, on every backend (tests/backend_suite.hpp): the
// closed forms check the OpenCL path directly, not only through agreement with the CPU.
//
// Tolerances. Double (CPU reference and OpenCL): the constants below (IM's energy: 1e-12, about
// 9000 ulps; measured at most 800). Float (OpenCL): each step rounds x and v to float (relative u = 2^-24
// each, 2u in a quadratic energy) and the right-hand side of its solve (another u). The implicit
// integrators form velocities as difference quotients (x_{n+1} - x_n) / h, which turn a position
// rounding of u |x| into a velocity error of u |x| / h, i.e. u / (omega h) relative to the
// velocity scale omega |x|: the per-step error is at most a few u times a = 1 + 1 / (omega h).
// Nothing in these conservative or contracting maps amplifies an old error, so after n steps
// the error is at most the sum of the per-step ones, bounded here by (10 + 4 n a) u of the
// quantity's scale (floatDrift; the 10 covers the energy evaluation itself). Measured on PoCL
// (scratch program over the same runs, errors in units of each precision's u): the OpenCL
// double and float runs show the same error in their own u, e.g. IM's energy 760 u after 140
// steps at omega h = 0.05 (bound: 11700 u) and 53 u after 265 steps at omega h = 3 (bound: 1400 u).
#include <stabint/stabint.hpp>

#include "backend_suite.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <tuple>

namespace stabint {
namespace {

using testing::BackendUnderTest;

constexpr double kMass = 2.0;
constexpr double kStiffness = 50.0;  // omega = 5 rad/s
constexpr double kAmplitude = 0.3;

Simulator makeOscillator(const BackendUnderTest& backend, Integrator integrator, double omega_h) {
  SimulatorOptions options;
  options.integrator = integrator;
  options.iterations = 1;
  options.time_step = omega_h / std::sqrt(kStiffness / kMass);
  return Simulator(makeLinearOscillator({kMass, kStiffness, kAmplitude}), backend.apply(options));
}

double energyOf(const Simulator& sim) { return sim.energy().total(); }

/// Float's accumulated round-off after n steps at this omega h, relative to the quantity's scale
/// (see the top).
double floatDrift(const BackendUnderTest& backend, int n, double omega_h) {
  return (10.0 + 4.0 * n * (1.0 + 1.0 / omega_h)) * backend.unitRoundoff();
}

/// Fixtures parameterized by (backend, omega h).
class OscillatorFixture : public ::testing::TestWithParam<std::tuple<BackendUnderTest, double>> {
 protected:
  void SetUp() override {
    const std::string reason = backend().skipReason();
    if (!reason.empty()) GTEST_SKIP() << reason;
  }
  const BackendUnderTest& backend() const { return std::get<0>(GetParam()); }
  double omegaH() const { return std::get<1>(GetParam()); }
};
class OscillatorTest : public OscillatorFixture {};
class SymplecticStableTest : public OscillatorFixture {};

// IM is the Cayley transform of the oscillator: it conserves the quadratic energy exactly and
// rotates the phase (x, v/omega) by theta = 2 atan(omega h / 2) per step.
TEST_P(OscillatorTest, ImplicitMidpointKeepsEnergyAndRotatesPhase) {
  Simulator sim = makeOscillator(backend(), Integrator::ImplicitMidpoint, omegaH());
  const double h0 = energyOf(sim);
  const double theta = 2.0 * std::atan(0.5 * omegaH());
  for (int n = 1; n <= 300; ++n) {
    sim.step();
    const double drift = floatDrift(backend(), n, omegaH());
    const double energy_tol = backend().isFloat() ? drift * h0 : 1e-12 * h0;
    const double x_tol = backend().isFloat() ? drift * kAmplitude : 1e-10;
    ASSERT_NEAR(energyOf(sim), h0, energy_tol) << "step " << n;
    ASSERT_NEAR(sim.positions()(0, 0), kAmplitude * std::cos(n * theta), x_tol) << "step " << n;
  }
}

// The energy range over which a ratio of consecutive energies is compared: float's exponent
// ends near 1e+-38, and the reductions square positions, so the float runs stop at 1e+-25
// (positions near 1e+-12); double's at 1e+-250.
double energyRangeExponent(const BackendUnderTest& backend) { return backend.isFloat() ? 25.0 : 250.0; }

// BE multiplies the energy by 1/(1 + (omega h)^2) every step. Each ratio of two consecutive
// energies carries the round-off of both evaluations and of one step: float 16 a u (measured at
// most 40 u at omega h = 0.05, a = 21, and 15 u at omega h = 0.3, a = 4.3).
/// Tolerance of a ratio of consecutive energies (see above).
double ratioTolerance(const BackendUnderTest& backend, double omega_h) {
  return backend.isFloat() ? 16.0 * (1.0 + 1.0 / omega_h) * backend.unitRoundoff() : 1e-11;
}

TEST_P(OscillatorTest, BackwardEulerLosesEnergyByClosedFormFactor) {
  Simulator sim = makeOscillator(backend(), Integrator::BackwardEuler, omegaH());
  const double factor = 1.0 / (1.0 + omegaH() * omegaH());
  const double tol = ratioTolerance(backend(), omegaH());
  const double floor = std::pow(10.0, -energyRangeExponent(backend()));
  double previous = energyOf(sim);
  for (int n = 1; n <= 100 && previous > floor; ++n) {
    sim.step();
    ASSERT_NEAR(energyOf(sim) / previous, factor, tol) << "step " << n;
    previous = energyOf(sim);
  }
}

// FE multiplies the energy by 1 + (omega h)^2 every step (the tolerance of BE's, relative; FE
// forms no difference quotient, measured at most 5 u).
TEST_P(OscillatorTest, ForwardEulerGainsEnergyByClosedFormFactor) {
  Simulator sim = makeOscillator(backend(), Integrator::ForwardEuler, omegaH());
  const double factor = 1.0 + omegaH() * omegaH();
  const double tol = ratioTolerance(backend(), omegaH());
  const double ceiling = std::pow(10.0, energyRangeExponent(backend()));
  double previous = energyOf(sim);
  for (int n = 1; n <= 100 && previous < ceiling; ++n) {
    sim.step();
    ASSERT_NEAR(energyOf(sim) / previous, factor, tol * factor) << "step " << n;
    previous = energyOf(sim);
  }
}

// For omega h < 2, SE conserves the modified energy 1/2 m v^2 + 1/2 k x^2 - 1/2 h k x v (its
// shadow Hamiltonian for this system), so the true energy stays bounded by
// H0 / (1 - omega h / 2) for all time. That bound is also the scale of the state, hence of
// float's round-off; SE forms no difference quotient, so the drift is (10 + 4 n) u of it
// (measured: the shadow energy within 26 u, the energy above the bound by at most 110 u).
// Horizon: 2000 steps on the CPU, 500 on OpenCL (about 0.4 ms per step of launch overhead on
// PoCL; still four periods at omega h = 0.05).
TEST_P(SymplecticStableTest, SymplecticEulerIsBoundedBelowTheStabilityLimit) {
  const double omega_h = omegaH();
  Simulator sim = makeOscillator(backend(), Integrator::SymplecticEuler, omega_h);
  const double h0 = energyOf(sim);
  const double bound = h0 / (1.0 - 0.5 * omega_h);
  const double h = sim.options().time_step;
  auto shadow = [&] {
    const double x = sim.positions()(0, 0), v = sim.velocities()(0, 0);
    return 0.5 * kMass * v * v + 0.5 * kStiffness * x * x - 0.5 * h * kStiffness * x * v;
  };
  const double shadow0 = shadow();
  const int steps = backend().kind == BackendKind::OpenCL ? 500 : 2000;
  for (int n = 1; n <= steps; ++n) {
    sim.step();
    const double drift = (10.0 + 4.0 * n) * backend().unitRoundoff();
    const double shadow_tol = backend().isFloat() ? drift * bound : 1e-9 * h0;
    const double bound_tol = backend().isFloat() ? drift * bound : 1e-12 * bound;
    ASSERT_NEAR(shadow(), shadow0, shadow_tol) << "step " << n;
    ASSERT_LE(energyOf(sim), bound + bound_tol) << "step " << n;
  }
}

std::string oscillatorName(const ::testing::TestParamInfo<std::tuple<BackendUnderTest, double>>& info) {
  std::ostringstream printed;
  printed << std::get<1>(info.param);  // "0.05", "1"
  std::string omega_h = printed.str();
  for (char& c : omega_h)
    if (c == '.') c = '_';
  return std::get<0>(info.param).name() + "_omega_h_" + omega_h;
}

const auto kOmegaH = ::testing::Values(0.05, 0.3, 1.0, 1.9, 3.0);
const auto kStableOmegaH = ::testing::Values(0.05, 0.3, 1.0, 1.9);
const auto kOpenCL = ::testing::Values(testing::kOpenCLDouble, testing::kOpenCLFloat);
INSTANTIATE_TEST_SUITE_P(Cpu, OscillatorTest, ::testing::Combine(::testing::Values(testing::kCpuReference), kOmegaH),
                         oscillatorName);
INSTANTIATE_TEST_SUITE_P(OpenCL, OscillatorTest, ::testing::Combine(kOpenCL, kOmegaH), oscillatorName);
INSTANTIATE_TEST_SUITE_P(Cpu, SymplecticStableTest,
                         ::testing::Combine(::testing::Values(testing::kCpuReference), kStableOmegaH), oscillatorName);
INSTANTIATE_TEST_SUITE_P(OpenCL, SymplecticStableTest, ::testing::Combine(kOpenCL, kStableOmegaH), oscillatorName);

class Oscillator : public testing::BackendTest {};

// Above omega h = 2 the SE amplification matrix has an eigenvalue -4 (omega h = 2.5): the energy
// grows 16-fold per step until the state overflows, which the simulator reports as a refused
// step. Float overflows sooner: x = 0.3 * 4^n passes float's largest value near n = 64 and its
// square in the energy reduction near n = 32, so the float run checks the growth after 20 steps.
TEST_P(Oscillator, SymplecticEulerExplodesAboveTheStabilityLimitAndIsReported) {
  Simulator sim = makeOscillator(backend(), Integrator::SymplecticEuler, 2.5);
  const double h0 = energyOf(sim);
  const int growth_steps = backend().isFloat() ? 20 : 40;
  for (int n = 0; n < growth_steps; ++n) sim.step();
  EXPECT_GT(energyOf(sim), 1e6 * h0);
  int refused_at = -1;
  try {
    for (int n = 0; n < 5000; ++n) sim.step();
  } catch (const NonFiniteStateError& e) {
    refused_at = e.step();
    EXPECT_NE(std::string(e.what()).find("step refused"), std::string::npos) << e.what();
  }
  ASSERT_GE(refused_at, growth_steps);
  // The refused step left the last finite state in place.
  EXPECT_EQ(sim.stepCount(), refused_at);
  EXPECT_TRUE(sim.positions().allFinite());
  EXPECT_TRUE(sim.velocities().allFinite());
  EXPECT_THROW(sim.step(), NonFiniteStateError);
}

// The blend on a linear system: IM is exact, so it is accepted every step with alpha = 0 and
// H* never moves. The energy tolerance is IM's above.
TEST_P(Oscillator, BlendAcceptsImplicitMidpointOnALinearSystem) {
  Simulator sim = makeOscillator(backend(), Integrator::EnergyBlend, 1.0);
  const double h0 = energyOf(sim);
  for (int n = 1; n <= 200; ++n) {
    const StepReport& r = sim.step();
    ASSERT_EQ(r.branch, BlendBranch::ImplicitMidpoint);
    ASSERT_EQ(r.alpha, 0.0);
    ASSERT_NEAR(r.energy.total(), h0, backend().isFloat() ? floatDrift(backend(), n, 1.0) * h0 : 1e-12 * h0);
    ASSERT_EQ(r.target, h0);
  }
}

STABINT_ON_EVERY_BACKEND(Oscillator);

}  // namespace
}  // namespace stabint
