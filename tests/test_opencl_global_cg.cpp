// GlobalSolve::ConjugateGradient on the OpenCL device (host/opencl/device_solver.*,
// kernels/cg.cl) against its CPU reference (GlobalSystem::solveConjugateGradient, the same
// algorithm in double) and against the CHOLMOD factor: local/global solves and whole runs agree
// at the cross-backend tolerances of test_opencl_support.hpp, the device solves to the requested
// tolerance, and its copy of L follows grabs and stiffness changes.
#include <stabint/stabint.hpp>

#include "cpu/cpu_backend.hpp"
#include "opencl/opencl_backend.hpp"
#include "scene/scene_data.hpp"
#include "solver/global_system.hpp"
#include "solver/local_global.hpp"
#include "test_opencl_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace stabint {
namespace {

using testing::crossBackendTolerance;
using testing::openclOptions;
using testing::relativeError;

enum { kX, kY, kScratch, kSlots };

Scene clothScene() {
  ClothGridParams p;
  p.nx = 12;
  p.ny = 10;
  return makeClothGrid(p);
}

Scene tetScene() {
  TetBarParams p;
  p.nx = 6;
  p.ny = 2;
  p.nz = 2;
  p.stiffness = 2e4;
  return makeTetBar(p);
}

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
  IterationControl control{iterations, 0.0, iterations, 1.0};
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
  for (const Scene& s : {clothScene(), tetScene()}) {
    const SceneData data(s);
    for (const int cg : {1, 5, 20}) {
      auto cpu = makeCpuBackend(data, kSlots);
      auto device = makeOpenCLBackend(data, kSlots, openclOptions(p));
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
  for (const Scene& s : {clothScene(), tetScene()}) {
    const SceneData data(s);
    auto cpu = makeCpuBackend(data, kSlots);
    auto device = makeOpenCLBackend(data, kSlots, openclOptions(p));
    const Eigen::MatrixX3d exact = solveOn(*cpu, data, s, IterationControl{1, 0.0, 1, 1.0});
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
  const Scene s = clothScene();
  for (const Integrator integrator : testing::crossBackendIntegrators(p)) {
    SimulatorOptions o;
    o.integrator = integrator;
    o.global_solve = GlobalSolve::ConjugateGradient;
    o.cg_iterations = 10;
    SimulatorOptions device_options = o;
    device_options.backend = BackendKind::OpenCL;
    device_options.opencl = openclOptions(p);
    Simulator cpu(s, o), device(s, device_options);
    for (Simulator* sim : {&cpu, &device}) {
      for (int n = 0; n < 5; ++n) sim->step();
      const int pin = sim->grab(40, 1e4);
      sim->setPinTarget(pin, sim->pinTarget(pin) + Eigen::Vector3d(0.1, 0.2, 0.0));
      for (int n = 0; n < 5; ++n) sim->step();
      sim->setElementStiffness(ElementKind::Spring, {0, 1, 2, 3}, 10.0);
      sim->release(pin);
      for (int n = 0; n < 5; ++n) sim->step();
    }
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

INSTANTIATE_TEST_SUITE_P(Precisions, OpenCLGlobalCgTest, ::testing::Values(Precision::Double, Precision::Float),
                         [](const auto& info) { return testing::precisionName(info.param); });

}  // namespace
}  // namespace stabint
