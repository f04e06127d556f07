// BDF2 starts with a backward-Euler step and is second order: on the linear oscillator (where
// one local/global iteration is exact) the error at a fixed time falls about 4x when h halves.
#include <stabint/stabint.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace stabint {
namespace {

TEST(BDF2, FirstStepIsBackwardEuler) {
  ClothGridParams p;
  p.nx = 6;
  p.ny = 6;
  const Scene s = makeClothGrid(p);
  SimulatorOptions o;
  o.integrator = Integrator::BDF2;
  Simulator bdf2(s, o);
  o.integrator = Integrator::BackwardEuler;
  Simulator be(s, o);
  bdf2.step();
  be.step();
  EXPECT_EQ(bdf2.positions(), be.positions());
  EXPECT_EQ(bdf2.velocities(), be.velocities());
  bdf2.step();
  be.step();
  EXPECT_GT((bdf2.positions() - be.positions()).norm(), 1e-9);  // from step 2 on it is not BE
}

double errorAtTimeOne(Integrator integrator, int steps) {
  const double mass = 1.0, stiffness = 4.0 * M_PI * M_PI;  // omega = 2 pi
  SimulatorOptions o;
  o.integrator = integrator;
  o.iterations = 1;
  o.time_step = 1.0 / steps;
  Simulator sim(makeLinearOscillator({mass, stiffness, 1.0}), o);
  for (int n = 0; n < steps; ++n) sim.step();
  const double omega = std::sqrt(stiffness / mass);
  return std::abs(sim.positions()(0, 0) - std::cos(omega * 1.0));
}

TEST(BDF2, IsSecondOrderOnTheOscillator) {
  for (int steps : {200, 400, 800}) {
    const double ratio = errorAtTimeOne(Integrator::BDF2, steps) / errorAtTimeOne(Integrator::BDF2, 2 * steps);
    // Second order: 4 asymptotically; the BE start adds an O(h^2) global term too, so allow 3.6-4.4.
    EXPECT_GT(ratio, 3.6) << steps;
    EXPECT_LT(ratio, 4.4) << steps;
  }
  // Contrast: BE is first order (ratio about 2).
  const double be_ratio = errorAtTimeOne(Integrator::BackwardEuler, 400) / errorAtTimeOne(Integrator::BackwardEuler, 800);
  EXPECT_NEAR(be_ratio, 2.0, 0.2);
}

}  // namespace
}  // namespace stabint
