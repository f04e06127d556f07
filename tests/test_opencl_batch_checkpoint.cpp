// Checkpoints of a batch on OpenCL (include/stabint/batch.hpp; the CPU tests are
// tests/test_batch_checkpoint.cpp): the checkpoint reads the device's slots and a restore writes
// them, through the Backend interface, so a new device batch restored from a checkpoint continues
// bit for bit as the batch it was taken from (the device's sums are in a fixed order, so the same
// slots give the same numbers), in double and float, with colliders, collider motion, forces and a
// refused scene.
#include <stabint/batch.hpp>
#include <stabint/errors.hpp>

#include "batch_scenes.hpp"
#include "opencl_batch_support.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::availablePrecisions;
using testing::BatchCase;
using testing::batchOptions;

// Every scene's positions, velocities and target after each of `steps` steps.
std::vector<std::vector<double>> run(BatchSimulator& batch, int steps) {
  std::vector<std::vector<double>> out;
  for (int i = 0; i < steps; ++i) {
    batch.step();
    std::vector<double> values;
    for (int s = 0; s < batch.size(); ++s) {
      const Eigen::MatrixX3d x = batch.positions(s), v = batch.velocities(s);
      values.insert(values.end(), x.data(), x.data() + x.size());
      values.insert(values.end(), v.data(), v.data() + v.size());
      values.push_back(batch.target(s));
      values.push_back(batch.active(s) ? 1.0 : 0.0);
    }
    out.push_back(values);
  }
  return out;
}

TEST(OpenCLBatchSimulator, CheckpointRestoresBitForBitInANewBatch) {
  std::vector<Scene> scenes = testing::contactBatchScenes();
  scenes.push_back(testing::mixedBatchScenes()[0]);
  scenes[3].colliders.push_back(testing::groundPlane(-5.0, 1e4, 0.5));  // far below the chain
  for (Precision precision : availablePrecisions()) {
    for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
      SCOPED_TRACE(std::string(precisionName(precision)) + " " + integratorName(integrator));
      SimulatorOptions options = batchOptions(BatchCase{integrator, 1.0 / 60.0, 0}, BackendKind::OpenCL, precision);
      options.energy_limit = 1e2;
      BatchSimulator batch(scenes, options);
      for (int step = 0; step < 15; ++step) {
        if (step < 10) batch.setExternalForces(1, Eigen::MatrixX3d::Constant(scenes[1].numParticles(), 3, 0.01 * step));
        batch.setColliderPosition(0, 2, scenes[0].colliders[2].center + Eigen::Vector3d(0.01 * step, 0.0, 0.0));
        // The final projection lifts the chain by a kilometre: energy H* does not have, refused.
        if (step == 8) batch.setColliderPosition(3, 0, batch.colliderPosition(3, 0) + Eigen::Vector3d(0.0, 1e3, 0.0));
        batch.step();
      }
      EXPECT_FALSE(batch.active(3));
      const BatchCheckpoint checkpoint = batch.checkpoint();
      const std::vector<std::vector<double>> original = run(batch, 10);
      BatchSimulator fresh(scenes, options);
      fresh.restore(BatchCheckpoint::fromBytes(checkpoint.bytes()));
      const std::vector<std::vector<double>> restored = run(fresh, 10);
      for (std::size_t i = 0; i < original.size(); ++i) EXPECT_TRUE(restored[i] == original[i]) << "step " << i;
    }
  }
}

}  // namespace
}  // namespace stabint
