// A refused step changes nothing (include/stabint/simulator.hpp): a Simulator is a batch of one
// (simulator.cpp), and where a batch's refused scene turns inactive while the batch's time and
// BDF2 history go on, a Simulator's refused step leaves its state, time, step count, BDF2
// history, H* and last report as they were, and it steps again.
#include <stabint/stabint.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

namespace stabint {
namespace {

// An oscillator of tiny mass stepped `steps` times, then pushed so hard that the next step's
// kinetic energy overflows (forces are not an event: BDF2 keeps its history). Plain iterations:
// L-BFGS's line search keeps such a solve finite.
Simulator pushedOscillator(Integrator integrator, int steps) {
  SimulatorOptions o;
  o.integrator = integrator;
  o.acceleration = Acceleration::None;
  Simulator sim(makeLinearOscillator({1e-20, 1e-20, 1.0}), o);
  for (int n = 0; n < steps; ++n) sim.step();
  sim.setExternalForces(Eigen::MatrixX3d::Constant(sim.positions().rows(), 3, 1e149));
  return sim;
}

TEST(SimulatorRefusal, ARefusedStepChangesNothingAndTheSimulatorStepsAgain) {
  for (Integrator integrator :
       {Integrator::BDF2, Integrator::BackwardEuler, Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
    SCOPED_TRACE(integratorName(integrator));
    Simulator sim = pushedOscillator(integrator, 3);
    const std::string before = sim.checkpoint().bytes();  // state, time, steps, H*, BDF2 history
    const StepReport last = sim.lastReport();
    for (int attempt = 0; attempt < 2; ++attempt) {
      try {
        sim.step();
        FAIL() << "the step was not refused";
      } catch (const NonFiniteStateError& e) {
        EXPECT_EQ(e.step(), 3);
        EXPECT_EQ(std::string(e.what()).find("scene 0"), std::string::npos) << e.what();
      }
      EXPECT_EQ(sim.checkpoint().bytes(), before);
      EXPECT_EQ(sim.stepCount(), 3);
      EXPECT_EQ(sim.lastReport().step, last.step);
      EXPECT_EQ(sim.lastReport().time, last.time);
      EXPECT_EQ(sim.lastReport().target, last.target);
    }
    // Without the push it steps on from where it was, as a Simulator that was never refused.
    Simulator fresh = pushedOscillator(integrator, 3);
    sim.setExternalForces(Eigen::MatrixX3d::Zero(sim.positions().rows(), 3));
    fresh.setExternalForces(Eigen::MatrixX3d::Zero(sim.positions().rows(), 3));
    sim.step();
    fresh.step();
    EXPECT_EQ(sim.stepCount(), 4);
    EXPECT_EQ(sim.positions(), fresh.positions());
    EXPECT_EQ(sim.velocities(), fresh.velocities());
    EXPECT_EQ(sim.target(), fresh.target());
  }
}

// A blow-up that stays finite: forward Euler on 1e9 N/m springs of 1 kg particles grows by about
// 10^3 a step and passes 1e150, the largest value setState and a checkpoint take, before it
// overflows. Such a step is refused like a non-finite one, so the last accepted state can be set,
// saved and restored (a checkpoint of a state beyond it could not be read back).
TEST(SimulatorRefusal, AStateBeyondTheInputLimitIsRefusedAndEveryAcceptedStateRestores) {
  Scene scene;
  scene.rest_positions = (Eigen::MatrixX3d(3, 3) << 0, 0, 0, 1, 0, 0, 2, 0, 0).finished();
  scene.positions = scene.rest_positions;
  scene.velocities = Eigen::MatrixX3d::Zero(3, 3);
  scene.masses = Eigen::VectorXd::Ones(3);
  scene.springs = {{0, 1, 1.0, 1e9}, {1, 2, 1.0, 1e9}};
  Pin pin;
  pin.vertex = 0;
  pin.stiffness = 1e9;
  scene.pins = {pin};
  SimulatorOptions o;
  o.integrator = Integrator::ForwardEuler;
  Simulator sim(scene, o);
  int accepted = 0;
  try {
    for (; accepted < 1000; ++accepted) sim.step();
    FAIL() << "forward Euler did not blow up";
  } catch (const NonFiniteStateError& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("beyond 1e+150 in magnitude"));
  }
  ASSERT_GT(accepted, 10);
  EXPECT_LE(sim.velocities().cwiseAbs().maxCoeff(), 1e150);
  EXPECT_LE(sim.positions().cwiseAbs().maxCoeff(), 1e150);
  const Checkpoint saved = sim.checkpoint();
  EXPECT_NO_THROW(Checkpoint::fromBytes(saved.bytes()));
  EXPECT_NO_THROW(sim.restore(saved));
  EXPECT_NO_THROW(sim.setState(sim.positions(), sim.velocities()));
  EXPECT_EQ(sim.checkpoint().bytes(), saved.bytes());
}

}  // namespace
}  // namespace stabint
