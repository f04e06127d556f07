// Event scripts on one scene of a batch (EventScript::apply(BatchSimulator&, int),
// include/stabint/events.hpp): the scene follows its own Simulator playing the same script, to the
// batch tests' standard (batch_scenes.hpp: states to 1e-9 of the scene's size, energies to 1e-12 of
// E_scale: the factor's ordering and updates); the other scenes step bit for bit as in a batch
// without the script. For the latter both batches start from a factor that has had one update
// (a grab and release in another scene, the same in both): cholmod_updown turns the batch's whole
// factor from LL' into LDL' at its first update, which moves every scene by round-off
// (docs/batch_design.md, "Per-scene input"); after that an update of one scene's block touches
// that block's columns only, so the difference a script makes stays in its scene.
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/events.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::expectSameReport;
using testing::expectSameState;

SimulatorOptions eventOptions(Integrator integrator) {
  SimulatorOptions options;
  options.integrator = integrator;
  options.time_step = 1.0 / 60.0;
  options.iterations = 5;
  return options;
}

// A free soft chain, the cloth falling onto the sphere, ground, box and capsule (the script's
// scene), the tet bar with its pinned end.
std::vector<Scene> eventScenes() {
  ChainPendulumParams params;
  params.particles = 6;
  params.stiffness = 1e2;
  Scene chain = makeChainPendulum(params);
  chain.pins.clear();
  for (int j = 0; j < chain.numParticles(); ++j)
    for (int k = 0; k < 3; ++k) chain.velocities(j, k) = 0.5 * std::sin(1.3 * j - 0.7 * k);
  return {chain, testing::clothOnColliders(), testing::mixedBatchScenes()[2]};
}

// A grab dragged along a path and released, springs softened, the box dragged along a path, the
// ground set moving, and (but for BDF2, see BatchEvents.ImpulseWithBDF2IsRefused) an impulse.
EventScript script(const Scene& cloth, bool impulse) {
  const Eigen::Vector3d corner = cloth.positions.row(30).transpose();
  const Eigen::Vector3d box = cloth.colliders[2].center;
  std::vector<ScriptedEvent> events = {
      {2, GrabEvent{"hand", 30, 5e2, {PathKey{8, corner + Eigen::Vector3d(0.0, 0.1, 0.05)}}}},
      {4, ColliderEvent{2, {PathKey{10, box + Eigen::Vector3d(0.2, 0.05, 0.0)}, PathKey{14, box}}, std::nullopt}},
      {6, ElementEvent{ElementKind::Spring, {0, 1, 2, 3}, 20.0, std::nullopt}},
      {8, ColliderEvent{1, {}, Eigen::Vector3d(0.0, 0.05, 0.0)}},
      {12, ReleaseEvent{"hand", -1}},
      {13, ElementEvent{ElementKind::Spring, {5}, std::nullopt, false}},
  };
  if (impulse) events.push_back({16, ImpulseEvent{{40, 41, 52}, Eigen::Vector3d(0.0, 0.8, 0.3)}});
  return EventScript(events);
}

class BatchEvents : public ::testing::TestWithParam<Integrator> {};

TEST_P(BatchEvents, ScriptOnOneSceneFollowsItsSimulatorAndLeavesTheOthers) {
  const std::vector<Scene> scenes = eventScenes();
  const SimulatorOptions options = eventOptions(GetParam());
  const bool impulse = GetParam() != Integrator::BDF2;
  BatchSimulator batch(scenes, options), without(scenes, options);
  for (BatchSimulator* b : {&batch, &without}) b->release(2, b->grab(2, 3, 1e3));  // the factor's first update
  Simulator own(scenes[1], options);
  EventScript in_batch = script(scenes[1], impulse), alone = script(scenes[1], impulse);
  double events = 0.0;
  for (int frame = 0; frame < 25; ++frame) {
    const std::string where = "frame " + std::to_string(frame);
    in_batch.apply(batch, 1);
    alone.apply(own);
    EXPECT_EQ(in_batch.handlePin("hand"), alone.handlePin("hand")) << where;
    const BatchStepReport& report = batch.step();
    const BatchStepReport& plain = without.step();
    const StepReport& own_report = own.step();
    EXPECT_TRUE(report.refusals[1].empty()) << where << ": " << report.refusals[1];
    expectSameReport(report.scenes[1], own_report, own.energyScale(), where);
    expectSameState(batch.positions(1), batch.velocities(1), own, where);
    events += std::abs(report.scenes[1].event_energy);
    for (int s : {0, 2}) {
      EXPECT_TRUE(batch.positions(s) == without.positions(s)) << where << " scene " << s;
      EXPECT_TRUE(batch.velocities(s) == without.velocities(s)) << where << " scene " << s;
      EXPECT_EQ(batch.target(s), without.target(s)) << where << " scene " << s;
      EXPECT_EQ(report.scenes[std::size_t(s)].event_energy, 0.0) << where << " scene " << s;
      EXPECT_EQ(report.scenes[std::size_t(s)].energy.kinetic, plain.scenes[std::size_t(s)].energy.kinetic) << where;
    }
  }
  EXPECT_GT(events, 0.0);  // the grab's drag, the release, the springs and the impulse were events
  for (int c = 0; c < int(scenes[1].colliders.size()); ++c) {
    EXPECT_EQ(batch.colliderPosition(1, c), own.colliderPosition(c)) << "collider " << c;
    EXPECT_EQ(batch.colliderVelocity(1, c), own.colliderVelocity(c)) << "collider " << c;
  }
  EXPECT_FALSE(batch.elementEnabled(1, ElementKind::Spring, 5));
}

INSTANTIATE_TEST_SUITE_P(Integrators, BatchEvents,
                         ::testing::Values(Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint,
                                           Integrator::EnergyBlend),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                           return std::string(integratorName(info.param));
                         });

// An impulse is setState of the scene in a batch, which BDF2 refuses (its restart would be every
// scene's): the event is named, the batch's call and scene too, and the script goes on.
TEST(BatchEventsRefused, ImpulseWithBDF2AndBadScenesNameTheEvent) {
  const std::vector<Scene> scenes = eventScenes();
  BatchSimulator batch(scenes, eventOptions(Integrator::BDF2));
  EventScript push({{0, ImpulseEvent{{1}, Eigen::Vector3d::UnitY()}}});
  try {
    push.apply(batch, 0);
    ADD_FAILURE() << "the impulse was accepted";
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("event 0 (frame 0): setState: scene 0: BDF2"), std::string::npos) << what;
  }
  EXPECT_TRUE(batch.velocities(0) == scenes[0].velocities);
  EventScript far({{0, ImpulseEvent{{1000}, Eigen::Vector3d::UnitX()}}});
  try {
    far.apply(batch, 2);
    ADD_FAILURE() << "vertex 1000 was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("event 0 (frame 0): scene 2: impulse vertex 1000 out of range"),
              std::string::npos)
        << e.what();
  }
  EventScript grab({{0, GrabEvent{"", 1000, 1e2, {}}}});
  try {
    grab.apply(batch, 1);
    ADD_FAILURE() << "vertex 1000 was accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("event 0 (frame 0): grab: scene 1: "), std::string::npos) << e.what();
  }
  EXPECT_THROW(push.apply(batch, 3), InvalidInputError);
}

}  // namespace
}  // namespace stabint
