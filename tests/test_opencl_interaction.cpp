// Per-frame input on the OpenCL backend: a driven cloth (user pin, user forces, grab and
// release, a teleport) follows the CPU reference within the equivalence tolerances of
// test_opencl_integrators, and checkpoints continue bit for bit in double and float.
#include "driven_cloth.hpp"
#include "test_opencl_support.hpp"
#include "triangle_cloth_scene.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace stabint {
namespace {

using testing::DrivenCloth;
using testing::drivenCloth;
using testing::relativeError;

struct DrivenRun {
  std::vector<Eigen::MatrixX3d> x;
  std::vector<StepReport> reports;
  double energy_scale = 0.0;
};

// 30 driven steps; a handle grabs the bottom corner at step 5 and is released at step 20 (the
// element set and the factors change), and at step 10 the velocities are replaced.
DrivenRun drivenRun(const DrivenCloth& d, BackendKind backend, Precision precision) {
  SimulatorOptions o = d.options;
  o.backend = backend;
  o.opencl.precision = precision;
  Simulator sim(d.scene, o);
  DrivenRun run;
  run.energy_scale = sim.energyScale();
  const int corner = d.scene.numParticles() - 7;
  int handle = -1;
  for (int i = 0; i < 30; ++i) {
    if (i == 5) handle = sim.grab(corner, 5e3);
    if (i > 5 && i < 20)
      sim.setPinTarget(handle, d.scene.positions.row(corner).transpose() + Eigen::Vector3d(0, 0, 0.01 * i));
    if (i == 20) sim.release(handle);
    if (i == 10) sim.setVelocities(sim.velocities() + Eigen::MatrixX3d::Constant(d.scene.numParticles(), 3, 0.1));
    d.drive(sim);
    run.reports.push_back(sim.step());
    run.x.push_back(sim.positions());
  }
  return run;
}

TEST(OpenCLInteraction, DrivenClothMatchesCpu) {
  for (Precision precision : testing::availablePrecisions()) {
    const std::vector<Integrator> integrators = testing::crossBackendIntegrators(precision);
    const double tol = testing::crossBackendTolerance(precision);
    for (Integrator integrator : integrators) {
      const DrivenCloth d = drivenCloth(integrator);
      const DrivenRun ref = drivenRun(d, BackendKind::CpuReference, Precision::Double);
      const DrivenRun got = drivenRun(d, BackendKind::OpenCL, precision);
      ASSERT_EQ(got.x.size(), ref.x.size());
      for (size_t i = 0; i < ref.x.size(); ++i) {
        const std::string what =
            std::string(integratorName(integrator)) + " " + precisionName(precision) + " step " + std::to_string(i);
        EXPECT_LT(relativeError(got.x[i], ref.x[i]), tol) << what;
        EXPECT_NEAR(got.reports[i].forcing, ref.reports[i].forcing, tol * ref.energy_scale) << what;
        EXPECT_NEAR(got.reports[i].event_energy, ref.reports[i].event_energy, tol * ref.energy_scale) << what;
        EXPECT_NEAR(got.reports[i].target, ref.reports[i].target, tol * ref.energy_scale) << what;
      }
      EXPECT_NE(ref.reports[10].event_energy, 0.0);
      EXPECT_NE(ref.reports[20].event_energy, 0.0);
    }
  }
}

// Element changes re-upload the params: the triangle cloth (triangle strain, hinges, pins) with
// stiffness changes at step 3, disabled elements at step 6 and enabled again at step 12 follows
// the CPU reference within the tolerances above, events included, and a checkpoint taken after
// the changes continues bit for bit.
TEST(OpenCLInteraction, ElementChangesMatchCpu) {
  const Scene cloth = testing::triangleCloth();
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    auto run = [&](BackendKind backend, Precision p, std::vector<StepReport>& reports) {
      SimulatorOptions o;
      o.integrator = Integrator::BDF2;
      o.backend = backend;
      o.opencl.precision = p;
      Simulator sim(cloth, o);
      std::vector<Eigen::MatrixX3d> xs;
      for (int i = 0; i < 20; ++i) {
        if (i == 3) sim.setElementStiffness(ElementKind::TriangleStrain, {0, 1, 2, 7}, 3000.0);
        if (i == 6) sim.setElementEnabled(ElementKind::BendingHinge, {2, 3}, false);
        if (i == 6) sim.setElementEnabled(ElementKind::Pin, 1, false);
        if (i == 12) sim.setElementEnabled(ElementKind::Pin, 1, true);
        reports.push_back(sim.step());
        xs.push_back(sim.positions());
      }
      const Checkpoint c = sim.checkpoint();
      std::vector<Eigen::MatrixX3d> after;
      for (int i = 0; i < 5; ++i) {
        sim.step();
        after.push_back(sim.positions());
      }
      sim.restore(c);
      for (int i = 0; i < 5; ++i) {
        sim.step();
        EXPECT_EQ(sim.positions(), after[std::size_t(i)]) << "restored step " << i;
      }
      return xs;
    };
    std::vector<StepReport> ref_reports, got_reports;
    const auto ref = run(BackendKind::CpuReference, Precision::Double, ref_reports);
    const auto got = run(BackendKind::OpenCL, precision, got_reports);
    const double scale = Simulator(cloth, {}).energyScale();
    for (std::size_t i = 0; i < ref.size(); ++i) {
      const std::string what = std::string(precisionName(precision)) + " step " + std::to_string(i);
      EXPECT_LT(relativeError(got[i], ref[i]), tol) << what;
      // Re-enabling the stiff pin after the corner fell books 700 J (500 E_scale): float's
      // error is relative to that energy, not to E_scale, and twice the positions' (the energy
      // is quadratic in the corner's distance from the pin's target).
      EXPECT_NEAR(got_reports[i].event_energy, ref_reports[i].event_energy,
                  2.0 * tol * std::max(scale, std::abs(ref_reports[i].event_energy)))
          << what;
    }
    EXPECT_NE(ref_reports[3].event_energy, 0.0);
    EXPECT_NE(ref_reports[6].event_energy, 0.0);
    EXPECT_NE(ref_reports[12].event_energy, 0.0);
  }
}

// A scripted grab-drag-release with an impulse and an element change (EventScript) on OpenCL
// follows the CPU reference within the tolerances above.
TEST(OpenCLInteraction, ScriptedEventsMatchCpu) {
  ClothGridParams p;
  p.nx = p.ny = 8;
  const Scene cloth = makeClothGrid(p);
  const std::vector<ScriptedEvent> events = {
      {3, GrabEvent{"hand", 56, 3e3, {{8, Eigen::Vector3d(0.1, 0.2, 0.3)}, {12, Eigen::Vector3d(0.0, 0.3, 0.2)}}}},
      {14, ReleaseEvent{"hand", -1}},
      {16, ImpulseEvent{{56, 57, 58}, Eigen::Vector3d(0.0, 0.0, 0.5)}},
      {18, ElementEvent{ElementKind::Spring, {0, 1, 2, 3}, 20.0, std::nullopt}},
  };
  for (Precision precision : testing::availablePrecisions()) {
    const double tol = testing::crossBackendTolerance(precision);
    auto run = [&](BackendKind backend, Precision prec) {
      SimulatorOptions o;
      o.integrator = Integrator::BDF2;
      o.backend = backend;
      o.opencl.precision = prec;
      Simulator sim(cloth, o);
      EventScript script(events);
      std::vector<Eigen::MatrixX3d> xs;
      for (int i = 0; i < 25; ++i) {
        script.apply(sim);
        sim.step();
        xs.push_back(sim.positions());
      }
      return xs;
    };
    const auto ref = run(BackendKind::CpuReference, Precision::Double);
    const auto got = run(BackendKind::OpenCL, precision);
    for (std::size_t i = 0; i < ref.size(); ++i)
      EXPECT_LT(relativeError(got[i], ref[i]), tol) << precisionName(precision) << " step " << i;
  }
}

TEST(OpenCLInteraction, CheckpointsContinueBitForBit) {
  for (Precision precision : testing::availablePrecisions()) {
    for (Integrator integrator : {Integrator::EnergyBlend, Integrator::BDF2}) {
      DrivenCloth d = drivenCloth(integrator);
      d.options.backend = BackendKind::OpenCL;
      d.options.opencl.precision = precision;
      Simulator sim(d.scene, d.options);
      d.run(sim, 10);
      const Checkpoint c = sim.checkpoint();
      const std::vector<Eigen::MatrixX3d> original = d.run(sim, 10);
      sim.restore(c);
      EXPECT_EQ(d.run(sim, 10), original) << integratorName(integrator) << " " << precisionName(precision);
      Simulator other(d.scene, d.options);
      other.restore(c);
      EXPECT_EQ(d.run(other, 10), original) << integratorName(integrator) << " " << precisionName(precision);
    }
  }
}

// `call` is refused with an InvalidInputError whose message contains `names`.
void refused(const std::function<void()>& call, const std::string& names) {
  try {
    call();
    ADD_FAILURE() << "accepted: " << names;
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
}

// On a float device per-frame values are bounded by validation::kMaxMagnitudeFloat (1e15), not
// 1e150: a pin target of 1e20 or velocities of 1e100 used to overflow the device, after which
// every step was refused. They are refused, the simulator unchanged; a double device takes 1e20.
TEST(OpenCLInteraction, FloatDevicesRefuseValuesBeyondTheirRange) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  const DrivenCloth d = drivenCloth(Integrator::BackwardEuler);
  SimulatorOptions o = d.options;
  o.backend = BackendKind::OpenCL;
  o.opencl = testing::openclOptions(Precision::Float);
  Simulator sim(d.scene, o);
  sim.step();
  const Eigen::MatrixX3d x = sim.positions();
  refused([&] { sim.setPinTarget(0, Eigen::Vector3d(1e20, 0.0, 0.0)); }, "the limit of a float device");
  Eigen::MatrixX3d fast = Eigen::MatrixX3d::Zero(x.rows(), 3);
  fast(2, 1) = 1e100;
  refused([&] { sim.setVelocities(fast); }, "velocities: row 2");
  EXPECT_EQ(sim.positions(), x);
  EXPECT_NO_THROW(sim.step());
  SimulatorOptions in_double = o;
  in_double.opencl = testing::openclOptions(Precision::Double);
  if (testing::openclSkipReason(Precision::Double).empty()) {
    Simulator wide(d.scene, in_double);
    EXPECT_NO_THROW(wide.setPinTarget(0, Eigen::Vector3d(1e20, 0.0, 0.0)));
  }
}

// The float device's bound holds at construction, at restore and for collider motion too: a
// scene built with a velocity of 1e100 lost it in its first float step, a restored one likewise,
// and a collider moved to 1e20 made every later step refused. Each is refused naming the value,
// and a refused restore or collider input changes nothing.
TEST(OpenCLInteraction, FloatDevicesRefuseStatesAndCollidersBeyondTheirRange) {
  STABINT_SKIP_WITHOUT_OPENCL(Precision::Float);
  Scene scene = drivenCloth(Integrator::BackwardEuler).scene;
  Collider ground;
  ground.center = Eigen::Vector3d(0.0, -10.0, 0.0);
  scene.colliders.push_back(ground);
  SimulatorOptions o;
  o.backend = BackendKind::OpenCL;
  o.opencl = testing::openclOptions(Precision::Float);
  Scene fast = scene;
  fast.velocities(3, 0) = 1e100;
  const std::string limit = "(the limit of a float device)";
  refused([&] { Simulator bad(fast, o); }, "velocities: row 3");
  refused([&] { Simulator bad(fast, o); }, limit);
  Simulator sim(scene, o);
  sim.step();
  const Eigen::MatrixX3d x = sim.positions();
  refused([&] { sim.setColliderPosition(0, Eigen::Vector3d(1e20, 0.0, 0.0)); }, "collider 0: position");
  refused([&] { sim.setColliderVelocity(0, Eigen::Vector3d(0.0, 1e20, 0.0)); },
          "collider 0: velocity (0, 1e+20, 0) exceeds 1e+15 in magnitude " + limit);
  // A checkpoint of a double run whose velocities a float device cannot hold.
  SimulatorOptions cpu;
  Simulator wide(scene, cpu);
  Eigen::MatrixX3d v = Eigen::MatrixX3d::Zero(x.rows(), 3);
  v(2, 1) = 1e100;
  wide.setVelocities(v);
  refused([&] { sim.restore(wide.checkpoint()); }, "velocities: row 2");
  refused([&] { sim.restore(wide.checkpoint()); }, limit);
  EXPECT_EQ(sim.positions(), x);
  EXPECT_NO_THROW(sim.step());
}

}  // namespace
}  // namespace stabint
