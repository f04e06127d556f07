// Whole simulations with the OpenCL backend against the CPU reference backend, for all six
// integrators: cloth and tet bar trajectories, and the blend's per-step decisions (branch,
// alpha) on the stiff chain pendulum.
//
// Scenes: a spring cloth, a triangle-element cloth and a tet bar.
//
// Tolerances: positions are compared relative to the largest entry of the reference (see
// relativeError), every step; velocities relative to max(max |v|, max |x| / h), because the
// implicit integrators form them as difference quotients (x* - x_n) / h, which turn position
// rounding of eps |x| into velocity errors of eps |x| / h even when the body is nearly at rest.
//   double: 1e-9. Per-operation differences are ~1e-15 (test_opencl_backend); 100+ steps of
//           a stiff simulation amplify them (measured on PoCL: at most 5e-12 for positions,
//           2e-12 for velocities). The explicit integrators run with a small step (see
//           options()) so that they, too, stay finite over the whole horizon.
//   float:  1e-3 over 30 steps (measured: at most 2e-6 for positions, 4e-5 for velocities of
//           the implicit integrators, 3e-4 for forward Euler on the cloth, whose energy grows
//           by (1 + (omega h)^2) per step and amplifies the rounding with it).
//           Each local step carries ~1e-7 relative rounding (float positions and
//           contributions) into the double solve; the solves are not iterated to convergence,
//           so the error accumulates step by step.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/simulator.hpp>

#include "test_opencl_support.hpp"
#include "triangle_cloth_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

namespace stabint {
namespace {

using testing::relativeError;

struct Trajectory {
  double energy_scale = 0.0;
  std::vector<Eigen::MatrixX3d> x, v;
  std::vector<StepReport> reports;
  int refused_at = -1;  // step that threw NonFiniteStateError, -1 if none
};

Trajectory simulate(const Scene& scene, SimulatorOptions options, int steps) {
  Trajectory run;
  Simulator sim(scene, options);
  run.energy_scale = sim.energyScale();
  for (int i = 0; i < steps; ++i) {
    try {
      run.reports.push_back(sim.step());
    } catch (const NonFiniteStateError& e) {
      run.refused_at = e.step();
      break;
    }
    run.x.push_back(sim.positions());
    run.v.push_back(sim.velocities());
  }
  return run;
}

bool isExplicit(Integrator i) { return i == Integrator::ForwardEuler || i == Integrator::SymplecticEuler; }

struct Worst {
  double x = 0.0, v = 0.0;
};

// Runs the scene on both backends and checks every step's state against the reference.
// Both must refuse the same step as non-finite (none is expected here), except in float, whose
// range (3e38) an exploding explicit simulation would leave many steps before double's (1e308):
// there only the steps both completed are compared.
Worst compareRuns(const Scene& scene, SimulatorOptions options, Precision precision, int steps, double tol) {
  options.backend = BackendKind::CpuReference;
  const Trajectory ref = simulate(scene, options, steps);
  options.backend = BackendKind::OpenCL;
  options.opencl.precision = precision;
  const Trajectory got = simulate(scene, options, steps);
  if (precision == Precision::Double || !isExplicit(options.integrator)) {
    EXPECT_EQ(got.refused_at, ref.refused_at) << "steps refused as non-finite differ";
  }
  // Every run here is meant to stay finite over the whole horizon (explicit ones use a small h),
  // so the comparison covers all the steps.
  EXPECT_EQ(ref.refused_at, -1) << "the reference run blew up";
  Worst worst;
  const std::size_t n = std::min(ref.x.size(), got.x.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double ex = relativeError(got.x[i], ref.x[i]);
    const double v_scale = std::max(ref.v[i].cwiseAbs().maxCoeff(), ref.x[i].cwiseAbs().maxCoeff() / options.time_step);
    const double ev = (got.v[i] - ref.v[i]).cwiseAbs().maxCoeff() / v_scale;
    worst.x = std::max(worst.x, ex);
    worst.v = std::max(worst.v, ev);
    if (ex > tol || ev > tol) {
      ADD_FAILURE() << "step " << i << ": positions " << ex << ", velocities " << ev << " relative error > " << tol;
      break;
    }
  }
  return worst;
}

Scene testCloth() {
  ClothGridParams p;
  p.nx = 10;
  p.ny = 10;
  return makeClothGrid(p);
}

Scene testTetBar() { return makeTetBar({}); }

// Triangle strain and bending hinges, flat and without strain limits. Within strain limits the
// membrane has no stiffness and its energy's second derivative jumps at the limits: IM and the
// blend then amplify round-off exponentially (measured: 1e-9 within 25-55 steps, from 1e-15 at
// step 1, on both backends alike), which would compare chaos rather than backends. The limits
// and curved rest shapes are compared operation by operation in test_opencl_backend.
Scene testTriangleCloth() { return testing::triangleCloth(10, 10, /*limits_and_dome=*/false); }

class OpenCLIntegratorTest : public ::testing::TestWithParam<Integrator> {
 protected:
  SimulatorOptions options() const {
    SimulatorOptions o;
    o.integrator = GetParam();
    o.iterations = 10;
    // The explicit integrators explode within a few real-time steps on these stiff scenes (the
    // pins' omega is ~2e4 rad/s); with h = 5e-5 (omega h ~ 1) they stay finite for 100+ steps, so
    // the comparison covers as many steps as for the implicit ones.
    if (isExplicit(GetParam())) o.time_step = 5e-5;
    // IM is unstable on this cloth: with Chebyshev-converged solves its energy grows from
    // 0.49 J to 3000 J within 40 steps and round-off grows with it (x3 every 3 steps from step
    // 12); with plain iterations it stays bounded over the horizon, so the backends are compared
    // there. OpenCLChebyshev below covers IM with acceleration before the blow-up.
    if (GetParam() == Integrator::ImplicitMidpoint) o.acceleration = Acceleration::None;
    return o;
  }
  double doubleTol() const { return 1e-9; }
};

TEST_P(OpenCLIntegratorTest, ClothMatchesCpuInDouble) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Worst w = compareRuns(testCloth(), options(), Precision::Double, 120, doubleTol());
  RecordProperty("worst_x", std::to_string(w.x));
  std::printf("  worst relative error: x %.3g, v %.3g\n", w.x, w.v);
}

TEST_P(OpenCLIntegratorTest, TetBarMatchesCpuInDouble) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Worst w = compareRuns(testTetBar(), options(), Precision::Double, 100, doubleTol());
  std::printf("  worst relative error: x %.3g, v %.3g\n", w.x, w.v);
}

TEST_P(OpenCLIntegratorTest, TriangleClothMatchesCpuInDouble) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Worst w = compareRuns(testTriangleCloth(), options(), Precision::Double, 120, doubleTol());
  std::printf("  worst relative error: x %.3g, v %.3g\n", w.x, w.v);
}

// Float with plain iterations: the same iterates in float arithmetic. With Chebyshev, the
// safeguard compares objectives whose float round-off (about 1e-7 of |U_ext|) can exceed an
// iteration's decrease, so float and double may keep different iterates; each such decision
// moves the iterate by a fraction of one iteration's update, hence the looser bound there.
TEST_P(OpenCLIntegratorTest, ClothAndTetBarFollowCpuInFloat) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  for (Acceleration acceleration : {Acceleration::None, Acceleration::Chebyshev}) {
    if (acceleration == Acceleration::Chebyshev && GetParam() == Integrator::ImplicitMidpoint) continue;
    SimulatorOptions o = options();
    o.acceleration = acceleration;
    const double tol = acceleration == Acceleration::None ? 1e-3 : 1e-2;
    const Worst t = compareRuns(testTetBar(), o, Precision::Float, 30, tol);
    const Worst c = compareRuns(testCloth(), o, Precision::Float, 30, tol);
    std::printf("  %s worst relative error: tet bar x %.3g v %.3g, cloth x %.3g v %.3g\n",
                accelerationName(acceleration), t.x, t.v, c.x, c.v);
    if (acceleration != Acceleration::None) continue;
    const Worst tc = compareRuns(testTriangleCloth(), o, Precision::Float, 30, tol);
    std::printf("  worst relative error: triangle cloth x %.3g v %.3g\n", tc.x, tc.v);
  }
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, OpenCLIntegratorTest, ::testing::ValuesIn(allIntegrators()),
                         [](const ::testing::TestParamInfo<Integrator>& info) {
                           std::string name = integratorName(info.param);
                           return name;
                         });

// Accelerated solves (Chebyshev, Anderson, L-BFGS): the safeguard or line search decides on objective comparisons,
// which agree between backends to round-off, so both take the same iterates. IM only over the
// steps before its energy takes off on this cloth (see OpenCLIntegratorTest::options).
TEST(OpenCLAcceleration, AcceleratedSolvesMatchCpu) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  for (Acceleration acceleration :
       {Acceleration::Chebyshev, Acceleration::Anderson, Acceleration::LBFGS, Acceleration::Newton}) {
    for (Integrator integrator :
         {Integrator::BackwardEuler, Integrator::BDF2, Integrator::ImplicitMidpoint, Integrator::EnergyBlend}) {
      SimulatorOptions o;
      o.integrator = integrator;
      o.acceleration = acceleration;
      const int steps = integrator == Integrator::ImplicitMidpoint ? 12 : 100;
      const Worst c = compareRuns(testCloth(), o, Precision::Double, steps, 1e-9);
      const Worst t = compareRuns(testTetBar(), o, Precision::Double, steps, 1e-9);
      std::printf("  %s %s worst relative error: cloth x %.3g, tet bar x %.3g\n", accelerationName(acceleration),
                  integratorName(integrator), c.x, t.x);
    }
  }
}

// In float the objective's round-off (1e-7 of it) is reached within a few L-BFGS iterations on a
// cloth near rest; there even the plain step fails the line search, and every later iteration
// would try it again from the same iterate. The solve stops there (docs/method.md, "L-BFGS"):
// under a loose gradient tolerance (1e-1, which the floor keeps out of reach) a step takes a few
// iterations, not the cap (before: 36 of 60 on average, most steps at the cap), and a larger cap
// changes nothing, bit for bit: no step ran into it.
TEST(OpenCLAcceleration, FloatSolvesStopAtTheirRoundOffFloor) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  ClothGridParams p;
  p.nx = p.ny = 10;
  p.stretch_stiffness = 100.0;
  const Scene scene = makeClothGrid(p);
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.acceleration = Acceleration::LBFGS;
  o.gradient_tolerance = 0.1;
  o.backend = BackendKind::OpenCL;
  o.opencl = testing::openclOptions(Precision::Float);
  o.iterations = 60;
  Simulator capped(scene, o);
  o.iterations = 100;
  Simulator wide(scene, o);
  int iterations = 0, most = 0;
  for (int step = 0; step < 20; ++step) {
    const int done = capped.step().iterations;
    EXPECT_EQ(wide.step().iterations, done) << "step " << step;
    iterations += done;
    most = std::max(most, done);
  }
  EXPECT_LT(most, 60);
  EXPECT_LT(iterations, 20 * 20) << "mean iterations per step " << iterations / 20.0;
  EXPECT_EQ(capped.positions(), wide.positions());
  EXPECT_EQ(capped.velocities(), wide.velocities());
}

// The blend's decisions depend on energy comparisons against its tolerance; with the energies
// of both backends equal to ~1e-15, every step takes the same branch with the same alpha.
TEST(OpenCLBlend, ChainPendulumBranchesAndAlphaMatchCpu) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  const Scene chain = makeChainPendulum({});
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  o.iterations = 10;
  o.backend = BackendKind::CpuReference;
  const Trajectory ref = simulate(chain, o, 50);
  o.backend = BackendKind::OpenCL;
  const Trajectory got = simulate(chain, o, 50);
  ASSERT_EQ(ref.reports.size(), 50u);
  ASSERT_EQ(got.reports.size(), 50u);
  const double swing = chain.masses.sum() * chain.gravity.norm() *
                       (chain.rest_positions.colwise().maxCoeff() - chain.rest_positions.colwise().minCoeff()).norm();
  int partner_steps = 0;
  double worst_alpha = 0.0;
  for (int i = 0; i < 50; ++i) {
    const StepReport& a = ref.reports[i];
    const StepReport& b = got.reports[i];
    EXPECT_EQ(blendBranchName(b.branch), std::string(blendBranchName(a.branch))) << "step " << i;
    EXPECT_NEAR(b.alpha, a.alpha, 1e-8) << "step " << i;
    EXPECT_EQ(b.iterations, a.iterations) << "step " << i;
    // H* starts at 0 here (at rest at gravity's zero): judge energies against the swing
    // energy m g L (~1 J), the scale of what the pendulum exchanges.
    EXPECT_NEAR(b.energy.total(), a.energy.total(), 1e-9 * swing) << "step " << i;
    EXPECT_NEAR(b.target, a.target, 1e-9 * swing) << "step " << i;
    if (a.branch != BlendBranch::ImplicitMidpoint) ++partner_steps;
    worst_alpha = std::max(worst_alpha, std::abs(b.alpha - a.alpha));
  }
  EXPECT_GT(partner_steps, 0) << "the test should exercise the BE/FE partners";
  std::printf("  %d partner steps, worst alpha difference %.3g\n", partner_steps, worst_alpha);
}

// The blend forms the blended state, the position move toward the partner and the velocity
// corrections on the host and writes them to the device (docs/method.md section 5, "Passes and
// waits per step"). The host's copies must be what the device holds: in float every position and
// velocity the simulator reports is a float, in every branch.
TEST(OpenCLBlend, HostStateIsWhatAFloatDeviceHolds) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  o.backend = BackendKind::OpenCL;
  o.opencl.precision = Precision::Float;
  Simulator sim(makeChainPendulum({}), o);
  auto holdsFloats = [](const Eigen::MatrixX3d& m) {
    return (m.cast<float>().cast<double>().array() == m.array()).all();
  };
  int blended = 0, scaled = 0;
  for (int i = 0; i < 60; ++i) {
    const StepReport& r = sim.step();
    blended += r.branch == BlendBranch::BackwardEuler && r.alpha > 0.0 && r.alpha < 1.0;
    scaled += r.velocity_scale != 1.0;
    ASSERT_TRUE(holdsFloats(sim.positions())) << "step " << i << ", branch " << blendBranchName(r.branch);
    ASSERT_TRUE(holdsFloats(sim.velocities())) << "step " << i << ", branch " << blendBranchName(r.branch);
  }
  EXPECT_GT(blended, 0) << "the test should blend with the BE partner";
  EXPECT_GT(scaled, 0) << "the test should correct the velocities";
}

TEST(OpenCLBlend, SimulatorReportsOpenCLBackendAndPhaseTimes) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  SimulatorOptions o;
  o.backend = BackendKind::OpenCL;
  Simulator sim(testCloth(), o);
  EXPECT_EQ(sim.backendDescription().rfind("OpenCL: ", 0), 0u) << sim.backendDescription();
  const StepReport& r = sim.step();
  EXPECT_GT(r.times.local, 0.0);
  EXPECT_GT(r.times.gather, 0.0);
  EXPECT_GT(r.times.transfer, 0.0);
  EXPECT_GT(r.times.energy, 0.0);
}

}  // namespace
}  // namespace stabint

namespace stabint {
namespace {

// Time-dependent forcing (a moving pin, a gusting force field) and damping: the OpenCL backend
// re-uploads pin targets and external forces whenever t changes, and the driver books forcing
// and damping into H*. Both backends must agree step by step, H* included.
TEST(OpenCLForcing, MovingPinWindAndDampingMatchCpu) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Double);
  ClothGridParams p;
  p.nx = 10;
  p.ny = 10;
  p.damping = 0.05;
  Scene s = makeClothGrid(p);
  s.pins[0].target.velocity = Eigen::Vector3d(0.2, 0.0, 0.1);
  s.pins[1].target.amplitude = Eigen::Vector3d(0.0, 0.0, 0.05);
  s.pins[1].target.frequency = 1.0;
  ForceField wind;
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.002);
  wind.amplitude = Eigen::Vector3d(0.0, 0.0, 0.003);
  wind.frequency = 0.5;
  s.force_fields.push_back(wind);
  for (Integrator integrator : {Integrator::BackwardEuler, Integrator::EnergyBlend}) {
    SimulatorOptions o;
    o.integrator = integrator;
    o.backend = BackendKind::CpuReference;
    const Trajectory ref = simulate(s, o, 100);
    o.backend = BackendKind::OpenCL;
    const Trajectory got = simulate(s, o, 100);
    ASSERT_EQ(ref.reports.size(), 100u);
    ASSERT_EQ(got.reports.size(), 100u);
    int damped_steps = 0;  // the blend may leave only rigid velocities, which damping keeps
    for (int i = 0; i < 100; ++i) {
      const StepReport& a = ref.reports[i];
      const StepReport& b = got.reports[i];
      ASSERT_NE(a.forcing, 0.0);
      damped_steps += a.damping > 0.0;
      // Energies relative to the energy scale (~0.1 J here); round-off amplified over 100 steps.
      const double scale = ref.energy_scale;
      EXPECT_NEAR(b.forcing, a.forcing, 1e-9 * scale) << integratorName(integrator) << " step " << i;
      EXPECT_NEAR(b.damping, a.damping, 1e-9 * scale) << integratorName(integrator) << " step " << i;
      EXPECT_NEAR(b.target, a.target, 1e-9 * scale) << integratorName(integrator) << " step " << i;
      EXPECT_LT(relativeError(got.x[i], ref.x[i]), 1e-9) << integratorName(integrator) << " step " << i;
    }
    EXPECT_GT(damped_steps, 90) << integratorName(integrator);
  }
}

}  // namespace
}  // namespace stabint
