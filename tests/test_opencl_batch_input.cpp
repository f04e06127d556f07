// Per-frame input of a batch on OpenCL (docs/method.md, "Batches"): the device batch given the
// same calls as the CPU batch, which follows each scene's own Simulator given them
// (tests/test_batch_input.cpp), follows it to the cross-backend tolerance.
#include <stabint/batch.hpp>
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>

#include "batch_scenes.hpp"
#include "opencl_batch_support.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::availablePrecisions;
using testing::BatchCase;
using testing::batchOptions;
using testing::crossBackendTolerance;
using testing::stepBothAndExpectNear;

// Per-frame input of one scene (include/stabint/batch.hpp) on the device as on the CPU batch, which
// follows each scene's own Simulator given the same calls (tests/test_batch_input.cpp): forces on
// the cloth, a grab of it (the later scenes' pins move in the pin list) dragged and released, one
// of its pins disabled, the bar's tets softened, a list of the cloth's springs stiffened (a
// refactorization), the bar's state set (moved and thrown; not with BDF2, which restarts only a
// batch of one), the chain's pin dragged; then the contact batch with a box dragged in one scene
// and a ground moved in another. Every scene within the cross-backend tolerance of the CPU batch,
// for the integrators those tests compare across backends.
TEST(OpenCLBatchSimulator, InputFollowsTheCpuBatch) {
  const std::vector<Scene> mixed = testing::mixedBatchScenes();
  const std::vector<Scene> scenes = {mixed[1], mixed[2], mixed[0]};
  const Scene& cloth = scenes[0];
  std::vector<int> springs;
  for (int i = 0; i < 70; ++i) springs.push_back(i);
  const std::function<void(BatchSimulator&, int)> input = [&](BatchSimulator& batch, int step) {
    if (step < 20) {
      Eigen::MatrixX3d f(cloth.numParticles(), 3);
      for (int j = 0; j < f.rows(); ++j) f.row(j) << 0.02 * std::sin(0.3 * step + j), 0.01, 0.02 * std::cos(0.2 * step);
      batch.setExternalForces(0, f);
    }
    batch.setPinTarget(2, 0, scenes[2].pins[0].target.position + Eigen::Vector3d(0.003 * step, 0.0, 0.0));
    if (step == 3) batch.setElementEnabled(0, ElementKind::Pin, 1, false);
    if (step == 5) {
      EXPECT_EQ(batch.grab(0, 12, 5e2), 2);
    }
    if (step > 5 && step < 20)
      batch.setPinTarget(0, 2, cloth.positions.row(12).transpose() + Eigen::Vector3d(0.0, 0.01 * step, 0.0));
    if (step == 8)
      batch.setElementStiffness(1, ElementKind::Tet, std::vector<int>{0, 1, 2}, 0.5 * scenes[1].tets[0].stiffness);
    if (step == 12) batch.setElementStiffness(0, ElementKind::Spring, springs, 2.0 * cloth.springs[0].stiffness);
    if (step == 15 && batch.options().integrator != Integrator::BDF2) {  // BDF2: a batch of one only
      Eigen::MatrixX3d x = batch.positions(1), v = batch.velocities(1);
      x.col(1).array() += 0.01;
      v.col(0).array() += 0.2;
      batch.setState(1, x, v);
    }
    if (step == 20) batch.release(0, 2);
  };
  const std::vector<Scene> contact = testing::contactBatchScenes();
  const std::function<void(BatchSimulator&, int)> move_colliders = [&](BatchSimulator& batch, int step) {
    batch.setColliderPosition(0, 2, contact[0].colliders[2].center + Eigen::Vector3d(0.02 * step, 0.0, 0.0));
    if (step == 10) batch.setColliderVelocity(2, 0, Eigen::Vector3d(0.0, 0.2, 0.0));
    if (step == 20) batch.setColliderVelocity(2, 0, Eigen::Vector3d::Zero());
  };
  for (Precision precision : availablePrecisions()) {
    const double tol = crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      SCOPED_TRACE(std::string(precisionName(precision)) + " " + integratorName(integrator));
      const BatchCase c{integrator, 1.0 / 60.0, 30};
      for (const bool colliders : {false, true}) {
        const std::vector<Scene>& batch_scenes = colliders ? contact : scenes;
        BatchSimulator opencl(batch_scenes, batchOptions(c, BackendKind::OpenCL, precision));
        BatchSimulator cpu(batch_scenes, batchOptions(c, BackendKind::CpuReference, precision));
        for (int step = 0; step < c.steps; ++step) {
          for (BatchSimulator* batch : {&opencl, &cpu}) (colliders ? move_colliders : input)(*batch, step);
          stepBothAndExpectNear(opencl, cpu, tol, step);
          for (int s = 0; s < cpu.size(); ++s)
            EXPECT_LT(testing::relativeError(opencl.positions(s), cpu.positions(s)), tol)
                << "scene " << s << " step " << step;
        }
      }
    }
  }
}

// A scene's setState writes its rows alone (Backend::writeRows): the host copies are still what the
// slots hold, the scene's rows as the device stores the new state (rounded to float there) and
// every other scene's as the device holds them (rounded too, as a read of the whole slots would
// give them, before any step), and the event is booked from the scene's own potential.
TEST(OpenCLBatchSimulator, SetStateLeavesEveryHostCopyWhatTheSlotsHold) {
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const auto stored = [&](const Eigen::MatrixX3d& m) -> Eigen::MatrixX3d {
      if (precision == Precision::Double) return m;
      return m.cast<float>().cast<double>();
    };
    const BatchCase c{Integrator::BackwardEuler, 1.0 / 60.0, 3};
    BatchSimulator batch(scenes, batchOptions(c, BackendKind::OpenCL, precision));
    const Eigen::MatrixX3d x = testing::perturbed(scenes[1].positions, 0.02, 12);
    const Eigen::MatrixX3d v = testing::perturbed(scenes[1].velocities, 0.3, 13);
    const double target_before = batch.target(0);
    batch.setState(1, x, v);
    EXPECT_EQ(batch.positions(1), stored(x));
    EXPECT_EQ(batch.velocities(1), stored(v));
    for (int s : {0, 2, 3}) EXPECT_EQ(batch.positions(s), stored(scenes[std::size_t(s)].positions)) << "scene " << s;
    EXPECT_EQ(batch.target(0), target_before);  // the event is scene 1's alone
    // The scene's energies are those of the state it holds: a CPU batch given the stored state.
    BatchSimulator cpu(scenes, batchOptions(c, BackendKind::CpuReference, precision));
    cpu.setState(1, stored(x), stored(v));
    const double tol = crossBackendTolerance(precision) * cpu.energyScale(1);
    EXPECT_NEAR(batch.energy(1).elastic, cpu.energy(1).elastic, tol);
    EXPECT_NEAR(batch.energy(1).external, cpu.energy(1).external, tol);
    EXPECT_EQ(batch.energy(1).kinetic, cpu.energy(1).kinetic);
    EXPECT_NEAR(batch.target(1), cpu.target(1), tol);
    for (int step = 0; step < c.steps; ++step)
      stepBothAndExpectNear(batch, cpu, crossBackendTolerance(precision), step);
  }
}

// setStates on the device (one pass over the listed scenes' elements, one wait) is bit for bit
// the same setState calls one by one there, in double and float, on the contact batch.
TEST(OpenCLBatchSimulator, SetStatesIsTheSameCallsOneByOne) {
  const std::vector<Scene> scenes = testing::contactBatchScenes();
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const BatchCase c{Integrator::EnergyBlend, 1.0 / 60.0, 4};
    const SimulatorOptions options = batchOptions(c, BackendKind::OpenCL, precision);
    BatchSimulator together(scenes, options), apart(scenes, options);
    for (int step = 0; step < 3; ++step) {
      together.step();
      apart.step();
    }
    const std::vector<int> list = {2, 0, 1};
    std::vector<Eigen::MatrixX3d> x, v;
    for (int s : list) {
      x.push_back(testing::perturbed(together.positions(s), 0.01, 20 + s));
      v.push_back(testing::perturbed(together.velocities(s), 0.2, 30 + s));
    }
    together.setStates(list, x, v);
    for (std::size_t i = 0; i < list.size(); ++i) apart.setState(list[i], x[i], v[i]);
    for (int step = 0; step <= c.steps; ++step) {
      for (int s = 0; s < together.size(); ++s) {
        ASSERT_EQ(together.positions(s), apart.positions(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(together.target(s), apart.target(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(together.energy(s).elastic, apart.energy(s).elastic) << "scene " << s << ", step " << step;
      }
      together.step();
      apart.step();
    }
    // 300 chains: the per-scene sums span several work-groups (merged into one launch where they
    // are adjacent); every third scene set.
    ChainPendulumParams params;
    params.particles = 4;
    const std::vector<Scene> chains(300, makeChainPendulum(params));
    BatchSimulator many(chains, options), one_by_one(chains, options);
    many.step();
    one_by_one.step();
    std::vector<int> every_third;
    std::vector<Eigen::MatrixX3d> xs, vs;
    for (int s = 299; s >= 0; s -= 3) {
      every_third.push_back(s);
      xs.push_back(testing::perturbed(many.positions(s), 0.05, s));
      vs.push_back(testing::perturbed(many.velocities(s), 0.5, 1000 + s));
    }
    many.setStates(every_third, xs, vs);
    for (std::size_t i = 0; i < every_third.size(); ++i) one_by_one.setState(every_third[i], xs[i], vs[i]);
    for (int s = 0; s < many.size(); ++s) {
      ASSERT_EQ(many.target(s), one_by_one.target(s)) << "scene " << s;
      ASSERT_EQ(many.energy(s).elastic, one_by_one.energy(s).elastic) << "scene " << s;
    }
    EXPECT_NE(many.target(299), many.target(298));  // the set scenes booked their events
  }
}

// Element changes of several scenes booked at the step (one pass over those scenes' elements,
// one wait) are bit for bit the same changes each read right after it on the device, in double
// and float (the CPU batch's test: BatchInputEvents in tests/test_batch_input.cpp).
TEST(OpenCLBatchSimulator, ElementChangesBookedAtTheStepAreTheChangesBookedAtOnce) {
  const std::vector<Scene> scenes = testing::mixedBatchScenes();
  for (Precision precision : availablePrecisions()) {
    SCOPED_TRACE(precisionName(precision));
    const BatchCase c{Integrator::EnergyBlend, 1.0 / 60.0, 4};
    const SimulatorOptions options = batchOptions(c, BackendKind::OpenCL, precision);
    BatchSimulator at_once(scenes, options), at_step(scenes, options);
    at_once.step();
    at_step.step();
    testing::changeElementsOfSeveralScenes(at_once, scenes, /*read_after_each=*/true);
    testing::changeElementsOfSeveralScenes(at_step, scenes, /*read_after_each=*/false);
    for (int step = 0; step < c.steps; ++step) {
      const BatchStepReport& a = at_once.step();
      const BatchStepReport& b = at_step.step();
      for (int s = 0; s < at_once.size(); ++s) {
        ASSERT_EQ(a.scenes[std::size_t(s)].event_energy, b.scenes[std::size_t(s)].event_energy) << "scene " << s;
        if (step == 0) {
          EXPECT_NE(b.scenes[std::size_t(s)].event_energy, 0.0) << "scene " << s;
        }
        ASSERT_EQ(at_once.positions(s), at_step.positions(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(at_once.target(s), at_step.target(s)) << "scene " << s << ", step " << step;
        ASSERT_EQ(at_once.energy(s).elastic, at_step.energy(s).elastic) << "scene " << s << ", step " << step;
      }
    }
  }
}

}  // namespace
}  // namespace stabint
