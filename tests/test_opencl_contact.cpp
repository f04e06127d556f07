// Colliders on the OpenCL backend: the contact element's projection (kernels/contact.cl) follows
// the CPU reference within the equivalence tolerances of test_opencl_integrators, on a cloth
// falling onto every shape with friction and a moving box, and checkpoints continue bit for bit.
#include "contact_scenes.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace stabint {
namespace {

using testing::relativeError;

struct ContactRun {
  std::vector<Eigen::MatrixX3d> x;
  std::vector<StepReport> reports;
  double energy_scale = 0.0;
};

ContactRun run(const Scene& scene, Integrator integrator, BackendKind backend, Precision precision, int steps) {
  SimulatorOptions o;
  o.integrator = integrator;
  o.backend = backend;
  o.opencl.precision = precision;
  Simulator sim(scene, o);
  ContactRun out;
  out.energy_scale = sim.energyScale();
  for (int i = 0; i < steps; ++i) {
    out.reports.push_back(sim.step());
    out.x.push_back(sim.positions());
  }
  return out;
}

TEST(OpenCLContact, ClothOnCollidersMatchesCpu) {
  const Scene scene = testing::clothOnColliders();
  for (Precision precision : {Precision::Double, Precision::Float}) {
    const std::string skip = testing::openclSkipReason(precision);
    if (!skip.empty()) {
      std::printf("  %s skipped: %s\n", testing::precisionName(precision), skip.c_str());
      continue;
    }
    const std::vector<Integrator> integrators = testing::crossBackendIntegrators(precision);
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : integrators) {
      const ContactRun ref = run(scene, integrator, BackendKind::CpuReference, Precision::Double, 30);
      const ContactRun got = run(scene, integrator, BackendKind::OpenCL, precision, 30);
      double friction = 0.0;
      for (std::size_t i = 0; i < ref.x.size(); ++i) {
        const std::string what = std::string(integratorName(integrator)) + " " + testing::precisionName(precision) +
                                 " step " + std::to_string(i);
        EXPECT_LT(relativeError(got.x[i], ref.x[i]), tol) << what;
        EXPECT_NEAR(got.reports[i].friction, ref.reports[i].friction, tol * ref.energy_scale) << what;
        EXPECT_NEAR(got.reports[i].forcing, ref.reports[i].forcing, tol * ref.energy_scale) << what;
        EXPECT_NEAR(got.reports[i].target, ref.reports[i].target, tol * ref.energy_scale) << what;
        friction += ref.reports[i].friction;
      }
      EXPECT_GT(friction, 0.0) << "the cloth must reach the colliders within the run";
    }
  }
}

TEST(OpenCLContact, CheckpointsContinueBitForBit) {
  const Scene scene = testing::clothOnColliders();
  for (Precision precision : {Precision::Double, Precision::Float}) {
    if (!testing::openclSkipReason(precision).empty()) continue;
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
    for (int i = 0; i < 10; ++i)
      EXPECT_EQ((other.step(), other.positions()), original[i]) << testing::precisionName(precision);
  }
}

}  // namespace
}  // namespace stabint
