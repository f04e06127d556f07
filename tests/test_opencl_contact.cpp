// Colliders on the OpenCL backend: the contact element's projection (kernels/contact.cl) follows
// the CPU reference within the equivalence tolerances of test_opencl_integrators, on a cloth
// falling onto every shape with friction and a moving box, and checkpoints continue bit for bit.
#include "contact_scenes.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace stabint {
namespace {

using testing::relativeError;

struct ContactRun {
  std::vector<Eigen::MatrixX3d> x;
  std::vector<StepReport> reports;
  double energy_scale = 0.0;
};

// `input(sim)` runs before each step (run-time collider motion).
ContactRun run(const Scene& scene, Integrator integrator, BackendKind backend, Precision precision, int steps,
               const std::function<void(Simulator&)>& input = nullptr, int contact_release = 0) {
  SimulatorOptions o;
  o.integrator = integrator;
  o.contact_release = contact_release;
  o.backend = backend;
  o.opencl.precision = precision;
  Simulator sim(scene, o);
  ContactRun out;
  out.energy_scale = sim.energyScale();
  for (int i = 0; i < steps; ++i) {
    if (input) input(sim);
    out.reports.push_back(sim.step());
    out.x.push_back(sim.positions());
  }
  return out;
}

// The device's run against the CPU reference's, step by step, within `tol`: positions (relative
// to their size), and friction, forcing and the target (relative to E_scale). Returns the
// reference's friction and |forcing| summed over the run, for the callers' checks that the run
// reached what it tests.
struct Reached {
  double friction = 0.0, forcing = 0.0;
};
Reached expectFollowsCpu(const ContactRun& got, const ContactRun& ref, double tol, const std::string& what) {
  Reached reached;
  for (std::size_t i = 0; i < ref.x.size(); ++i) {
    const std::string step = what + " step " + std::to_string(i);
    EXPECT_LT(relativeError(got.x[i], ref.x[i]), tol) << step;
    EXPECT_NEAR(got.reports[i].friction, ref.reports[i].friction, tol * ref.energy_scale) << step;
    EXPECT_NEAR(got.reports[i].forcing, ref.reports[i].forcing, tol * ref.energy_scale) << step;
    EXPECT_NEAR(got.reports[i].target, ref.reports[i].target, tol * ref.energy_scale) << step;
    reached.friction += ref.reports[i].friction;
    reached.forcing += std::abs(ref.reports[i].forcing);
  }
  return reached;
}

TEST(OpenCLContact, ClothOnCollidersMatchesCpu) {
  const Scene scene = testing::clothOnColliders();
  for (Precision precision : testing::availablePrecisions()) {
    const std::vector<Integrator> integrators = testing::crossBackendIntegrators(precision);
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : integrators) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 30);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 30);
      const Reached reached =
          expectFollowsCpu(got, ref, tol, std::string(integratorName(integrator)) + " " + precisionName(precision));
      EXPECT_GT(reached.friction, 0.0) << "the cloth must reach the colliders within the run";
    }
  }
}

// Contact pairs leaving within the solve (SimulatorOptions::contact_release) on a cloth lifted off
// the ground by a hand (test_contact's ReleasedPairsLetALiftedClothFollowItsHand): the device
// releases and returns the CPU reference's pairs, within the same tolerances (measured in float:
// 3e-6 of the positions for BE, 8e-3 for the blend, whose root finds amplify the float rounding;
// 7e-4 and 0.13 with the step's set kept).
TEST(OpenCLContact, ReleasedPairsMatchCpu) {
  Scene scene = testing::horizontalCloth(20, 0.005);
  scene.colliders = {testing::groundPlane(0.0, Collider{}.stiffness, 0.5)};
  const int held = testing::edgeMiddle(scene);
  const Eigen::Vector3d start = scene.positions.row(held).transpose();
  int hand = -1;
  auto input = [&](Simulator& sim) {
    if (sim.stepCount() == 0) hand = sim.grab(held, 1e4);
    const double t = sim.time() + sim.options().time_step;
    sim.setPinTarget(hand, start + Eigen::Vector3d(0.0, std::min(0.8, t), 0.4 * t));
  };
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 30, input, 1);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 30, input, 1);
      const std::string what = std::string(integratorName(integrator)) + " " + precisionName(precision);
      EXPECT_GT(expectFollowsCpu(got, ref, tol, what).forcing, 0.0) << what << ": the hand must do work";
    }
  }
}

// A tet bar at 10 m/s onto a 2 cm thick box (test_contact's FastBodiesDoNotPassThroughThinColliders):
// the pairs' half-spaces, derived on the host and uploaded with the contact params, give the
// device the CPU reference's motion within the same tolerances, and no vertex of the device's
// run goes below the box's middle.
TEST(OpenCLContact, FastBarOnAThinBoxMatchesCpu) {
  Scene scene = testing::freeBar(0.05);
  scene.velocities.col(1).setConstant(-10.0);
  scene.colliders.push_back(
      testing::boxCollider(Eigen::Vector3d(0.5, -0.01, 0.125), Eigen::Vector3d(2.0, 0.01, 2.0), 1e4));
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 20);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 20);
      for (std::size_t i = 0; i < ref.x.size(); ++i) {
        const std::string what =
            std::string(integratorName(integrator)) + " " + precisionName(precision) + " step " + std::to_string(i);
        EXPECT_LT(relativeError(got.x[i], ref.x[i]), tol) << what;
        EXPECT_GT(got.x[i].col(1).minCoeff(), -0.01) << what;
      }
    }
  }
}

// Colliders moved at run time (Simulator::setColliderPosition every frame for the box, a velocity
// set at frame 6 for the sphere, once the cloth lies on it: BDF2's cloth bounces off it by frame
// 10): the same tolerances, the friction and forcing they book included.
TEST(OpenCLContact, CollidersMovedAtRunTimeMatchCpu) {
  const Scene scene = testing::clothOnColliders();
  auto input = [](Simulator& sim) {
    const double t = sim.time() + sim.options().time_step;
    sim.setColliderPosition(2, Eigen::Vector3d(-0.6 + 0.8 * t, -0.2, 0.15 * std::sin(4.0 * t)));
    if (sim.stepCount() == 6) sim.setColliderVelocity(0, Eigen::Vector3d(0.0, 0.3, 0.0));
  };
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 30, input);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 30, input);
      const std::string what = std::string(integratorName(integrator)) + " " + precisionName(precision);
      EXPECT_GT(expectFollowsCpu(got, ref, tol, what).forcing, 0.0)
          << what << ": the moved colliders must do work within the run";
    }
  }
}

// Mesh colliders (docs/method.md, "Mesh colliders"): a 12 x 12 cloth dropped onto an icosphere
// mesh of 1,280 triangles and a box mesh beside it that swings along z at run time
// (Simulator::setColliderPosition every frame) and meets the draping cloth from frame 25: the
// half-spaces the host derives from the meshes give the device the CPU reference's motion within
// the same tolerances, the work of the moved mesh included (measured: 1e-12 in double; in float
// 7e-4 before the box meets the cloth and 5.5e-3 after, with BDF2, whose impact amplifies the
// float run's difference).
TEST(OpenCLContact, MeshCollidersMatchCpu) {
  Scene scene = testing::horizontalCloth(12, 0.4);
  scene.colliders.push_back(testing::icosphereCollider(Eigen::Vector3d(0.0, 0.0, 0.0), 0.25, 3, 0.5));
  scene.colliders.push_back(testing::boxMeshCollider(Eigen::Vector3d(-0.35, 0.0, 0.0), Eigen::Vector3d(0.1, 0.1, 0.1)));
  scene.colliders.back().friction = 0.3;
  auto input = [](Simulator& sim) {
    const double t = sim.time() + sim.options().time_step;
    sim.setColliderPosition(1, Eigen::Vector3d(-0.35, 0.0, 0.15 * std::sin(4.0 * t)));
  };
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : testing::crossBackendIntegrators(precision)) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 30, input);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 30, input);
      const std::string what = std::string(integratorName(integrator)) + " " + precisionName(precision);
      const Reached reached = expectFollowsCpu(got, ref, tol, what);
      EXPECT_GT(reached.friction, 0.0) << what << ": the cloth must reach the sphere within the run";
      EXPECT_GT(reached.forcing, 0.0) << what << ": the moved box must reach the cloth within the run";
    }
  }
}

TEST(OpenCLContact, CheckpointsContinueBitForBit) {
  const Scene scene = testing::clothOnColliders();
  for (Precision precision : testing::availablePrecisions()) {
    SimulatorOptions o;
    o.backend = BackendKind::OpenCL;
    o.opencl.precision = precision;
    Simulator sim(scene, o);
    for (int i = 0; i < 15; ++i) sim.step();
    const Checkpoint c = sim.checkpoint();
    std::vector<Eigen::MatrixX3d> original;
    for (int i = 0; i < 10; ++i) original.push_back((sim.step(), sim.positions()));
    Simulator other(scene, o);
    other.restore(c);
    for (int i = 0; i < 10; ++i) EXPECT_EQ((other.step(), other.positions()), original[i]) << precisionName(precision);
  }
}

}  // namespace
}  // namespace stabint
