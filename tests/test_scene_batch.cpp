// Scene concatenation for the batched simulator (docs/batch_design.md, step 1): the segments say
// where each scene lies, and the concatenation, stepped by one Simulator, steps every scene as its
// own Simulator does (the premise of the batch: no element couples two scenes).
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "elements/element_type.hpp"
#include "scene/scene_batch.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace stabint {
namespace {

// Four scenes covering every element type but contact: springs and a pin (chain, with a
// time-dependent force field on "all particles"), springs with a damped body (cloth), tets
// (bar), triangle strain and bending hinges (triangle cloth).
std::vector<Scene> mixedScenes() {
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

int typeIndex(const char* identifier) {
  const std::vector<const ElementType*>& types = elementTypes();
  for (std::size_t i = 0; i < types.size(); ++i)
    if (std::string(types[i]->identifier()) == identifier) return static_cast<int>(i);
  ADD_FAILURE() << "no element type " << identifier;
  return 0;
}

TEST(SceneBatch, SegmentsLocateEveryScenesParticlesAndElements) {
  const std::vector<Scene> scenes = mixedScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  ASSERT_EQ(batch.segments.size(), scenes.size());
  const int spring = typeIndex("spring"), tet = typeIndex("tet"), pin = typeIndex("pin");
  int particles = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const SceneSegment& seg = batch.segments[s];
    const Scene& own = scenes[s];
    EXPECT_EQ(seg.first_particle, particles);
    EXPECT_EQ(seg.num_particles, own.numParticles());
    const int off = seg.first_particle;
    EXPECT_EQ(batch.scene.positions.middleRows(off, own.numParticles()), own.positions);
    EXPECT_EQ(batch.scene.masses.segment(off, own.numParticles()), own.masses);
    for (std::size_t i = 0; i < elementTypes().size(); ++i)
      EXPECT_EQ(seg.num_elements[i], elementTypes()[i]->count(own)) << elementTypes()[i]->name();
    ASSERT_EQ(seg.num_elements[static_cast<std::size_t>(spring)], static_cast<int>(own.springs.size()));
    for (std::size_t k = 0; k < own.springs.size(); ++k) {
      const Spring& got = batch.scene.springs[std::size_t(seg.first_element[std::size_t(spring)]) + k];
      EXPECT_EQ(got.a, own.springs[k].a + off);
      EXPECT_EQ(got.b, own.springs[k].b + off);
      EXPECT_EQ(got.stiffness, own.springs[k].stiffness);
    }
    for (std::size_t k = 0; k < own.tets.size(); ++k)
      for (int v = 0; v < 4; ++v)
        EXPECT_EQ(batch.scene.tets[std::size_t(seg.first_element[std::size_t(tet)]) + k].vertices[std::size_t(v)],
                  own.tets[k].vertices[std::size_t(v)] + off);
    for (std::size_t k = 0; k < own.pins.size(); ++k)
      EXPECT_EQ(batch.scene.pins[std::size_t(seg.first_element[std::size_t(pin)]) + k].vertex, own.pins[k].vertex + off);
    particles += own.numParticles();
  }
  EXPECT_EQ(batch.scene.numParticles(), particles);
  // The chain's field on "all particles" acts on the chain's particles only.
  ASSERT_EQ(batch.scene.force_fields.size(), 1u);
  EXPECT_EQ(batch.scene.force_fields[0].particles.size(), std::size_t(scenes[0].numParticles()));
  EXPECT_EQ(batch.scene.force_fields[0].particles.back(), scenes[0].numParticles() - 1);
  // Each scene's bodies (the builders make one per scene; the cloth's is damped) follow, shifted.
  ASSERT_EQ(batch.scene.bodies.size(), scenes.size());
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    ASSERT_EQ(scenes[s].bodies.size(), 1u);
    const Body& got = batch.scene.bodies[s];
    EXPECT_EQ(got.damping, scenes[s].bodies[0].damping);
    ASSERT_EQ(got.particles.size(), scenes[s].bodies[0].particles.size());
    for (std::size_t k = 0; k < got.particles.size(); ++k)
      EXPECT_EQ(got.particles[k], scenes[s].bodies[0].particles[k] + batch.segments[s].first_particle);
  }
}

TEST(SceneBatch, RefusesWhatItCannotKeepApartNamingTheScene) {
  EXPECT_THROW(concatenateScenes({}), InvalidInputError);
  std::vector<Scene> scenes = mixedScenes();
  scenes[2].gravity = Eigen::Vector3d(0.0, -1.0, 0.0);
  try {
    concatenateScenes(scenes);
    ADD_FAILURE() << "differing gravity accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene 2: gravity"), std::string::npos) << e.what();
  }
  scenes = mixedScenes();
  scenes[1].colliders.push_back(Collider{});
  try {
    concatenateScenes(scenes);
    ADD_FAILURE() << "a collider accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene 1: has colliders"), std::string::npos) << e.what();
  }
  scenes = mixedScenes();
  scenes[3].masses[0] = -1.0;
  try {
    concatenateScenes(scenes);
    ADD_FAILURE() << "a negative mass accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("scene 3: ", 0), 0u) << e.what();
  }
}

struct PremiseCase {
  Integrator integrator;
  double time_step;
  int steps;
};

class SceneBatchPremise : public ::testing::TestWithParam<PremiseCase> {};

// The concatenation stepped by one Simulator gives every scene its own Simulator's trajectory.
// Explicit (SE): bit for bit, since every per-vertex sum (forces, the gather) adds the scene's
// own terms in the same order. Implicit: the factor of the block-diagonal K_c orders each block as
// CHOLMOD orders the union, which need not be the order of the scene alone, so only agreement to
// round-off is guaranteed: about eps times the conditioning per solve, grown over the steps; 1e-9
// of the scene's size is far above that and far below any coupling (one element between two
// scenes would move them by millimetres in these steps). With these scenes AMD happens to order
// each block as alone and the trajectories were bit for bit (docs/batch_design.md).
TEST_P(SceneBatchPremise, EachSceneStepsAsItsOwnSimulator) {
  const PremiseCase c = GetParam();
  const std::vector<Scene> scenes = mixedScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  SimulatorOptions options;
  options.integrator = c.integrator;
  options.time_step = c.time_step;
  options.iterations = 5;
  Simulator together(batch.scene, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  for (int step = 0; step < c.steps; ++step) {
    together.step();
    for (Simulator& sim : alone) sim.step();
  }
  const bool explicit_method = c.integrator == Integrator::SymplecticEuler;
  double energy_sum = 0.0, energy_scale = 0.0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const SceneSegment& seg = batch.segments[s];
    const Eigen::MatrixX3d x = together.positions().middleRows(seg.first_particle, seg.num_particles);
    const Eigen::MatrixX3d v = together.velocities().middleRows(seg.first_particle, seg.num_particles);
    const Eigen::MatrixX3d& x_own = alone[s].positions();
    const Eigen::MatrixX3d& v_own = alone[s].velocities();
    // The scene really moved (so agreement is not two resting states).
    ASSERT_GT((x_own - scenes[s].positions).cwiseAbs().maxCoeff(), 1e-6) << "scene " << s;
    if (explicit_method) {
      EXPECT_EQ(x, x_own) << "scene " << s;
      EXPECT_EQ(v, v_own) << "scene " << s;
    } else {
      const double size = (scenes[s].positions.colwise().maxCoeff() - scenes[s].positions.colwise().minCoeff()).norm();
      const double speed = v_own.cwiseAbs().maxCoeff();
      EXPECT_LE((x - x_own).cwiseAbs().maxCoeff(), 1e-9 * size) << "scene " << s;
      EXPECT_LE((v - v_own).cwiseAbs().maxCoeff(), 1e-9 * (speed + size / c.time_step)) << "scene " << s;
    }
    const EnergyReport e = alone[s].energy();
    energy_sum += e.total();
    energy_scale += std::abs(e.kinetic) + std::abs(e.elastic) + std::abs(e.external);
  }
  // The batch's energy is the sum of the scenes' (the per-segment energies the batch will report
  // add up to what one reduction over the concatenation gives), to the round-off of the sums.
  EXPECT_NEAR(together.energy().total(), energy_sum, 1e-11 * energy_scale);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SceneBatchPremise,
                         ::testing::Values(PremiseCase{Integrator::SymplecticEuler, 1e-4, 20},
                                           PremiseCase{Integrator::BackwardEuler, 1.0 / 60.0, 20},
                                           PremiseCase{Integrator::ImplicitMidpoint, 1.0 / 60.0, 20},
                                           PremiseCase{Integrator::BDF2, 1.0 / 60.0, 20}),
                         [](const ::testing::TestParamInfo<PremiseCase>& info) {
                           return std::string(integratorName(info.param.integrator));
                         });

}  // namespace
}  // namespace stabint
