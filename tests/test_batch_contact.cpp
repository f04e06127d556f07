// Colliders in a batch (docs/batch_design.md, "Colliders"): each scene's colliders act on its own
// particles only, wherever the scenes lie in space, and every scene's contact set, friction and
// final projection are its own Simulator's, booked in its own target.
#include <stabint/batch.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"
#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "scene/scene_batch.hpp"
#include "scene/scene_data.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::contactBatchScenes;
using testing::expectSameReport;
using testing::expectSameState;
using testing::setStateInBoth;
using testing::stepAndExpectSame;

// The concatenation gives each collider its scene's particles, and the contact elements of a
// scene are its own pairs (collider by collider, its particles in order), shifted.
TEST(SceneBatchContact, EachCollidersParticlesAreItsScenes) {
  const std::vector<Scene> scenes = contactBatchScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  const ElementBlock all = contactElementType().build(batch.scene);
  const SceneData batch_data(batch.scene);
  const int contact = testing::typeIndex("contact");
  int colliders = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const SceneSegment& seg = batch.segments[s];
    EXPECT_EQ(seg.first_collider, colliders);
    EXPECT_EQ(seg.num_colliders, int(scenes[s].colliders.size()));
    for (int c = seg.first_collider; c < seg.first_collider + seg.num_colliders; ++c) {
      const IndexRange particles = colliderParticles(batch.scene, c);
      EXPECT_EQ(particles.first, seg.first_particle) << "collider " << c;
      EXPECT_EQ(particles.count, seg.num_particles) << "collider " << c;
    }
    const ElementBlock own = contactElementType().build(scenes[s]);
    const SceneData own_data(scenes[s]);
    ASSERT_EQ(seg.num_elements[std::size_t(contact)], own.count);
    for (int e = 0; e < own.count; ++e) {
      const int in_batch = seg.first_element[std::size_t(contact)] + e;
      EXPECT_EQ(all.vertices[std::size_t(in_batch)], own.vertices[std::size_t(e)] + seg.first_particle);
      // w_j, from the scene's own elements (Collider::elastic_ratio): the batch's is its scene's.
      EXPECT_EQ(batch_data.enabledWeight(contact, in_batch), own_data.enabledWeight(contact, e));
      EXPECT_GT(own_data.enabledWeight(contact, e), scenes[s].colliders[0].stiffness * scenes[s].masses.minCoeff());
    }
    colliders += seg.num_colliders;
  }
  // Not every collider against every particle: only the scenes' own pairs.
  EXPECT_EQ(all.count, 4 * scenes[0].numParticles() + 1 * scenes[2].numParticles());
}

SimulatorOptions contactOptions(Integrator integrator) {
  SimulatorOptions options;
  options.integrator = integrator;
  options.time_step = 1.0 / 60.0;
  options.iterations = 5;
  return options;
}

class BatchSimulatorContact : public ::testing::TestWithParam<Integrator> {};

// Every scene of the contact batch steps as its own Simulator (the batch's standard: the same
// branches and iterations, energies, target, friction and projection to 1e-12 of the scene's
// energy scale, states to the factor ordering's round-off), for one second in which the cloth
// without colliders falls through the first cloth's sphere, box, capsule and ground, and the first
// cloth's edges through the bar's ground: a collider acting on another scene's particles would
// change that scene's motion by centimetres.
TEST_P(BatchSimulatorContact, EveryScenesContactIsItsOwnSimulators) {
  const std::vector<Scene> scenes = contactBatchScenes();
  const SimulatorOptions options = contactOptions(GetParam());
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  std::vector<double> friction(scenes.size(), 0.0);
  double lowest_first_cloth = 1.0;
  for (int step = 0; step < 60; ++step) {
    const BatchStepReport& report = stepAndExpectSame(batch, alone, "step " + std::to_string(step));
    for (std::size_t s = 0; s < scenes.size(); ++s) friction[s] += report.scenes[s].friction;
    lowest_first_cloth = std::min(lowest_first_cloth, batch.positions(0).col(1).minCoeff());
  }
  // Contact happened and was compared: the cloth and the bar rubbed on their colliders.
  EXPECT_GT(friction[0], 0.0);
  EXPECT_GT(friction[2], 0.0);
  EXPECT_EQ(friction[1], 0.0);
  // The scenes crossed each other's colliders: the free cloth fell below the first cloth's ground,
  // the first cloth's edges below the bar's.
  EXPECT_LT(batch.positions(1).col(1).maxCoeff(), scenes[0].colliders[1].center.y());
  EXPECT_LT(lowest_first_cloth, scenes[2].colliders[0].center.y());
}

INSTANTIATE_TEST_SUITE_P(Integrators, BatchSimulatorContact,
                         ::testing::Values(Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint,
                                           Integrator::EnergyBlend),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                           return std::string(integratorName(info.param));
                         });

// With contact pairs leaving within the solve (SimulatorOptions::contact_release) every scene of
// the contact batch still steps as its own Simulator: each scene's pairs leave and return by its
// own iterates, and a change in one scene restarts nothing in the others.
TEST_P(BatchSimulatorContact, ReleasedPairsAreEachScenesOwn) {
  const std::vector<Scene> scenes = contactBatchScenes();
  SimulatorOptions options = contactOptions(GetParam());
  options.contact_release = 1;
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  options.contact_release = 0;
  BatchSimulator keeping(scenes, options);
  for (int step = 0; step < 60; ++step) {
    stepAndExpectSame(batch, alone, "step " + std::to_string(step));
    keeping.step();
  }
  // Pairs did leave: the first cloth, which lands on its ground and sphere, moved otherwise than
  // with each step's set kept.
  EXPECT_NE(batch.positions(0), keeping.positions(0));
}

// setState books a scene's contact energy as its own Simulator does: its contact set follows the
// new positions (here pushed into its ground), and the event is booked in its target only.
TEST(BatchSimulatorContact, SetStateIntoAColliderIsAnEventOfOneScene) {
  const std::vector<Scene> scenes = contactBatchScenes();
  const SimulatorOptions options = contactOptions(Integrator::EnergyBlend);
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  for (int step = 0; step < 5; ++step) {
    batch.step();
    for (Simulator& sim : alone) sim.step();
  }
  const int moved = 2;  // the bar, 2 cm into its ground
  Eigen::MatrixX3d x = alone[moved].positions();
  x.col(1).array() += scenes[moved].colliders[0].center.y() - 0.02 - x.col(1).minCoeff();
  const Eigen::MatrixX3d v = alone[moved].velocities();
  const double elastic_before = batch.energy(moved).elastic;
  setStateInBoth(batch, alone, moved, x, v);
  // The event holds the contact energy of the pairs that entered inside: the bar moved rigidly,
  // so its own elastic energy did not change, and its bottom particles' w_j/2 (2 cm)^2 is tens
  // of joules.
  EXPECT_GT(batch.energy(moved).elastic - elastic_before, 1.0);
  for (int step = 0; step < 20; ++step) stepAndExpectSame(batch, alone, "step " + std::to_string(step));
}

// With an energy ceiling below what contact adds, scenes are refused at the steps their own
// Simulators refuse, with their messages, and the others step on; a refused scene is left alone:
// its state and target stay its own Simulator's after the refusal (its colliders, its friction and
// its projection do not touch it, nor does the broad phase of the others).
TEST(BatchSimulatorContact, RefusalsArePerSceneAndLeaveTheSceneAlone) {
  const std::vector<Scene> scenes = contactBatchScenes();
  SimulatorOptions options = contactOptions(Integrator::EnergyBlend);
  options.energy_limit = 1e-7;
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  std::vector<bool> refused(scenes.size(), false);
  for (int step = 0; step < 40; ++step) {
    const BatchStepReport& report = batch.step();
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const std::string where = "scene " + std::to_string(s) + " step " + std::to_string(step);
      if (!refused[s]) {
        try {
          const StepReport& own = alone[s].step();
          EXPECT_TRUE(report.refusals[s].empty()) << where << ": " << report.refusals[s];
          expectSameReport(report.scenes[s], own, alone[s].energyScale(), where);
        } catch (const EnergyLimitError& e) {
          EXPECT_EQ(report.refusals[s], e.what()) << where;
          refused[s] = true;
        }
      }
      EXPECT_EQ(batch.active(int(s)), !refused[s]) << where;
      EXPECT_EQ(batch.stepCount(int(s)), alone[s].stepCount()) << where;
      EXPECT_NEAR(batch.target(int(s)), alone[s].target(), 1e-12 * alone[s].energyScale()) << where;
      expectSameState(batch.positions(int(s)), batch.velocities(int(s)), alone[s], where);
    }
  }
  int refused_scenes = 0;
  for (bool r : refused) refused_scenes += r ? 1 : 0;
  EXPECT_GT(refused_scenes, 0);
  EXPECT_LT(refused_scenes, int(scenes.size()));
}

}  // namespace
}  // namespace stabint
