// GlobalSolve::ConjugateGradient on the OpenCL device (host/opencl/device_solver.*,
// kernels/cg.cl) against its CPU reference (GlobalSystem::solveConjugateGradient, the same
// algorithm in double) and against the CHOLMOD factor: local/global solves and whole runs agree
// at the cross-backend tolerances of test_opencl_support.hpp, the device solves to the requested
// tolerance, and its copy of L follows grabs and stiffness changes.
#include <stabint/stabint.hpp>

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"
#include "test_opencl_support.hpp"
#include "contact_scenes.hpp"
#include "global_cg_scenes.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace stabint {
namespace {

using testing::crossBackendTolerance;
using testing::openclOptions;
using testing::relativeError;

enum { kX, kY, kScratch, kSlots };

using testing::cgClothScene;
using testing::cgTetScene;

Eigen::MatrixX3d stretched(const Scene& s) {
  Eigen::MatrixX3d y = s.positions;
  y.col(0) *= 1.2;
  y.col(2) += 0.2 * s.positions.col(1).cwiseProduct(s.positions.col(0));
  return y;
}

// One local/global solve of `iterations` iterations from y with `control` on a backend.
Eigen::MatrixX3d solveOn(Backend& backend, const SceneData& data, const Scene& s, const IterationControl& control) {
  GlobalSystem system(data);
  LocalGlobalSolver solver(backend, system, kScratch);
  const Eigen::MatrixX3d y = stretched(s);
  backend.write(kY, y);
  backend.write(kX, y);
  const double h = 1.0 / 30.0;
  solver.solve(4.0 / (h * h), kY, kX, h, control);
  Eigen::MatrixX3d x;
  backend.read(kX, x);
  return x;
}

IterationControl cgControl(int iterations, int cg_iterations, double cg_tolerance) {
  IterationControl control = IterationControl::plain(iterations);
  control.global_solve = GlobalSolve::ConjugateGradient;
  control.cg_iterations = cg_iterations;
  control.cg_tolerance = cg_tolerance;
  return control;
}

class OpenCLGlobalCgTest : public ::testing::TestWithParam<Precision> {};

// The same local/global iterations with the same fixed CG count: the device's CG and the host's
// are one algorithm, so they agree to the cross-backend tolerance (double: round-off of
// different summation orders, measured 3e-14; float: its precision, measured 9e-7).
TEST_P(OpenCLGlobalCgTest, FixedCountAgreesWithTheCpuReference) {
  const Precision p = GetParam();
  STABINT_SKIP_WITHOUT_OPENCL(p);
  for (const Scene& s : {cgClothScene(), cgTetScene()}) {
    const SceneData data(s);
    Forcing forcing(data.scene());
    for (const int cg : {1, 5, 20}) {
      auto cpu = makeCpuBackend(data, forcing, kSlots);
      auto device = makeOpenCLBackend(data, forcing, kSlots, openclOptions(p));
      const IterationControl control = cgControl(5, cg, 0.0);
      const Eigen::MatrixX3d reference = solveOn(*cpu, data, s, control);
      const Eigen::MatrixX3d x = solveOn(*device, data, s, control);
      EXPECT_LE(relativeError(x, reference), crossBackendTolerance(p)) << "cg " << cg;
    }
  }
}

// One local/global iteration: the same local step, then the device's CG to a relative residual
// of 1e-10 (double) or 1e-5 (float, near its round-off); the result matches the factor's global
// step within cond(K) times that (K_c is dominated by c M: measured 2e-11 and 3e-6 against the
// bound 100 tolerance).
TEST_P(OpenCLGlobalCgTest, SolvesToTheRequestedToleranceAgainstTheFactor) {
  const Precision p = GetParam();
  STABINT_SKIP_WITHOUT_OPENCL(p);
  const double tolerance = p == Precision::Double ? 1e-10 : 1e-5;
  for (const Scene& s : {cgClothScene(), cgTetScene()}) {
    const SceneData data(s);
    Forcing forcing(data.scene());
    auto cpu = makeCpuBackend(data, forcing, kSlots);
    auto device = makeOpenCLBackend(data, forcing, kSlots, openclOptions(p));
    const Eigen::MatrixX3d exact = solveOn(*cpu, data, s, IterationControl::plain(1));
    const Eigen::MatrixX3d x = solveOn(*device, data, s, cgControl(1, 1000, tolerance));
    EXPECT_LE(relativeError(x, exact), 100.0 * tolerance);
  }
}

// Whole runs of the integrators (the blend included: its BE and IM solves use two c with no
// factor) with a grab, a drag, a stiffness change and a release in the middle: the device's L
// follows each change, and the run agrees with the CPU reference's CG run (measured for the blend
// in double 2e-10 for positions, float 1.2e-5 for BDF2).
TEST_P(OpenCLGlobalCgTest, RunsWithElementChangesAgreeWithTheCpuReference) {
  const Precision p = GetParam();
  STABINT_SKIP_WITHOUT_OPENCL(p);
  const Scene s = cgClothScene();
  for (const Integrator integrator : testing::crossBackendIntegrators(p)) {
    SimulatorOptions o;
    o.integrator = integrator;
    o.global_solve = GlobalSolve::ConjugateGradient;
    o.cg_iterations = 10;
    SimulatorOptions device_options = o;
    device_options.backend = BackendKind::OpenCL;
    device_options.opencl = openclOptions(p);
    Simulator cpu(s, o), device(s, device_options);
    for (Simulator* sim : {&cpu, &device}) testing::stepWithChangesOfL(*sim);
    EXPECT_LE(relativeError(device.positions(), cpu.positions()), crossBackendTolerance(p))
        << integratorName(integrator);
    // Velocities against max(|v|, |x| / h), as test_opencl_integrators: they are differences of
    // positions over h.
    const double v_scale =
        std::max(cpu.velocities().cwiseAbs().maxCoeff(), cpu.positions().cwiseAbs().maxCoeff() / o.time_step);
    EXPECT_LE((device.velocities() - cpu.velocities()).cwiseAbs().maxCoeff() / v_scale, crossBackendTolerance(p))
        << integratorName(integrator);
  }
}

// The paths around the device CG that read back: the objective tracking of a solve to an outer
// tolerance (the energy of every local step), and the accelerations, whose extrapolation runs on
// the host (each iteration reads the CG's result back). Double only: in float the accelerations'
// accept/reject decisions may differ from the CPU's (test_opencl_support.hpp).
TEST(OpenCLGlobalCg, TrackedAndAcceleratedSolvesAgreeWithTheCpuReference) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Scene s = cgTetScene();
  const SceneData data(s);
  Forcing forcing(data.scene());
  for (const Acceleration acceleration :
       {Acceleration::None, Acceleration::Chebyshev, Acceleration::Anderson, Acceleration::LBFGS}) {
    IterationControl control = cgControl(15, 8, 0.0);
    control.acceleration = acceleration;
    control.tolerance = acceleration == Acceleration::None ? 1e-9 : 0.0;  // tracked to a tolerance
    control.max_iterations = 15;
    control.energy_scale = 1.0;
    auto cpu = makeCpuBackend(data, forcing, kSlots);
    auto device = makeOpenCLBackend(data, forcing, kSlots, openclOptions(Precision::Double));
    const Eigen::MatrixX3d reference = solveOn(*cpu, data, s, control);
    const Eigen::MatrixX3d x = solveOn(*device, data, s, control);
    // Measured 5e-16: the same iterates and the same decisions.
    EXPECT_LE(relativeError(x, reference), crossBackendTolerance(Precision::Double)) << accelerationName(acceleration);
  }
}

// A device run with converged CG steps against the CPU reference's factor run, both BE.
// Each global step leaves a relative residual <= 1e-12, an error up to cond(K_c) times that
// (the stiff cloth's K_c is far less well conditioned than the tet bar's): measured 1.1e-10
// after 10 steps of the cloth.
void expectDeviceCgTracksTheFactorRun(const Scene& s, int steps) {
  SimulatorOptions factor_options;
  factor_options.integrator = Integrator::BackwardEuler;
  SimulatorOptions o = testing::convergedCgOptions();
  o.backend = BackendKind::OpenCL;
  o.opencl = openclOptions(Precision::Double);
  Simulator factor(s, factor_options), device(s, o);
  for (int n = 0; n < steps; ++n) factor.step(), device.step();
  EXPECT_LE(relativeError(device.positions(), factor.positions()), 1e-8);
}

// cg_tolerance reaches the device: with a tight tolerance and a large iteration cap the run ends
// where the factor's does.
TEST(OpenCLGlobalCg, ToleranceOptionMatchesTheFactorRun) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  expectDeviceCgTracksTheFactorRun(cgClothScene(), 10);
}

// The contact set changes L at step starts: the device's copy of L follows (a stale one, without
// the contact weights, misses by a relative 14). A cloth dropped onto every collider shape.
TEST(OpenCLGlobalCg, ContactSetChangesFollowTheFactorRun) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  expectDeviceCgTracksTheFactorRun(testing::clothOnColliders(), 30);
}

// With cg_tolerance the device stops once the residual is small enough: a looser tolerance takes
// fewer CG iterations, and neither needs the cap.
TEST(OpenCLGlobalCg, ToleranceStopsEarly) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Scene s = cgClothScene();
  const SceneData data(s);
  Forcing forcing(data.scene());
  GlobalSystem system(data);
  auto device = makeOpenCLBackend(data, forcing, kSlots, openclOptions(Precision::Double));
  device->setGlobalMatrix(system.stiffnessLaplacian());
  const Eigen::MatrixX3d y = stretched(s);
  const double h = 1.0 / 30.0, c = 1.0 / (h * h);
  auto iterationsFor = [&](double tolerance) {
    device->write(kY, y);
    device->write(kX, y);
    device->localStep(kX, kY, c, h, nullptr);
    return device->solveGlobal(c, kX, 5000, tolerance);
  };
  const int loose = iterationsFor(1e-3), tight = iterationsFor(1e-10);
  EXPECT_GT(loose, 0);
  EXPECT_LT(loose, tight);
  EXPECT_LT(tight, 5000);
}

INSTANTIATE_TEST_SUITE_P(Precisions, OpenCLGlobalCgTest, ::testing::Values(Precision::Double, Precision::Float),
                         [](const auto& info) { return precisionName(info.param); });

}  // namespace
}  // namespace stabint
