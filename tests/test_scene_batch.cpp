// Scene concatenation for the batched simulator (docs/batch_design.md, "Why concatenation is
// block-diagonal"): the segments say where each scene lies, and the concatenation, stepped by one
// Simulator, steps every scene as its own Simulator does (the premise of the batch: no element
// couples two scenes).
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "batch_scenes.hpp"
#include "cpu/cpu_backend.hpp"
#include "common/worker_pool.hpp"
#include "elements/element_type.hpp"
#include "scene/scene_batch.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::expectSameReport;
using testing::expectSameState;
using testing::mixedBatchScenes;
using testing::setStateInBoth;
using testing::stepAndExpectSame;
using testing::typeIndex;

TEST(SceneBatch, SegmentsLocateEveryScenesParticlesAndElements) {
  const std::vector<Scene> scenes = mixedBatchScenes();
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
      EXPECT_EQ(batch.scene.pins[std::size_t(seg.first_element[std::size_t(pin)]) + k].vertex,
                own.pins[k].vertex + off);
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

// concatenateScenes refuses `scenes` with an InvalidInputError whose message starts with `prefix`.
void expectRefusedNaming(const std::vector<Scene>& scenes, const std::string& prefix) {
  try {
    concatenateScenes(scenes);
    ADD_FAILURE() << "accepted; expected a refusal starting \"" << prefix << "\"";
  } catch (const InvalidInputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
  }
}

TEST(SceneBatch, RefusesWhatItCannotKeepApartNamingTheScene) {
  EXPECT_THROW(concatenateScenes({}), InvalidInputError);
  std::vector<Scene> scenes = mixedBatchScenes();
  scenes[2].gravity = Eigen::Vector3d(0.0, -1.0, 0.0);
  expectRefusedNaming(scenes, "scene 2: gravity");
  scenes = mixedBatchScenes();
  scenes[1].colliders.push_back(Collider{});
  scenes[1].colliders.back().first_particle = 2;
  scenes[1].colliders.back().num_particles = scenes[1].numParticles();  // one past the scene's last
  expectRefusedNaming(scenes, "scene 1: collider 0: first_particle 2 and num_particles");
  scenes = mixedBatchScenes();
  scenes[3].masses[0] = -1.0;
  expectRefusedNaming(scenes, "scene 3: ");
}

// Positions and velocities away from rest, the same for a scene alone and in the batch.
Eigen::MatrixX3d perturbed(const Eigen::MatrixX3d& m, double amount) {
  Eigen::MatrixX3d out = m;
  for (Eigen::Index j = 0; j < out.rows(); ++j)
    for (int k = 0; k < 3; ++k) out(j, k) += amount * std::sin(1.7 * double(j) + 2.3 * double(k) + 0.4);
  return out;
}

// The CPU reference's per-scene values of a batch are each scene's own backend's, bit for bit:
// the same elements in the same order, and each segment's reductions over an `n_s by 3` copy as
// the scene alone's are. Bit for bit is what the batch's blend decisions need to match the own
// simulators' (a decision at the tolerance's edge would otherwise go the other way).
TEST(SceneBatch, CpuPerSceneEnergiesAreEachScenesOwn) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  const SceneData data(batch.scene);
  Forcing forcing(data.scene());
  const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 2);
  ASSERT_TRUE(backend->computesPerScene());
  backend->setSegments(batch.segments);
  backend->write(0, perturbed(batch.scene.positions, 0.02));
  backend->write(1, perturbed(batch.scene.velocities, 0.5));
  const double t = 0.7;  // the chain's force field has grown by its rate
  std::vector<PotentialEnergy> potentials;
  std::vector<double> dots;
  backend->potentials(0, t, potentials);
  backend->massDots(1, 1, dots);
  ASSERT_EQ(potentials.size(), scenes.size());
  ASSERT_EQ(dots.size(), scenes.size());
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const SceneSegment& seg = batch.segments[s];
    const SceneData own_data(scenes[s]);
    Forcing own_forcing(own_data.scene());
    const std::unique_ptr<Backend> own = makeCpuBackend(own_data, own_forcing, 2);
    own->write(0, perturbed(batch.scene.positions, 0.02).middleRows(seg.first_particle, seg.num_particles));
    own->write(1, perturbed(batch.scene.velocities, 0.5).middleRows(seg.first_particle, seg.num_particles));
    const PotentialEnergy p = own->potential(0, t);
    // Not trivially zero: every term is exercised somewhere.
    EXPECT_NE(p.internal, 0.0) << "scene " << s;
    EXPECT_EQ(potentials[s].internal, p.internal) << "scene " << s;
    EXPECT_EQ(potentials[s].pins, p.pins) << "scene " << s;
    EXPECT_EQ(potentials[s].external, p.external) << "scene " << s;
    EXPECT_EQ(dots[s], own->massDot(1, 1)) << "scene " << s;
    // One segment's pass alone (a scene's event in a batch) is its part of the whole pass.
    const PotentialEnergy alone = backend->potentialOf(int(s), 0, t);
    EXPECT_EQ(alone.internal, p.internal) << "scene " << s;
    EXPECT_EQ(alone.pins, p.pins) << "scene " << s;
    EXPECT_EQ(alone.external, p.external) << "scene " << s;
  }
  // Rows written alone replace those rows only, exactly.
  ASSERT_TRUE(backend->writesRows());
  const SceneSegment& last = batch.segments.back();
  const Eigen::MatrixX3d before = perturbed(batch.scene.positions, 0.02);
  const Eigen::MatrixX3d rows = Eigen::MatrixX3d::Constant(last.num_particles, 3, 0.25);
  backend->writeRows(0, last.first_particle, rows);
  Eigen::MatrixX3d after;
  backend->read(0, after);
  EXPECT_EQ(after.middleRows(last.first_particle, last.num_particles), rows);
  EXPECT_EQ(after.topRows(last.first_particle), before.topRows(last.first_particle));
  backend->write(0, before);
  // And together they are the batch's single values, to the round-off of the different sums.
  const PotentialEnergy whole = backend->potential(0, t);
  double internal = 0.0, pins = 0.0, external = 0.0, dot = 0.0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    internal += potentials[s].internal;
    pins += potentials[s].pins;
    external += potentials[s].external;
    dot += dots[s];
  }
  EXPECT_NEAR(whole.internal, internal, 1e-13 * std::abs(internal));
  EXPECT_NEAR(whole.pins, pins, 1e-13 * std::abs(pins));
  EXPECT_NEAR(whole.external, external, 1e-12 * (std::abs(external) + std::abs(whole.external)));
  EXPECT_NEAR(backend->massDot(1, 1), dot, 1e-13 * dot);
}

// A batch's L-BFGS solve leaves each scene's potential of its result (the per-segment energies of
// its last local step), which the batch's BE step and blend partner take instead of an energy
// pass: it must be Backend::potentials at the result bit for bit.
TEST(SceneBatch, PotentialsOfAnLbfgsResultAreThePerScenePass) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  const SceneData data(batch.scene);
  Forcing forcing(data.scene());
  const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 3);
  backend->setSegments(batch.segments);
  GlobalSystem system(data);
  LocalGlobalSolver solver(*backend, system, 2);
  solver.setSegments(batch.segments, std::vector<double>(scenes.size(), 1.0));
  backend->write(0, perturbed(batch.scene.positions, 0.02));
  backend->write(1, batch.scene.positions);
  const double c = 3600.0, t = 0.7;
  IterationControl control;
  control.iterations = 6;
  control.acceleration = Acceleration::LBFGS;
  solver.solve(c, 1, 0, t, control);
  const std::vector<PotentialEnergy>& left = solver.potentialsOfResult();
  ASSERT_EQ(left.size(), scenes.size());
  std::vector<PotentialEnergy> pass;
  backend->potentials(0, t, pass);
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    EXPECT_NE(pass[s].internal, 0.0) << "scene " << s;
    EXPECT_EQ(left[s].internal, pass[s].internal) << "scene " << s;
    EXPECT_EQ(left[s].pins, pass[s].pins) << "scene " << s;
    EXPECT_EQ(left[s].external, pass[s].external) << "scene " << s;
  }
}

// The CPU reference's per-scene passes of a large batch run on threads, each thread a run of
// segments, and a batch's L-BFGS takes its gradient and every scene's energy from one pass
// (localStepGradientPerScene): both must be the serial per-segment pass and the force pass bit
// for bit, whatever the thread count, or a scene would step differently in a large batch.
TEST(SceneBatch, CpuPerScenePassesOnThreadsAreTheSerialOnes) {
  std::vector<Scene> scenes;
  for (int copy = 0; copy < 60; ++copy)  // about 40,000 elements: enough for the threads to pay
    for (const Scene& s : mixedBatchScenes()) scenes.push_back(s);
  const SceneBatch batch = concatenateScenes(scenes);
  const SceneData data(batch.scene);
  Forcing forcing(data.scene());
  const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 2);
  backend->setSegments(batch.segments);
  backend->write(0, perturbed(batch.scene.positions, 0.02));
  backend->write(1, batch.scene.positions);
  const double c = 3600.0, t = 0.7;
  const int threads = cpuThreads();
  setCpuThreads(1);
  std::vector<PotentialEnergy> serial, fused;
  backend->potentials(0, t, serial);
  Eigen::MatrixX3d gradient, serial_gradient;
  backend->localStepGradient(0, 1, c, t, serial_gradient);
  for (int n : {1, 2, 3}) {
    setCpuThreads(n);
    for (ThreadedPassPath path : {ThreadedPassPath::Auto, ThreadedPassPath::Serial}) {
      setThreadedPassPath(path);
      std::vector<PotentialEnergy> pass;
      backend->potentials(0, t, pass);
      backend->localStepGradientPerScene(0, 1, c, t, gradient, fused);
      ASSERT_EQ(pass.size(), scenes.size());
      ASSERT_EQ(fused.size(), scenes.size());
      EXPECT_EQ(gradient, serial_gradient) << n << " threads";
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        for (const std::vector<PotentialEnergy>* got : {&pass, &fused}) {
          EXPECT_EQ((*got)[s].internal, serial[s].internal) << "scene " << s << ", " << n << " threads";
          EXPECT_EQ((*got)[s].pins, serial[s].pins) << "scene " << s << ", " << n << " threads";
          EXPECT_EQ((*got)[s].external, serial[s].external) << "scene " << s << ", " << n << " threads";
        }
      }
    }
  }
  setThreadedPassPath(ThreadedPassPath::Auto);
  setCpuThreads(threads);
  EXPECT_NE(serial.back().internal, 0.0);
}

// A solve of some of a batch's blocks (GlobalSystem::solve and solveConjugateGradient with
// `solved`, and the product multiply): the blocks solved are the whole solve's rows bit for bit, and the others' rows
// are not touched (the work skipped), on a small batch (one thread) and on one past kForestRows (the trees on threads).
TEST(SceneBatch, SolvesOfSomeBlocksSkipTheOthers) {
  for (int copies : {1, 60}) {
    std::vector<Scene> scenes;
    for (int copy = 0; copy < copies; ++copy)
      for (const Scene& s : mixedBatchScenes()) scenes.push_back(s);
    const SceneBatch batch = concatenateScenes(scenes);
    const SceneData data(batch.scene);
    GlobalSystem system(data);
    system.setBlocks(batch.segments);
    const Eigen::Index n = batch.scene.numParticles();
    ASSERT_EQ(copies > 1, n >= GlobalSystem::kForestRows) << n;
    const Eigen::MatrixX3d rhs = perturbed(batch.scene.positions, 0.3);
    std::vector<char> solved(scenes.size(), 1);
    for (std::size_t s = 1; s < scenes.size(); s += 2) solved[s] = 0;
    const double c = 900.0;
    for (const std::string kind : {"factor", "CG", "product"}) {  // the product: Newton-CG's (K_c x)
      const std::string what = std::to_string(copies) + " copies, " + kind;
      Eigen::MatrixX3d whole = Eigen::MatrixX3d::Zero(n, 3);
      Eigen::MatrixX3d some = Eigen::MatrixX3d::Constant(n, 3, 7.0);  // the rows not solved keep it
      Eigen::MatrixX3d start = Eigen::MatrixX3d::Zero(n, 3);
      for (std::size_t s = 0; s < scenes.size(); ++s)
        if (solved[s]) some.middleRows(batch.segments[s].first_particle, batch.segments[s].num_particles).setZero();
      if (kind == "CG") {
        system.solveConjugateGradient(c, rhs, whole, 5, 0.0);
        system.solveConjugateGradient(c, rhs, some, 5, 0.0, &solved);
      } else if (kind == "product") {
        system.multiply(c, rhs, whole);
        system.multiply(c, rhs, some, &solved);
      } else {
        system.solve(c, rhs, whole);
        system.solve(c, rhs, some, &solved);
      }
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        const SceneSegment& seg = batch.segments[s];
        if (solved[s])
          EXPECT_EQ(some.middleRows(seg.first_particle, seg.num_particles),
                    whole.middleRows(seg.first_particle, seg.num_particles))
              << what << ", scene " << s;
        else
          EXPECT_TRUE((some.middleRows(seg.first_particle, seg.num_particles).array() == 7.0).all())
              << what << ", scene " << s;
      }
      EXPECT_NE(whole, start) << what;
    }
  }
}

// Scenes that take no part in a solve (LocalGlobalSolver::setSolving: a batch's inactive scenes,
// or those that need no blend partner) keep their warm start exactly, take no iteration and have
// no potential (NaN), while the others take the iterates they take when all solve, bit for bit:
// every solver, to a fixed count and to a tolerance, with the factor and with CG. The CPU
// reference also skips their element passes (their energies are not computed: checked through
// localStepGradientPerScene's entries, which stay as they were).
TEST(SceneBatch, ScenesThatTakeNoPartInASolveKeepTheirWarmStart) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  const SceneData data(batch.scene);
  Forcing forcing(data.scene());
  const std::vector<char> solving = {1, 0, 1, 0};
  ASSERT_EQ(solving.size(), scenes.size());
  const Eigen::MatrixX3d warm = perturbed(batch.scene.positions, 0.02);
  const double c = 3600.0, t = 0.7;
  struct Case {
    Acceleration acceleration;
    double tolerance;
  };
  for (const Case k : {Case{Acceleration::None, 0.0}, Case{Acceleration::None, 1e-8}, Case{Acceleration::LBFGS, 0.0},
                       Case{Acceleration::LBFGS, 1e-8}, Case{Acceleration::Anderson, 1e-8},
                       Case{Acceleration::Chebyshev, 0.0}, Case{Acceleration::Newton, 1e-8}})
    for (GlobalSolve global : {GlobalSolve::Factor, GlobalSolve::ConjugateGradient}) {
      const std::string what = std::string(accelerationName(k.acceleration)) + ", tolerance " +
                               std::to_string(k.tolerance) + (global == GlobalSolve::Factor ? ", factor" : ", CG");
      IterationControl control;
      control.iterations = 6;
      control.acceleration = k.acceleration;
      control.tolerance = k.tolerance;
      control.max_iterations = 40;
      control.global_solve = global;
      auto run = [&](const std::vector<char>& taking_part, Eigen::MatrixX3d& x, std::vector<int>& iterations,
                     std::vector<PotentialEnergy>& potentials) {
        const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 3);
        backend->setSegments(batch.segments);
        GlobalSystem system(data);
        LocalGlobalSolver solver(*backend, system, 2);
        solver.setSegments(batch.segments, std::vector<double>(scenes.size(), 1.0));
        solver.setSolving(taking_part);
        backend->write(0, warm);
        backend->write(1, batch.scene.positions);
        solver.solve(c, 1, 0, t, control);
        backend->read(0, x);
        iterations.clear();
        for (std::size_t s = 0; s < scenes.size(); ++s) iterations.push_back(solver.segmentIterations(s));
        potentials = solver.potentialsOfResult();
      };
      Eigen::MatrixX3d all_x, some_x;
      std::vector<int> all_iterations, some_iterations;
      std::vector<PotentialEnergy> all_potentials, some_potentials;
      run({}, all_x, all_iterations, all_potentials);
      run(solving, some_x, some_iterations, some_potentials);
      for (std::size_t s = 0; s < scenes.size(); ++s) {
        const SceneSegment& seg = batch.segments[s];
        const std::string where = what + ", scene " + std::to_string(s);
        if (solving[s]) {
          EXPECT_EQ(some_x.middleRows(seg.first_particle, seg.num_particles),
                    all_x.middleRows(seg.first_particle, seg.num_particles))
              << where;
          EXPECT_EQ(some_iterations[s], all_iterations[s]) << where;
          EXPECT_GT(some_iterations[s], 0) << where;
        } else {
          EXPECT_EQ(some_x.middleRows(seg.first_particle, seg.num_particles),
                    warm.middleRows(seg.first_particle, seg.num_particles))
              << where;
          EXPECT_EQ(some_iterations[s], 0) << where;
        }
        if (some_potentials.empty()) continue;
        ASSERT_EQ(some_potentials.size(), scenes.size()) << where;
        if (solving[s]) {
          if (!all_potentials.empty()) {
            EXPECT_EQ(some_potentials[s].total(), all_potentials[s].total()) << where;
          }
        } else {
          EXPECT_TRUE(std::isnan(some_potentials[s].total())) << where;
        }
      }
    }
  // The flags hold for one solve: the next one, given none, solves every scene.
  {
    const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 3);
    backend->setSegments(batch.segments);
    GlobalSystem system(data);
    LocalGlobalSolver solver(*backend, system, 2);
    solver.setSegments(batch.segments, std::vector<double>(scenes.size(), 1.0));
    backend->write(1, batch.scene.positions);
    IterationControl control = IterationControl::plain(3);
    for (bool flagged : {true, false}) {
      if (flagged) solver.setSolving(solving);
      backend->write(0, warm);
      solver.solve(c, 1, 0, t, control);
      for (std::size_t s = 0; s < scenes.size(); ++s)
        EXPECT_EQ(solver.segmentIterations(s), flagged && !solving[s] ? 0 : 3) << "scene " << s;
    }
  }
  // The CPU reference's pass skips the scenes not flagged: their entries stay as they were.
  const std::unique_ptr<Backend> backend = makeCpuBackend(data, forcing, 2);
  backend->setSegments(batch.segments);
  backend->write(0, warm);
  backend->write(1, batch.scene.positions);
  const PotentialEnergy sentinel{1.0, 2.0, 3.0};
  std::vector<PotentialEnergy> all, some(scenes.size(), sentinel);
  Eigen::MatrixX3d gradient;
  backend->localStepGradientPerScene(0, 1, c, t, gradient, all);
  backend->localStepGradientPerScene(0, 1, c, t, gradient, some, &solving);
  for (std::size_t s = 0; s < scenes.size(); ++s)
    EXPECT_EQ(some[s].total(), solving[s] ? all[s].total() : sentinel.total()) << "scene " << s;
  // And so does its energy pass of some scenes (a blend's root-find rounds).
  some.assign(scenes.size(), sentinel);
  backend->potentials(0, t, all);
  backend->potentials(0, t, some, &solving);
  for (std::size_t s = 0; s < scenes.size(); ++s)
    EXPECT_EQ(some[s].total(), solving[s] ? all[s].total() : sentinel.total()) << "scene " << s;
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
// each block as alone and the trajectories were bit for bit (docs/batch_design.md). Plain
// iterations: one Simulator's L-BFGS takes its dot products and step lengths over the whole
// concatenation, which couples the scenes; BatchSimulator's takes them per scene
// (LocalGlobalSolver::setSegments; BatchSimulatorBlend.LbfgsSolvesArePerScene).
TEST_P(SceneBatchPremise, EachSceneStepsAsItsOwnSimulator) {
  const PremiseCase c = GetParam();
  const std::vector<Scene> scenes = mixedBatchScenes();
  const SceneBatch batch = concatenateScenes(scenes);
  SimulatorOptions options;
  options.integrator = c.integrator;
  options.time_step = c.time_step;
  options.iterations = 5;
  options.acceleration = Acceleration::None;
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

// ---- BatchSimulator ----------------------------------------------------------------------------

class BatchSimulatorMatches : public ::testing::TestWithParam<PremiseCase> {};

// Every scene of the batch follows its own Simulator: state (SE bit for bit, BE to the round-off
// of the factor's ordering, as in the premise above), and its own energies, target, forcing and
// damping, which the batch computes per segment. The energies agree to 1e-12 of the scene's
// energy scale: bit for bit where the states are, round-off of the state otherwise.
TEST_P(BatchSimulatorMatches, EveryScenesStateEnergyAndTargetAreItsOwnSimulators) {
  const PremiseCase c = GetParam();
  const std::vector<Scene> scenes = mixedBatchScenes();
  SimulatorOptions options;
  options.integrator = c.integrator;
  options.time_step = c.time_step;
  options.iterations = 5;
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  ASSERT_EQ(batch.size(), int(scenes.size()));
  for (std::size_t s = 0; s < scenes.size(); ++s) EXPECT_EQ(batch.energyScale(int(s)), alone[s].energyScale());
  double forcing = 0.0, damping = 0.0;
  for (int step = 0; step < c.steps; ++step) {
    const BatchStepReport& report = batch.step();
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const StepReport& own = alone[s].step();
      const StepReport& got = report.scenes[s];
      EXPECT_TRUE(report.refusals[s].empty()) << report.refusals[s];
      const double scale = alone[s].energyScale();
      EXPECT_EQ(got.step, own.step);
      EXPECT_EQ(got.time, own.time);
      EXPECT_NEAR(got.forcing, own.forcing, 1e-12 * scale) << "scene " << s << " step " << step;
      EXPECT_NEAR(got.damping, own.damping, 1e-12 * scale) << "scene " << s << " step " << step;
      EXPECT_NEAR(got.target, own.target, 1e-12 * scale) << "scene " << s << " step " << step;
      EXPECT_NEAR(got.energy.kinetic, own.energy.kinetic, 1e-12 * scale) << "scene " << s << " step " << step;
      EXPECT_NEAR(got.energy.elastic, own.energy.elastic, 1e-12 * scale) << "scene " << s << " step " << step;
      EXPECT_NEAR(got.energy.external, own.energy.external, 1e-12 * scale) << "scene " << s << " step " << step;
      forcing += std::abs(own.forcing);
      damping += own.damping;
    }
  }
  // The chain's growing field does work and the cloth's body is damped: both were compared.
  EXPECT_GT(forcing, 0.0);
  EXPECT_GT(damping, 0.0);
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    EXPECT_EQ(batch.time(int(s)), alone[s].time());
    if (c.integrator == Integrator::SymplecticEuler || c.integrator == Integrator::ForwardEuler) {
      EXPECT_EQ(batch.positions(int(s)), alone[s].positions()) << "scene " << s;
      EXPECT_EQ(batch.velocities(int(s)), alone[s].velocities()) << "scene " << s;
    } else {
      const double size = (scenes[s].positions.colwise().maxCoeff() - scenes[s].positions.colwise().minCoeff()).norm();
      EXPECT_LE((batch.positions(int(s)) - alone[s].positions()).cwiseAbs().maxCoeff(), 1e-9 * size);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Integrators, BatchSimulatorMatches,
                         ::testing::Values(PremiseCase{Integrator::SymplecticEuler, 1e-4, 20},
                                           PremiseCase{Integrator::ForwardEuler, 1e-5, 20},
                                           PremiseCase{Integrator::BackwardEuler, 1.0 / 60.0, 20},
                                           PremiseCase{Integrator::BDF2, 1.0 / 60.0, 20},
                                           PremiseCase{Integrator::ImplicitMidpoint, 1.0 / 60.0, 20}),
                         [](const ::testing::TestParamInfo<PremiseCase>& info) {
                           return std::string(integratorName(info.param.integrator));
                         });

// A scene that blows up is refused alone, with its own Simulator's message at the same step, and
// keeps its last accepted state; its neighbour steps on as its own Simulator does.
TEST(BatchSimulator, OneScenesRefusalLeavesTheOthersStepping) {
  ChainPendulumParams soft, stiff;
  soft.stiffness = 10.0;
  soft.pin_stiffness = 100.0;  // SE stable at h = 1e-3 (omega about 90/s)
  stiff.particles = 6;         // pin omega about 7,700/s: SE explodes at h = 1e-3
  const std::vector<Scene> scenes = {makeChainPendulum(soft), makeChainPendulum(stiff)};
  SimulatorOptions options;
  options.integrator = Integrator::SymplecticEuler;
  options.time_step = 1e-3;
  options.energy_limit = 1.0;
  BatchSimulator batch(scenes, options);
  Simulator soft_alone(scenes[0], options), stiff_alone(scenes[1], options);
  std::string own_refusal;
  int refused_at = -1;
  for (int step = 0; step < 200; ++step) {
    const BatchStepReport& report = batch.step();
    soft_alone.step();
    EXPECT_TRUE(report.refusals[0].empty()) << report.refusals[0];
    if (own_refusal.empty()) {
      try {
        stiff_alone.step();
        EXPECT_TRUE(report.refusals[1].empty()) << "step " << step << ": " << report.refusals[1];
      } catch (const EnergyLimitError& e) {
        own_refusal = e.what();
        refused_at = step;
        EXPECT_EQ(report.refusals[1], own_refusal);
      }
    } else {
      EXPECT_FALSE(report.refusals[1].empty());
      EXPECT_FALSE(batch.active(1));
    }
  }
  ASSERT_GE(refused_at, 1) << "the stiff chain never exceeded the limit";
  EXPECT_EQ(batch.stepCount(1), stiff_alone.stepCount());
  EXPECT_EQ(batch.positions(1), stiff_alone.positions());
  EXPECT_EQ(batch.target(1), stiff_alone.target());
  EXPECT_TRUE(batch.active(0));
  EXPECT_EQ(batch.positions(0), soft_alone.positions());
  EXPECT_EQ(batch.velocities(0), soft_alone.velocities());
}

// A scene whose state overflows (SE above its stability limit: omega h = 2.5 multiplies the
// energy by 16 per step) is refused with the NonFiniteStateError message of its own Simulator, at
// its step; the NaN stays in its block and the neighbour steps on bit for bit.
TEST(BatchSimulator, OneScenesBlowUpStaysInItsBlock) {
  const double h = 1e-3;
  LinearOscillatorParams oscillator;
  oscillator.stiffness = std::pow(2.5 / h, 2.0);  // omega h = 2.5 with mass 1
  ChainPendulumParams soft;
  soft.stiffness = 10.0;
  soft.pin_stiffness = 100.0;
  soft.gravity = 0.0;  // the oscillator's
  Scene chain = makeChainPendulum(soft);
  chain.velocities = perturbed(Eigen::MatrixX3d::Zero(chain.numParticles(), 3), 0.5);
  const std::vector<Scene> scenes = {makeLinearOscillator(oscillator), chain};
  SimulatorOptions options;
  options.integrator = Integrator::SymplecticEuler;
  options.time_step = h;
  BatchSimulator batch(scenes, options);
  Simulator exploding(scenes[0], options), neighbour(scenes[1], options);
  int refused_at = -1;
  for (int step = 0; step < 400; ++step) {
    const BatchStepReport& report = batch.step();
    neighbour.step();
    EXPECT_TRUE(report.refusals[1].empty()) << report.refusals[1];
    if (refused_at >= 0) continue;
    try {
      exploding.step();
      EXPECT_TRUE(report.refusals[0].empty()) << "step " << step << ": " << report.refusals[0];
    } catch (const NonFiniteStateError& e) {
      refused_at = step;
      EXPECT_EQ(report.refusals[0], e.what());
    }
  }
  ASSERT_GE(refused_at, 100) << "the oscillator did not overflow";
  EXPECT_FALSE(batch.active(0));
  EXPECT_EQ(batch.positions(0), exploding.positions());
  EXPECT_TRUE(batch.positions(0).allFinite());
  EXPECT_EQ(batch.positions(1), neighbour.positions());
  EXPECT_EQ(batch.velocities(1), neighbour.velocities());
}

// Every option runs per scene in a batch: each acceleration with its stops, and CG (each scene's
// block on its own); only Simulator's own checks refuse options.
TEST(BatchSimulator, TakesEverySolverOptionRefusesBadOnes) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  SimulatorOptions options;
  options.integrator = Integrator::BackwardEuler;
  options.global_solve = GlobalSolve::ConjugateGradient;
  EXPECT_NO_THROW(BatchSimulator(scenes, options));
  options.global_solve = GlobalSolve::Factor;
  for (Acceleration per_scene :
       {Acceleration::LBFGS, Acceleration::Anderson, Acceleration::Chebyshev, Acceleration::Newton}) {
    options.acceleration = per_scene;
    EXPECT_NO_THROW(BatchSimulator(scenes, options)) << accelerationName(per_scene);
  }
  options.acceleration = Acceleration::LBFGS;
  options.gradient_tolerance = 1e-3;  // its stops are per scene too
  options.tolerance = 1e-6;
  EXPECT_NO_THROW(BatchSimulator(scenes, options));
  options.gradient_tolerance = 0.0;
  options.acceleration = Acceleration::None;  // and plain iterations' stop
  EXPECT_NO_THROW(BatchSimulator(scenes, options));
  options.tolerance = 0.0;
  // Simulator's own checks come first.
  options.integrator = Integrator::BackwardEuler;
  options.time_step = -1.0;
  try {
    BatchSimulator batch(scenes, options);
    ADD_FAILURE() << "a negative time step accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("simulator options: time_step"), std::string::npos) << e.what();
  }
}

// ---- the blend in lockstep -----------------------------------------------------------------------

// Scenes whose blend steps take every branch in the first steps (checked below): the mixed scenes
// (the chain's swing and growing field, the damped cloth, the bar, the triangle cloth) and a
// chain released with its links stretched and moving, whose IM candidates gain energy at once.
std::vector<Scene> blendScenes() {
  std::vector<Scene> scenes = mixedBatchScenes();
  ChainPendulumParams chain;
  chain.particles = 6;
  Scene stretched = makeChainPendulum(chain);
  stretched.positions = perturbed(stretched.positions, 0.05);
  stretched.velocities = perturbed(Eigen::MatrixX3d::Zero(stretched.numParticles(), 3), 2.0);
  scenes.push_back(stretched);
  return scenes;
}

// The blend tests' options: 60 Hz, 5 iterations (every branch occurs in blendScenes' first steps).
SimulatorOptions blendOptions() {
  SimulatorOptions options;
  options.integrator = Integrator::EnergyBlend;
  options.time_step = 1.0 / 60.0;
  options.iterations = 5;
  return options;
}

// Every scene of a blend batch takes the branch its own Simulator takes, step by step, with its
// alpha, velocity scale, forcing, damping, target and energies, and follows its trajectory: the
// decisions, root finds and corrections are per scene (one energy pass per round for all), the
// partner is solved for the scenes that need it (the others take no part in its solve).
void expectBlendBatchFollowsItsScenes(Acceleration acceleration) {
  const std::vector<Scene> scenes = blendScenes();
  SimulatorOptions options = blendOptions();
  options.acceleration = acceleration;
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  std::vector<std::vector<int>> branches(scenes.size(), std::vector<int>(4, 0));
  int steps_with_mixed_branches = 0;
  for (int step = 0; step < 40; ++step) {
    const BatchStepReport& report = batch.step();
    std::vector<int> this_step(4, 0);
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const StepReport& own = alone[s].step();
      const std::string where = "scene " + std::to_string(s) + " step " + std::to_string(step);
      EXPECT_TRUE(report.refusals[s].empty()) << where << ": " << report.refusals[s];
      expectSameReport(report.scenes[s], own, alone[s].energyScale(), where);
      expectSameState(batch.positions(int(s)), batch.velocities(int(s)), alone[s], where);
      ++branches[s][std::size_t(own.branch)];
      ++this_step[std::size_t(own.branch)];
    }
    const auto at = [&](BlendBranch b) { return this_step[std::size_t(b)]; };
    if (at(BlendBranch::ImplicitMidpoint) > 0 && at(BlendBranch::BackwardEuler) > 0 &&
        at(BlendBranch::VelocityScale) > 0)
      ++steps_with_mixed_branches;
  }
  // The batch really mixed the branches within single steps (else lockstep was not exercised).
  EXPECT_GT(steps_with_mixed_branches, 0);
  for (std::size_t s = 0; s < scenes.size(); ++s)
    EXPECT_EQ(branches[s][std::size_t(BlendBranch::None)], 0) << "scene " << s;
}

TEST(BatchSimulatorBlend, EveryScenesBranchAndStateAreItsOwnSimulators) {
  expectBlendBatchFollowsItsScenes(Acceleration::None);
}

// L-BFGS in a batch keeps its dot products, step lengths, line search and history per scene
// (LocalGlobalSolver::setSegments): each scene takes the iterates it takes alone, so the blend's
// decisions and states are again its own Simulator's.
TEST(BatchSimulatorBlend, LbfgsSolvesArePerScene) { expectBlendBatchFollowsItsScenes(Acceleration::LBFGS); }

// 15 steps of the batch against its scenes' own Simulators (testing::stepAndExpectSame); returns
// how many of them had scenes that took different iteration counts.
int stepsWithDifferentCounts(BatchSimulator& batch, std::vector<Simulator>& alone, const std::string& what) {
  int steps_with_different_counts = 0;
  for (int step = 0; step < 15; ++step) {
    const BatchStepReport& report = testing::stepAndExpectSame(batch, alone, what + ", step " + std::to_string(step));
    int fewest = report.scenes[0].iterations, most = fewest;
    for (const StepReport& r : report.scenes) {
      fewest = std::min(fewest, r.iterations);
      most = std::max(most, r.iterations);
    }
    if (fewest < most) ++steps_with_different_counts;
  }
  return steps_with_different_counts;
}

// Stops by accuracy in a batch are per scene: each scene stops its solve where its own Simulator
// stops (the same iterations in every step's report, the partner's and the full-budget BE's
// included), stays at that iterate while the others go on, and follows its own trajectory.
// L-BFGS's objective-change and gradient stops and plain iterations' tolerance; BE, BDF2, IM and
// the blend; the scenes stop at different counts within one step (else nothing per scene was
// exercised; a scene may also run into the cap, 60, as its own Simulator does).
TEST(BatchSimulator, StopsByAccuracyArePerScene) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  for (Integrator integrator :
       {Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
    for (int stop = 0; stop < 3; ++stop) {
      SimulatorOptions options;
      options.integrator = integrator;
      options.time_step = 1.0 / 60.0;
      options.acceleration = stop == 2 ? Acceleration::None : Acceleration::LBFGS;
      options.max_iterations = 60;
      if (stop == 1) {
        options.gradient_tolerance = 1e-3;
        options.iterations = 60;  // the gradient stop's cap
      } else {
        options.tolerance = stop == 0 ? 1e-7 : 1e-5;
      }
      const std::string what = std::string(integratorName(integrator)) + (stop == 0   ? ", L-BFGS tolerance"
                                                                          : stop == 1 ? ", gradient"
                                                                                      : ", plain");
      BatchSimulator batch(scenes, options);
      std::vector<Simulator> alone;
      for (const Scene& s : scenes) alone.emplace_back(s, options);
      EXPECT_GT(stepsWithDifferentCounts(batch, alone, what), 0) << what;
    }
  }
}

// Chebyshev, Anderson and Newton-CG in a batch: each scene has its own rule, objective, safeguard
// or CG and line search, and tolerance stop, so it takes the iterates its own Simulator takes
// (states to round-off, the same iterations and branches). With a fixed count and with the
// tolerance stop (the scenes then stop at different counts within a step), BE, IM and the blend.
TEST(BatchSimulator, AccelerationsArePerScene) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  for (Acceleration acceleration : {Acceleration::Chebyshev, Acceleration::Anderson, Acceleration::Newton}) {
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
      for (const bool stop : {false, true}) {
        SimulatorOptions options;
        options.integrator = integrator;
        options.time_step = 1.0 / 60.0;
        options.acceleration = acceleration;
        options.iterations = 12;
        if (stop) {
          options.tolerance = 1e-6;
          options.max_iterations = 60;
        }
        const std::string what = std::string(accelerationName(acceleration)) + ", " + integratorName(integrator) +
                                 (stop ? ", tolerance" : ", fixed count");
        BatchSimulator batch(scenes, options);
        std::vector<Simulator> alone;
        for (const Scene& s : scenes) alone.emplace_back(s, options);
        const int steps_with_different_counts = stepsWithDifferentCounts(batch, alone, what);
        if (stop) {
          EXPECT_GT(steps_with_different_counts, 0) << what;
        }
      }
    }
  }
}

// CG in a batch runs on each scene's block of the system on its own (GlobalSystem::setBlocks), as
// the scene's own Simulator runs it on its system: the same iterates to round-off, with a fixed
// CG count and with CG's tolerance, under plain iterations (also with their tolerance stop, each
// scene's CG warm-started from its iterate, which this test does not tell apart from a stale start:
// the stop's many iterations wash it out), Anderson and L-BFGS, BE and the blend.
TEST(BatchSimulator, ConjugateGradientsArePerScene) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  for (Acceleration acceleration : {Acceleration::None, Acceleration::Anderson, Acceleration::LBFGS})
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend})
      for (const double cg_tolerance : {0.0, 1e-8}) {
        SimulatorOptions options;
        options.integrator = integrator;
        options.time_step = 1.0 / 60.0;
        options.acceleration = acceleration;
        options.global_solve = GlobalSolve::ConjugateGradient;
        options.cg_iterations = 4;  // far from converged: a CG over the whole batch would part from its scenes
        options.cg_tolerance = cg_tolerance;
        if (cg_tolerance == 0.0 && acceleration == Acceleration::None) {
          options.tolerance = 1e-6;  // the solve's own stop, per scene
          options.max_iterations = 40;
        }
        const std::string what = std::string(accelerationName(acceleration)) + ", " + integratorName(integrator) +
                                 ", CG tolerance " + std::to_string(cg_tolerance);
        BatchSimulator batch(scenes, options);
        std::vector<Simulator> alone;
        for (const Scene& s : scenes) alone.emplace_back(s, options);
        stepsWithDifferentCounts(batch, alone, what);
      }
}

// With an energy ceiling far below the blend's band, the steps whose energy ends above H* are
// refused: each scene at the step its own Simulator refuses, with its message; the others step on.
TEST(BatchSimulatorBlend, RefusalsArePerScene) {
  const std::vector<Scene> scenes = blendScenes();
  SimulatorOptions options = blendOptions();
  options.energy_limit = 1e-7;
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  std::vector<bool> refused(scenes.size(), false);
  for (int step = 0; step < 40; ++step) {
    const BatchStepReport& report = batch.step();
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      const std::string where = "scene " + std::to_string(s) + " step " + std::to_string(step);
      if (refused[s]) {
        EXPECT_FALSE(batch.active(int(s))) << where;
        EXPECT_FALSE(report.refusals[s].empty()) << where;
        continue;
      }
      try {
        const StepReport& own = alone[s].step();
        EXPECT_TRUE(report.refusals[s].empty()) << where << ": " << report.refusals[s];
        expectSameReport(report.scenes[s], own, alone[s].energyScale(), where);
      } catch (const EnergyLimitError& e) {
        EXPECT_EQ(report.refusals[s], e.what()) << where;
        refused[s] = true;
      }
      expectSameState(batch.positions(int(s)), batch.velocities(int(s)), alone[s], where);
      EXPECT_EQ(batch.stepCount(int(s)), alone[s].stepCount()) << where;
    }
  }
  int refused_scenes = 0;
  for (bool r : refused) refused_scenes += r ? 1 : 0;
  // Some scenes were refused and some were not: the refusals did not spread.
  EXPECT_GT(refused_scenes, 0);
  EXPECT_LT(refused_scenes, int(scenes.size()));
}

// setState is an event of one scene: booked in its H* only (its event_energy as its own
// Simulator's), the others untouched; a refused scene steps again after it.
TEST(BatchSimulatorBlend, SetStateIsAnEventOfOneScene) {
  const std::vector<Scene> scenes = blendScenes();
  SimulatorOptions options = blendOptions();
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  for (int step = 0; step < 5; ++step) {
    batch.step();
    for (Simulator& sim : alone) sim.step();
  }
  const int moved = 1;
  const Eigen::MatrixX3d x = perturbed(alone[moved].positions(), 0.01);
  const Eigen::MatrixX3d v = perturbed(alone[moved].velocities(), 0.3);
  setStateInBoth(batch, alone, moved, x, v);
  for (int step = 0; step < 10; ++step) stepAndExpectSame(batch, alone, "step " + std::to_string(step));
  // Bad input changes nothing and names the scene.
  const double before = batch.target(2);
  EXPECT_THROW(batch.setState(2, x, v), InvalidInputError);  // scene 1's row count
  EXPECT_THROW(batch.setState(7, x, v), InvalidInputError);
  // Finite but beyond 1e150, as every scene value must be (docs/method.md, "Per-frame input").
  const Eigen::MatrixX3d x_own = batch.positions(moved), v_own = batch.velocities(moved);
  Eigen::MatrixX3d huge = v_own;
  huge(0, 0) = -1e151;
  try {
    batch.setState(moved, x_own, huge);
    ADD_FAILURE() << "a velocity of -1e151 accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("velocities: row 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("exceeds"), std::string::npos) << e.what();
  }
  EXPECT_EQ(batch.velocities(moved), v_own);
  EXPECT_EQ(batch.target(2), before);
}

// A pin dragged in one scene does work booked in that scene's H* only, as its own Simulator books
// it; the other scenes' targets do not move by it.
TEST(BatchSimulatorBlend, APinDraggedInOneSceneIsBookedInItsTargetOnly) {
  const std::vector<Scene> scenes = blendScenes();
  SimulatorOptions options = blendOptions();
  BatchSimulator batch(scenes, options);
  std::vector<Simulator> alone;
  for (const Scene& s : scenes) alone.emplace_back(s, options);
  const int dragged = 4;  // the stretched chain, pinned at its first particle
  ASSERT_FALSE(scenes[dragged].pins.empty());
  double work = 0.0;
  for (int step = 0; step < 30; ++step) {
    const Eigen::Vector3d q = scenes[dragged].pins[0].target.position + Eigen::Vector3d(0.01 * step, 0.0, 0.0);
    batch.setPinTarget(dragged, 0, q);
    alone[std::size_t(dragged)].setPinTarget(0, q);
    const BatchStepReport& report = stepAndExpectSame(batch, alone, "step " + std::to_string(step));
    work += std::abs(report.scenes[std::size_t(dragged)].forcing);
  }
  EXPECT_GT(work, 0.0);
  EXPECT_THROW(batch.setPinTarget(dragged, 1, Eigen::Vector3d::Zero()), InvalidInputError);  // one pin
  EXPECT_THROW(batch.setPinTarget(dragged, 0, Eigen::Vector3d::Constant(NAN)), InvalidInputError);
  EXPECT_THROW(batch.setPinTarget(dragged, 0, Eigen::Vector3d(0.0, 1e151, 0.0)), InvalidInputError);
}

// The public accessors: the concatenation's rows per scene, the batch's time, and bad scene
// indices refused naming the call; setState refused for BDF2 (its restart is the whole batch's).
TEST(BatchSimulator, AccessorsLocateEachSceneAndRefuseBadIndices) {
  const std::vector<Scene> scenes = mixedBatchScenes();
  SimulatorOptions options;
  options.integrator = Integrator::BDF2;
  options.time_step = 1.0 / 60.0;
  options.iterations = 5;
  BatchSimulator batch(scenes, options);
  EXPECT_FALSE(batch.backendDescription().empty());
  EXPECT_EQ(batch.options().integrator, Integrator::BDF2);
  batch.step();
  batch.step();
  EXPECT_EQ(batch.time(), 2.0 * (1.0 / 60.0));
  int first = 0;
  for (int s = 0; s < batch.size(); ++s) {
    EXPECT_EQ(batch.firstParticle(s), first);
    EXPECT_EQ(batch.numParticles(s), scenes[std::size_t(s)].numParticles());
    EXPECT_EQ(batch.positions(s), batch.allPositions().middleRows(first, batch.numParticles(s)));
    EXPECT_EQ(batch.time(s), batch.time());
    EXPECT_EQ(batch.stepCount(s), 2);
    first += batch.numParticles(s);
  }
  EXPECT_EQ(batch.allPositions().rows(), first);
  for (int bad : {-1, batch.size()}) {
    try {
      batch.target(bad);
      ADD_FAILURE() << "scene " << bad << " accepted";
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("target: scene " + std::to_string(bad) + " out of range"), std::string::npos)
          << e.what();
    }
    EXPECT_THROW(batch.positions(bad), InvalidInputError);
    EXPECT_THROW(batch.active(bad), InvalidInputError);
  }
  const double target = batch.target(0);
  const Eigen::MatrixX3d x = batch.positions(0);
  EXPECT_THROW(batch.setState(0, x, Eigen::MatrixX3d::Zero(x.rows(), 3)), InvalidInputError);
  EXPECT_EQ(batch.target(0), target);
  EXPECT_EQ(batch.positions(0), x);
}

// One budget for every scene (they share their solves); a refused one changes nothing.
TEST(BatchSimulator, SetIterationsIsEveryScenesBudget) {
  SimulatorOptions options;
  options.integrator = Integrator::BackwardEuler;
  options.acceleration = Acceleration::None;
  BatchSimulator batch(mixedBatchScenes(), options);
  EXPECT_THROW(batch.setIterations(0), InvalidInputError);
  EXPECT_EQ(batch.options().iterations, options.iterations);
  batch.setIterations(3);
  EXPECT_EQ(batch.options().iterations, 3);
  for (const StepReport& r : batch.step().scenes) EXPECT_EQ(r.iterations, 3);
}

// The step's phase times are the batch's: every pass is shared, so no scene has times of its own.
TEST(BatchSimulator, ReportsTheWholeStepsPhaseTimes) {
  SimulatorOptions options;
  options.integrator = Integrator::EnergyBlend;
  BatchSimulator batch(mixedBatchScenes(), options);
  const BatchStepReport& report = batch.step();
  EXPECT_GT(report.times.local, 0.0);
  EXPECT_GT(report.times.global, 0.0);
  for (const StepReport& r : report.scenes) EXPECT_EQ(r.times.total(), 0.0);
}

}  // namespace
}  // namespace stabint
