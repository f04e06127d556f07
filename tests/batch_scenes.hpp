#pragma once
// The scenes of the batch tests (tests/test_scene_batch.cpp, test_batch_contact.cpp,
// test_opencl_batch.cpp): the mixed scenes (every element type but contact, pins, a
// time-dependent force field and a damped body), the contact scenes (colliders of different
// scenes in the same space); the comparison of a batch with each scene's own Simulator; and
// where each element type lies in a segment.
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/scene.hpp>
#include <stabint/simulator.hpp>

#include "contact_scenes.hpp"

#include "elements/element_type.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace stabint::testing {

/// Four scenes covering every element type but contact: springs and a pin (chain, with a
/// time-dependent force field on "all particles"), springs with a damped body (cloth), tets with
/// pins (bar), triangle strain and bending hinges (triangle cloth).
inline std::vector<Scene> mixedBatchScenes() {
  ChainPendulumParams chain;
  chain.particles = 8;
  Scene a = makeChainPendulum(chain);
  ForceField wind;
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.01);
  wind.rate = Eigen::Vector3d(0.02, 0.0, 0.0);
  a.force_fields.push_back(wind);

  ClothGridParams cloth;
  cloth.nx = 6;
  cloth.ny = 5;
  cloth.damping = 0.1;
  const Scene b = makeClothGrid(cloth);

  TetBarParams bar;
  bar.nx = 3;
  bar.ny = 1;
  bar.nz = 1;
  const Scene c = makeTetBar(bar);

  ClothGridParams triangles;
  triangles.nx = 5;
  triangles.ny = 4;
  triangles.model = ClothModel::Triangles;
  const Scene d = makeClothGrid(triangles);
  return {a, b, c, d};
}

/// Three scenes in the same space whose colliders must keep to their own scene: a cloth dropped
/// onto every collider shape (friction, a moving box: clothOnColliders); a cloth without colliders
/// falling through all of them; a bar sliding (1 m/s along x, friction 0.5) on its own ground at
/// y = 0.2, a plane the first cloth's edges fall through on their way to its ground at -0.25.
inline std::vector<Scene> contactBatchScenes() {
  Scene free_bar = makeTetBar([] {
    TetBarParams bar;
    bar.nx = 4;
    bar.ny = 1;
    bar.nz = 1;
    return bar;
  }());
  free_bar.pins.clear();
  free_bar.positions.col(1).array() += 0.35 - free_bar.positions.col(1).minCoeff();
  free_bar.velocities.col(0).setConstant(1.0);
  free_bar.colliders.push_back(groundPlane(0.2, 1e4, 0.5));
  return {clothOnColliders(), horizontalCloth(8, 0.4), free_bar};
}

/// A scene's batch step report against its own Simulator's: the same branch, step, time and
/// iterations, alpha and velocity scale to 1e-9, the energies, target and the energy booked in
/// the step (forcing, damping, events, friction, the contact projection) to 1e-12 of the scene's
/// energy scale `scale` (the state's round-off: the factor's ordering may differ).
inline void expectSameReport(const StepReport& got, const StepReport& own, double scale, const std::string& where) {
  EXPECT_EQ(got.branch, own.branch) << where;
  EXPECT_EQ(got.step, own.step) << where;
  EXPECT_EQ(got.time, own.time) << where;
  EXPECT_EQ(got.iterations, own.iterations) << where;
  EXPECT_NEAR(got.alpha, own.alpha, 1e-9) << where;
  EXPECT_NEAR(got.velocity_scale, own.velocity_scale, 1e-9) << where;
  EXPECT_NEAR(got.forcing, own.forcing, 1e-12 * scale) << where;
  EXPECT_NEAR(got.damping, own.damping, 1e-12 * scale) << where;
  EXPECT_NEAR(got.event_energy, own.event_energy, 1e-12 * scale) << where;
  EXPECT_NEAR(got.friction, own.friction, 1e-12 * scale) << where;
  EXPECT_NEAR(got.contact_projection, own.contact_projection, 1e-12 * scale) << where;
  EXPECT_NEAR(got.target, own.target, 1e-12 * scale) << where;
  EXPECT_NEAR(got.energy.kinetic, own.energy.kinetic, 1e-12 * scale) << where;
  EXPECT_NEAR(got.energy.elastic, own.energy.elastic, 1e-12 * scale) << where;
  EXPECT_NEAR(got.energy.external, own.energy.external, 1e-12 * scale) << where;
}

/// A scene's batch state (x, v) against its own Simulator's, to the round-off of the factor's
/// ordering: 1e-9 of the scene's size, velocities of size / h.
inline void expectSameState(const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v, const Simulator& own,
                            const std::string& where) {
  // The factor's ordering of a block may differ from the scene alone's (round-off, see the premise).
  const Eigen::MatrixX3d& x0 = own.scene().positions;
  const double size = (x0.colwise().maxCoeff() - x0.colwise().minCoeff()).norm();
  const double speed = own.velocities().cwiseAbs().maxCoeff();
  EXPECT_LE((x - own.positions()).cwiseAbs().maxCoeff(), 1e-9 * size) << where;
  EXPECT_LE((v - own.velocities()).cwiseAbs().maxCoeff(), 1e-9 * (speed + size / own.options().time_step)) << where;
}

/// One batch step against one step of each scene's own Simulator (`alone`, in the batch's order):
/// no refusal, every scene's report and state its own's (expectSameReport, expectSameState);
/// `when` names the step in messages. Returns the batch's report.
inline const BatchStepReport& stepAndExpectSame(BatchSimulator& batch, std::vector<Simulator>& alone,
                                                const std::string& when) {
  const BatchStepReport& report = batch.step();
  for (std::size_t s = 0; s < alone.size(); ++s) {
    const StepReport& own = alone[s].step();
    const std::string where = "scene " + std::to_string(s) + " " + when;
    EXPECT_TRUE(report.refusals[s].empty()) << where << ": " << report.refusals[s];
    expectSameReport(report.scenes[s], own, alone[s].energyScale(), where);
    expectSameState(batch.positions(int(s)), batch.velocities(int(s)), alone[s], where);
  }
  return report;
}

/// setState(scene, x, v) in the batch and in that scene's own Simulator: an event of that scene
/// only, its target and energy moved as its own Simulator's, the other scenes' targets unmoved.
inline void setStateInBoth(BatchSimulator& batch, std::vector<Simulator>& alone, int scene, const Eigen::MatrixX3d& x,
                           const Eigen::MatrixX3d& v) {
  std::vector<double> before;
  for (int s = 0; s < batch.size(); ++s) before.push_back(batch.target(s));
  batch.setState(scene, x, v);
  alone[std::size_t(scene)].setState(x, v);
  for (int s = 0; s < batch.size(); ++s) {
    const Simulator& own = alone[std::size_t(s)];
    if (s != scene) {
      EXPECT_EQ(batch.target(s), before[std::size_t(s)]) << "scene " << s;
      continue;
    }
    EXPECT_NE(batch.target(s), before[std::size_t(s)]);
    EXPECT_NEAR(batch.target(s), own.target(), 1e-12 * own.energyScale());
    EXPECT_NEAR(batch.energy(s).elastic, own.energy().elastic, 1e-12 * own.energyScale());
    EXPECT_NEAR(batch.energy(s).kinetic, own.energy().kinetic, 1e-12 * own.energyScale());
  }
}

/// Element changes of the mixed scenes (mixedBatchScenes) before one step, as a frame of a game
/// gives them: the bar's tets softened, a chain spring stiffened, the chain's pin moved and
/// forces on the chain and the cloth, a second
/// change of the bar (a tet disabled), 70 cloth springs stiffened (past the factor's update price:
/// a refactorization) and the triangle cloth's hinges disabled. With `read_after_each` each
/// change's event is read (target()) right after it, which books it there; without, the events
/// wait for the step, but the bar's second change books its first.
inline void changeElementsOfSeveralScenes(BatchSimulator& batch, const std::vector<Scene>& scenes,
                                          bool read_after_each) {
  auto read = [&](int s) {
    if (read_after_each) (void)batch.target(s);
  };
  batch.setElementStiffness(2, ElementKind::Tet, std::vector<int>{0, 1, 2}, 0.5 * scenes[2].tets[0].stiffness);
  read(2);
  batch.setElementStiffness(0, ElementKind::Spring, 1, 3.0 * scenes[0].springs[1].stiffness);
  read(0);
  // Ramps that start at this time leave the potential there as it was: the chain's unsettled
  // event is booked after them as before them.
  batch.setPinTarget(0, 0, batch.pinTarget(0, 0) + Eigen::Vector3d(0.01, 0.0, 0.0));
  batch.setExternalForces(0, Eigen::MatrixX3d::Constant(scenes[0].numParticles(), 3, -0.001));
  batch.setExternalForces(1, Eigen::MatrixX3d::Constant(scenes[1].numParticles(), 3, 0.002));
  batch.setElementEnabled(2, ElementKind::Tet, 1, false);
  read(2);
  std::vector<int> springs;
  for (int i = 0; i < 70 && i < int(scenes[1].springs.size()); ++i) springs.push_back(i);
  batch.setElementStiffness(1, ElementKind::Spring, springs, 2.0 * scenes[1].springs[0].stiffness);
  read(1);
  std::vector<int> hinges;
  for (int i = 0; i < int(scenes[3].bending_hinges.size()); i += 2) hinges.push_back(i);
  batch.setElementEnabled(3, ElementKind::BendingHinge, hinges, false);
  read(3);
}

/// Position of the element type `identifier` in elementTypes() (the per-type ranges of a segment).
inline int typeIndex(const char* identifier) {
  const std::vector<const ElementType*>& types = elementTypes();
  for (std::size_t i = 0; i < types.size(); ++i)
    if (std::string(types[i]->identifier()) == identifier) return static_cast<int>(i);
  ADD_FAILURE() << "no element type " << identifier;
  return 0;
}

}  // namespace stabint::testing
