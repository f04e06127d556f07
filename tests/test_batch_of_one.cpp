// A batch of one scene is that scene's Simulator, bit for bit: the same states and the same step
// reports over many steps, for every integrator and the two per-scene solvers, on every element
// type, pins, force fields, damping and colliders. This is the check that keeps the two drivers
// from drifting apart (docs/batch_design.md, "The single-scene overhead") and the ground for a
// Simulator that is a batch of one.
#include <stabint/batch.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"

#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

namespace stabint {
namespace {

// Every field of the report, exactly (the timing phases aside). energy_evaluations counts the
// batched passes (BatchStepReport), which a batch of one takes where its Simulator does.
void expectSameReport(const StepReport& b, const StepReport& s, const std::string& where) {
  EXPECT_EQ(b.step, s.step) << where;
  EXPECT_EQ(b.time, s.time) << where;
  EXPECT_EQ(b.energy.kinetic, s.energy.kinetic) << where;
  EXPECT_EQ(b.energy.elastic, s.energy.elastic) << where;
  EXPECT_EQ(b.energy.external, s.energy.external) << where;
  EXPECT_EQ(b.target, s.target) << where;
  EXPECT_EQ(b.forcing, s.forcing) << where;
  EXPECT_EQ(b.damping, s.damping) << where;
  EXPECT_EQ(b.branch, s.branch) << where;
  EXPECT_EQ(b.alpha, s.alpha) << where;
  EXPECT_EQ(b.velocity_scale, s.velocity_scale) << where;
  EXPECT_EQ(b.iterations, s.iterations) << where;
  EXPECT_EQ(b.event_energy, s.event_energy) << where;
  EXPECT_EQ(b.friction, s.friction) << where;
  EXPECT_EQ(b.contact_projection, s.contact_projection) << where;
  EXPECT_EQ(b.energy_evaluations, s.energy_evaluations) << where;
}

// Every scene of the batch tests, each stepped `steps` times alone and as a batch of one.
void expectBatchOfOneIsItsSimulator(const SimulatorOptions& o, int steps, const std::string& label) {
  std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (const Scene& s : testing::contactBatchScenes()) scenes.push_back(s);
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    Simulator alone(scenes[k], o);
    BatchSimulator batch({scenes[k]}, o);
    for (int n = 0; n < steps; ++n) {
      const std::string where = label + "scene " + std::to_string(k) + ", step " + std::to_string(n);
      const StepReport own = alone.step();
      const BatchStepReport& b = batch.step();
      ASSERT_EQ(b.refusals[0], "") << where;
      expectSameReport(b.scenes[0], own, where);
      ASSERT_TRUE(batch.positions(0) == alone.positions()) << where;
      ASSERT_TRUE(batch.velocities(0) == alone.velocities()) << where;
    }
  }
}

using Case = std::tuple<Integrator, Acceleration>;

class BatchOfOne : public ::testing::TestWithParam<Case> {};

TEST_P(BatchOfOne, StepsAsItsSimulatorBitForBit) {
  const auto [integrator, acceleration] = GetParam();
  SimulatorOptions o;
  o.integrator = integrator;
  o.acceleration = acceleration;
  expectBatchOfOneIsItsSimulator(o, 40, "");
}

// Every solver option: a batch of one takes them, as its Simulator does, bit for bit.
class BatchOfOneSolver : public ::testing::TestWithParam<std::tuple<Integrator, int>> {};

TEST_P(BatchOfOneSolver, TakesTheCouplingOptionsAsItsSimulator) {
  const auto [integrator, variant] = GetParam();
  SimulatorOptions o;
  o.integrator = integrator;
  switch (variant) {
    case 0: o.acceleration = Acceleration::Chebyshev; break;
    case 1: o.acceleration = Acceleration::Anderson; break;
    case 2: o.acceleration = Acceleration::Newton; break;
    case 3:
      o.tolerance = 1e-6;
      o.acceleration = Acceleration::None;
      break;
    case 4: o.gradient_tolerance = 1e-2; break;
    case 5:
      o.global_solve = GlobalSolve::ConjugateGradient;
      o.acceleration = Acceleration::None;
      break;
    case 6:
      o.global_solve = GlobalSolve::ConjugateGradient;
      o.cg_tolerance = 1e-8;
      break;
  }
  expectBatchOfOneIsItsSimulator(o, 30, "variant " + std::to_string(variant) + ", ");
}

INSTANTIATE_TEST_SUITE_P(Options, BatchOfOneSolver,
                         ::testing::Combine(::testing::Values(Integrator::BackwardEuler, Integrator::BDF2,
                                                              Integrator::ImplicitMidpoint, Integrator::EnergyBlend),
                                            ::testing::Range(0, 7)));

// setState restarts BDF2 with a BE step in a batch of one, as in its Simulator (a batch of more
// than one refuses it: its scenes share one history).
TEST(BatchOfOne, SetStateRestartsBdf2AsItsSimulator) {
  SimulatorOptions o;
  o.integrator = Integrator::BDF2;
  const Scene scene = testing::mixedBatchScenes()[1];
  Simulator alone(scene, o);
  BatchSimulator batch({scene}, o);
  for (int n = 0; n < 30; ++n) {
    const std::string where = "step " + std::to_string(n);
    if (n == 12) {
      const Eigen::MatrixX3d x = alone.positions() * 0.999, v = alone.velocities() * 1.5;
      alone.setState(x, v);
      batch.setState(0, x, v);
    }
    const StepReport own = alone.step();
    expectSameReport(batch.step().scenes[0], own, where);
    ASSERT_TRUE(batch.positions(0) == alone.positions()) << where;
    ASSERT_TRUE(batch.velocities(0) == alone.velocities()) << where;
  }
  BatchSimulator two({scene, scene}, o);
  two.step();
  EXPECT_THROW(two.setState(1, scene.positions, scene.velocities), InvalidInputError);
}

INSTANTIATE_TEST_SUITE_P(Integrators, BatchOfOne,
                         ::testing::Combine(::testing::Values(Integrator::BackwardEuler, Integrator::BDF2,
                                                              Integrator::ImplicitMidpoint, Integrator::EnergyBlend),
                                            ::testing::Values(Acceleration::None, Acceleration::LBFGS)));

}  // namespace
}  // namespace stabint
