// Linear oscillator (docs/method.md section 9): one particle on a zero-rest-length spring (a pin) to
// the origin, omega^2 = k/m, no gravity. The local step's projection is the constant pin
// target, so one local/global iteration solves each implicit step exactly and every integrator
// must match its closed form to round-off.
#include <stabint/stabint.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace stabint {
namespace {

constexpr double kMass = 2.0;
constexpr double kStiffness = 50.0;  // omega = 5 rad/s

Simulator makeOscillator(Integrator integrator, double omega_h, int iterations = 1) {
  SimulatorOptions options;
  options.integrator = integrator;
  options.iterations = iterations;
  options.time_step = omega_h / std::sqrt(kStiffness / kMass);
  return Simulator(makeLinearOscillator({kMass, kStiffness, 0.3}), options);
}

double energyOf(const Simulator& sim) { return sim.energy().total(); }

class OscillatorTest : public ::testing::TestWithParam<double> {};

// IM is the Cayley transform of the oscillator: it conserves the quadratic energy exactly and
// rotates the phase (x, v/omega) by theta = 2 atan(omega h / 2) per step.
TEST_P(OscillatorTest, ImplicitMidpointKeepsEnergyAndRotatesPhase) {
  const double omega_h = GetParam();
  Simulator sim = makeOscillator(Integrator::ImplicitMidpoint, omega_h);
  const double h0 = energyOf(sim);
  const double theta = 2.0 * std::atan(0.5 * omega_h);
  for (int n = 1; n <= 300; ++n) {
    sim.step();
    ASSERT_NEAR(energyOf(sim), h0, 1e-12 * h0) << "step " << n;
    ASSERT_NEAR(sim.positions()(0, 0), 0.3 * std::cos(n * theta), 1e-10) << "step " << n;
  }
}

// BE multiplies the energy by 1/(1 + (omega h)^2) every step.
TEST_P(OscillatorTest, BackwardEulerLosesEnergyByClosedFormFactor) {
  const double omega_h = GetParam();
  Simulator sim = makeOscillator(Integrator::BackwardEuler, omega_h);
  const double factor = 1.0 / (1.0 + omega_h * omega_h);
  double previous = energyOf(sim);
  for (int n = 1; n <= 100 && previous > 1e-250; ++n) {
    sim.step();
    ASSERT_NEAR(energyOf(sim) / previous, factor, 1e-11) << "step " << n;
    previous = energyOf(sim);
  }
}

// FE multiplies the energy by 1 + (omega h)^2 every step.
TEST_P(OscillatorTest, ForwardEulerGainsEnergyByClosedFormFactor) {
  const double omega_h = GetParam();
  Simulator sim = makeOscillator(Integrator::ForwardEuler, omega_h);
  const double factor = 1.0 + omega_h * omega_h;
  double previous = energyOf(sim);
  for (int n = 1; n <= 100; ++n) {
    sim.step();
    ASSERT_NEAR(energyOf(sim) / previous, factor, 1e-11 * factor) << "step " << n;
    previous = energyOf(sim);
  }
}

// For omega h < 2, SE conserves the modified energy 1/2 m v^2 + 1/2 k x^2 - 1/2 h k x v (its
// shadow Hamiltonian for this system), so the true energy stays bounded by
// H0 / (1 - omega h / 2) for all time.
class SymplecticStableTest : public ::testing::TestWithParam<double> {};
TEST_P(SymplecticStableTest, SymplecticEulerIsBoundedBelowTheStabilityLimit) {
  const double omega_h = GetParam();
  Simulator sim = makeOscillator(Integrator::SymplecticEuler, omega_h);
  const double h0 = energyOf(sim);
  const double h = sim.options().time_step;
  auto shadow = [&] {
    const double x = sim.positions()(0, 0), v = sim.velocities()(0, 0);
    return 0.5 * kMass * v * v + 0.5 * kStiffness * x * x - 0.5 * h * kStiffness * x * v;
  };
  const double shadow0 = shadow();
  for (int n = 1; n <= 2000; ++n) {
    sim.step();
    ASSERT_NEAR(shadow(), shadow0, 1e-9 * h0) << "step " << n;
    ASSERT_LE(energyOf(sim), h0 / (1.0 - 0.5 * omega_h) * (1 + 1e-12)) << "step " << n;
  }
}

INSTANTIATE_TEST_SUITE_P(OmegaH, OscillatorTest, ::testing::Values(0.05, 0.3, 1.0, 1.9, 3.0));
INSTANTIATE_TEST_SUITE_P(OmegaH, SymplecticStableTest, ::testing::Values(0.05, 0.3, 1.0, 1.9));

// Above omega h = 2 the SE amplification matrix has an eigenvalue of modulus > 1: the energy
// grows geometrically until the state overflows, which the simulator reports as a refused step.
TEST(Oscillator, SymplecticEulerExplodesAboveTheStabilityLimitAndIsReported) {
  Simulator sim = makeOscillator(Integrator::SymplecticEuler, 2.5);
  const double h0 = energyOf(sim);
  for (int n = 0; n < 40; ++n) sim.step();
  EXPECT_GT(energyOf(sim), 1e6 * h0);
  int refused_at = -1;
  try {
    for (int n = 0; n < 5000; ++n) sim.step();
  } catch (const NonFiniteStateError& e) {
    refused_at = e.step();
    EXPECT_NE(std::string(e.what()).find("step refused"), std::string::npos) << e.what();
  }
  ASSERT_GE(refused_at, 40);
  // The refused step left the last finite state in place.
  EXPECT_EQ(sim.stepCount(), refused_at);
  EXPECT_TRUE(sim.positions().allFinite());
  EXPECT_TRUE(sim.velocities().allFinite());
  EXPECT_THROW(sim.step(), NonFiniteStateError);
}

// The blend on a linear system: IM is exact, so it is accepted every step with alpha = 0.
TEST(Oscillator, BlendAcceptsImplicitMidpointOnALinearSystem) {
  Simulator sim = makeOscillator(Integrator::EnergyBlend, 1.0);
  const double h0 = energyOf(sim);
  for (int n = 0; n < 200; ++n) {
    const StepReport& r = sim.step();
    ASSERT_EQ(r.branch, BlendBranch::ImplicitMidpoint);
    ASSERT_EQ(r.alpha, 0.0);
    ASSERT_NEAR(r.energy.total(), h0, 1e-12 * h0);
    ASSERT_EQ(r.target, h0);
  }
}

}  // namespace
}  // namespace stabint
