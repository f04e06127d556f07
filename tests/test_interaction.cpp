// Per-frame input of a running simulator (docs/method.md, "Per-frame input"): pin targets and
// external forces set every frame are booked exactly in H*, discontinuous events move H* by the
// jump they cause, rejected calls change nothing, and checkpoints continue bit for bit.
#include <stabint/stabint.hpp>

#include "../fuzz/checkpoint_properties.hpp"
#include "backend_suite.hpp"
#include "cloth_and_twin.hpp"
#include "driven_cloth.hpp"
#include "temp_dir_test.hpp"
#include "energy_band.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <vector>

namespace stabint {
namespace {

using testing::DrivenCloth;
using testing::drivenCloth;

constexpr double kPi = 3.14159265358979323846;

// A hand moving the pin of the one-particle oscillator on a sine, set every frame through
// setPinTarget. The pin is the only element and linear, so IM is exact in one local/global
// iteration, and the work rule that IM obeys for a target interpolated linearly over the step
// books its energy change exactly: H* = H to round-off, whatever the stiffness.
TEST(Interaction, PinTargetSetEveryFrameIsBookedExactly) {
  for (double k : {1e2, 1e4, 1e6}) {
    SimulatorOptions o;
    o.integrator = Integrator::ImplicitMidpoint;
    o.iterations = 1;
    Simulator sim(makeLinearOscillator({1.0, k, 0.0}), o);
    const double h = o.time_step;
    double worst = 0.0, scale = 0.0;
    for (int i = 0; i < 120; ++i) {
      const double t1 = (i + 1) * h;
      sim.setPinTarget(0, Eigen::Vector3d(0.3 * std::sin(2 * kPi * 2.0 * t1), 0.1 * std::sin(2 * kPi * t1), 0.0));
      const StepReport& r = sim.step();
      worst = std::max(worst, std::abs(r.energy.total() - r.target));
      scale = std::max(scale, std::abs(r.energy.total()));
    }
    EXPECT_GT(scale, 0.0);
    // Round-off of sums of energies of size `scale` over 120 steps.
    EXPECT_LT(worst, 1e-10 * scale) << "k = " << k;
    const double t_last = 120 * h;
    const Eigen::Vector3d last(0.3 * std::sin(2 * kPi * 2.0 * t_last), 0.1 * std::sin(2 * kPi * t_last), 0.0);
    EXPECT_EQ(sim.pinTarget(0), last);
  }
}

// The same for external forces per particle: -f(t).x is linear in x, so IM books it exactly.
TEST(Interaction, ExternalForcesSetEveryFrameAreBookedExactly) {
  SimulatorOptions o;
  o.integrator = Integrator::ImplicitMidpoint;
  o.iterations = 1;
  Simulator sim(makeLinearOscillator({1.0, 100.0, 0.1}), o);
  double worst = 0.0, scale = 0.0, work = 0.0;
  for (int i = 0; i < 120; ++i) {
    const double t1 = (i + 1) * o.time_step;
    Eigen::MatrixX3d f(1, 3);
    f << 5.0 * std::sin(2 * kPi * 1.5 * t1), 2.0, 0.0;
    sim.setExternalForces(f);
    const StepReport& r = sim.step();
    work += r.forcing;
    worst = std::max(worst, std::abs(r.energy.total() - r.target));
    scale = std::max(scale, std::abs(r.energy.total()));
  }
  EXPECT_GT(std::abs(work), 0.01 * scale) << "the forces should do work";
  EXPECT_LT(worst, 1e-10 * scale);
}

// Forces persist at their last value: a constant force set once accelerates a free particle
// like gravity would (the first step ramps it up from zero).
TEST(Interaction, ExternalForcesPersistUntilChanged) {
  Scene s;
  s.rest_positions = Eigen::MatrixX3d::Zero(1, 3);
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(1, 3);
  s.masses = Eigen::VectorXd::Constant(1, 2.0);
  s.gravity.setZero();
  SimulatorOptions o;
  o.integrator = Integrator::SymplecticEuler;
  Simulator sim(s, o);
  Eigen::MatrixX3d f(1, 3);
  f << 4.0, 0.0, 0.0;
  sim.setExternalForces(f);
  sim.step();  // explicit Euler uses f(t_n) = 0: the ramp starts at zero
  EXPECT_EQ(sim.velocities()(0, 0), 0.0);
  for (int i = 0; i < 10; ++i) sim.step();
  EXPECT_NEAR(sim.velocities()(0, 0), 10 * o.time_step * 4.0 / 2.0, 1e-12);
  sim.setExternalForces(Eigen::MatrixX3d::Zero(1, 3));
  sim.step();  // f(t_n) = 4 still
  const double v = sim.velocities()(0, 0);
  sim.step();
  EXPECT_EQ(sim.velocities()(0, 0), v);
}

// Every input call validates first; a rejected one changes nothing, so the next step equals a
// twin simulator's that never saw it, bit for bit.
TEST(Interaction, RejectedInputChangesNothing) {
  ClothGridParams p;
  p.nx = p.ny = 6;
  const Scene cloth = makeClothGrid(p);
  Simulator sim(cloth, {}), twin(cloth, {});
  sim.step();
  twin.step();
  const int n = cloth.numParticles();
  Eigen::MatrixX3d bad = cloth.positions;
  bad(3, 1) = std::nan("");
  auto expectRejected = [&](const std::function<void()>& call, const std::string& names) {
    try {
      call();
      FAIL() << "accepted: " << names;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  expectRejected([&] { sim.setPinTarget(2, Eigen::Vector3d::Zero()); }, "pin 2 out of range");
  expectRejected([&] { sim.setPinTarget(-1, Eigen::Vector3d::Zero()); }, "pin -1 out of range");
  expectRejected([&] { sim.setPinTarget(0, Eigen::Vector3d(0, std::nan(""), 0)); }, "pin 0: target is not finite");
  expectRejected([&] { sim.setExternalForces(Eigen::MatrixX3d::Zero(n - 1, 3)); }, "external forces: 35 rows");
  expectRejected([&] { sim.setState(bad, cloth.velocities); }, "positions: row 3 is not finite");
  expectRejected([&] { sim.setVelocities(bad); }, "velocities: row 3 is not finite");
  expectRejected([&] { sim.setPositions(Eigen::MatrixX3d::Zero(0, 3)); }, "positions: 0 rows");
  expectRejected([&] { sim.setIterations(0); }, "iterations = 0");
  // Finite but beyond the 1e150 every scene value obeys (the simulator would then run with
  // H ~ 1e300 or refuse every step): refused, naming the row or the pin.
  Eigen::MatrixX3d huge = cloth.positions;
  huge(4, 2) = 1e151;
  expectRejected([&] { sim.setPinTarget(1, Eigen::Vector3d(0, -1e151, 0)); }, "pin 1: target (0, -1e+151, 0) exceeds");
  expectRejected([&] { sim.setExternalForces(huge); }, "external forces: row 4");
  expectRejected([&] { sim.setPositions(huge); }, "positions: row 4");
  expectRejected([&] { sim.setVelocities(huge); }, "velocities: row 4");
  expectRejected([&] { sim.setState(cloth.positions, huge); }, "velocities: row 4");
  EXPECT_EQ(sim.target(), twin.target());
  for (int i = 0; i < 5; ++i) {
    const StepReport& a = sim.step();
    const StepReport& b = twin.step();
    EXPECT_EQ(a.target, b.target);
    EXPECT_EQ(a.event_energy, 0.0);
  }
  EXPECT_EQ(sim.positions(), twin.positions());
  EXPECT_EQ(sim.velocities(), twin.velocities());
}

// A teleport is a discontinuous event: H* moves by the jump of H (reported as the next step's
// event_energy), the BDF2 history restarts, and the run then matches a fresh simulator started
// from that state bit for bit.
TEST(Interaction, TeleportBooksTheJumpAndMatchesAFreshSimulator) {
  ClothGridParams p;
  p.nx = p.ny = 8;
  const Scene cloth = makeClothGrid(p);
  SimulatorOptions o;
  o.integrator = Integrator::BDF2;
  Simulator sim(cloth, o);
  for (int i = 0; i < 10; ++i) sim.step();

  Scene moved = cloth;
  moved.positions.col(2).array() += 0.01;  // pushed out of the pins' plane
  moved.velocities.col(0).setConstant(0.2);
  const double target_before = sim.target();
  const double h_before = sim.energy().total();
  sim.setState(moved.positions, moved.velocities);
  const double jump = sim.energy().total() - h_before;
  EXPECT_GT(jump, 0.0);
  EXPECT_DOUBLE_EQ(sim.target(), target_before + jump);

  Simulator fresh(moved, o);
  EXPECT_EQ(sim.energy().total(), fresh.energy().total());
  for (int i = 0; i < 10; ++i) {
    const StepReport& r = sim.step();
    fresh.step();
    if (i == 0) {
      EXPECT_EQ(r.event_energy, jump);
    } else {
      EXPECT_EQ(r.event_energy, 0.0);
    }
  }
  EXPECT_EQ(sim.positions(), fresh.positions());
  EXPECT_EQ(sim.velocities(), fresh.velocities());
}

TEST(Interaction, IterationBudgetChangesBetweenSteps) {
  SimulatorOptions o;
  o.integrator = Integrator::BackwardEuler;
  o.iterations = 4;
  ClothGridParams p;
  p.nx = p.ny = 5;
  Simulator sim(makeClothGrid(p), o);
  EXPECT_EQ(sim.step().iterations, 4);
  const double t = sim.time(), target = sim.target();
  sim.setIterations(9);
  EXPECT_EQ(sim.time(), t);
  EXPECT_EQ(sim.target(), target);
  EXPECT_EQ(sim.step().iterations, 9);
  EXPECT_EQ(sim.options().iterations, 9);
}

// A driven cloth: corner 0 is dragged by the hand for 1 s (starting and ending at rest), then
// held. The blend books the hand's work, so H stays within its tolerance band of H*, and the
// cloth keeps swinging after the drag, where BE's motion dies out.
TEST(Interaction, DraggedClothKeepsSwingingWithTheBlend) {
  ClothGridParams p;
  p.nx = p.ny = 10;
  const Scene cloth = makeClothGrid(p);
  const Eigen::Vector3d corner = cloth.pins[0].target.position;
  auto run = [&](Integrator integrator, double& worst_gap, double& late_kinetic) {
    SimulatorOptions o;
    o.integrator = integrator;
    Simulator sim(cloth, o);
    worst_gap = late_kinetic = 0.0;
    for (int i = 0; i < 150; ++i) {
      const double t1 = (i + 1) * o.time_step;
      if (t1 <= 1.0)
        sim.setPinTarget(
            0, corner + Eigen::Vector3d(0.15 * (1 - std::cos(kPi * t1)), 0.0, 0.1 * (1 - std::cos(2 * kPi * t1))));
      const StepReport& r = sim.step();
      worst_gap = std::max(worst_gap, std::abs(r.energy.total() - r.target) / sim.energyScale());
      if (i >= 120) late_kinetic += r.energy.kinetic / 30.0;
    }
  };
  double gap_blend, k_blend, gap_be, k_be;
  run(Integrator::EnergyBlend, gap_blend, k_blend);
  run(Integrator::BackwardEuler, gap_be, k_be);
  // The blend's band: energy_tolerance (1e-3) of K + E_int + E_scale, about 2e-3 E_scale here;
  // measured 1.0e-3 (1.1e-3 with plain iterations). BE's gap grows to 0.083 E_scale (what it
  // lost; 0.25 with plain iterations, whose unconverged solves damp more).
  EXPECT_LT(gap_blend, 3e-3);
  EXPECT_GT(gap_be, 0.05);
  EXPECT_GT(k_blend, 20.0 * k_be) << "blend " << k_blend << " J, BE " << k_be << " J";
}

// A hand grabs the free corner of a 20 x 20 cloth and drags it up and out of the cloth's plane
// (the path of scenes/cloth_drag.json), over two seconds or one, on every backend. The blend's
// partner is a few iterations from x_n; where even it, whole, kept more energy than the target,
// the corrections zeroed the velocities, and the cloth froze step after step while the hand
// stretched it. Before the partner went on in such steps (BatchDriver::extendPartner), measured
// on the CPU reference: 10 frozen steps and H 0.018 E_scale above H* at the default 10
// iterations, 30-60 frozen steps and 0.23-0.64 E_scale above at 20 and 30 iterations, mean K 0
// there. Now no step freezes and H stays at most 1.1e-3 E_scale above H* on every backend (the
// band: energy_tolerance of K + E_int + E_scale, about 1.1e-3 E_scale here; the limit allows a
// step twice that) and at most 7.9e-3 below in double, 1.4e-2 in float (a velocity scale capped
// at 2 per step restores a deficit over the next steps; float's state rounds to 6e-8 per step).
class DraggedCorner : public testing::BackendTest {};

TEST_P(DraggedCorner, KeepsMovingWhateverTheBudget) {
  ClothGridParams p;
  const Scene cloth = makeClothGrid(p);
  const int corner = p.nx * p.ny - 1;
  const Eigen::Vector3d start = cloth.positions.row(corner).transpose();
  const Eigen::Vector3d up(1.0, 0.2, 0.4), across(0.7, 0.5, 0.5);
  for (int iterations : {10, 20, 30})
    for (int steps : {30, 15}) {  // per leg of the path
      SimulatorOptions o;
      o.iterations = iterations;
      Simulator sim(cloth, options(o));
      const int hand = sim.grab(corner, 1e4);
      double above = 0.0, below = 0.0, mean_kinetic = 0.0;
      int frozen = 0;
      for (int i = 0; i < 2 * steps; ++i) {
        const double s = double(i % steps + 1) / steps;
        sim.setPinTarget(hand, i < steps ? ((1 - s) * start + s * up).eval() : ((1 - s) * up + s * across).eval());
        const StepReport& r = sim.step();
        const double gap = (r.energy.total() - r.target) / sim.energyScale();
        above = std::max(above, gap);
        below = std::max(below, -gap);
        frozen += r.velocity_scale == 0.0 ? 1 : 0;
        mean_kinetic += r.energy.kinetic / (2 * steps);
      }
      const std::string what = std::to_string(iterations) + " iterations, " + std::to_string(steps) + " steps a leg";
      EXPECT_EQ(frozen, 0) << what;
      EXPECT_LT(above, 3e-3) << what;
      EXPECT_LT(below, backend().isFloat() ? 3e-2 : 1e-2) << what;
      EXPECT_GT(mean_kinetic, 1e-3) << what << ": the cloth follows the hand";
    }
}

STABINT_ON_EVERY_BACKEND(DraggedCorner);

// The tool of scenes/cloth_poke.json pushes into the cloth and pulls back out, at 30 iterations
// and at h = 1/15. The forcing rule's sum charged the pull for less than the energy the cloth's
// state kept, so H started above H* by 0.01-0.06 E_scale in the stretch, where even the blend's
// partner whole could not take it out (75 and 39 steps carried such an excess, c1b5089's rule
// kept it from growing). A moving collider's work is now its contact forces at the step's
// midpoint times its displacement (contactWork, docs/method.md "Contact"): H stays within the
// band (measured: largest excess 1.0e-3 and 1.7e-3 E_scale, the band being about 1.1e-3) and at
// most one step zeroes the velocities (measured 0 and 1), where 99 and 40 did before c1b5089.
TEST(Interaction, PokedClothsToolWorkIsBookedWithoutAnExcess) {
  const std::string path =
      (std::filesystem::path(__FILE__).parent_path().parent_path() / "scenes" / "cloth_poke.json").string();
  for (const auto& [iterations, h] : {std::pair{30, 1.0 / 30.0}, std::pair{10, 1.0 / 15.0}}) {
    SceneFile file = loadSceneFileWithEvents(path);
    SimulatorOptions o;
    o.iterations = iterations;
    o.time_step = h;
    o.backend = BackendKind::CpuReference;
    Simulator sim(file.scene, o);
    double forcing = 0.0, worst = 0.0;
    int frozen = 0, carried = 0;
    for (int i = 0; i < int(8.0 / h); ++i) {
      file.events.apply(sim);
      const StepReport& r = sim.step();
      const double excess = (r.energy.total() - r.target) / sim.energyScale();
      worst = std::max(worst, excess);
      carried += excess > 2e-3 ? 1 : 0;
      frozen += r.velocity_scale == 0.0 ? 1 : 0;
      forcing += std::abs(r.forcing);
    }
    const std::string what = std::to_string(iterations) + " iterations, h = " + std::to_string(h);
    std::printf("%s: largest excess %.3g E_scale, tool's work |W| summed %.3g J\n", what.c_str(), worst, forcing);
    EXPECT_GT(forcing, 0.0) << what << ": the tool must reach the cloth";
    EXPECT_EQ(carried, 0) << what;
    EXPECT_LE(frozen, 1) << what;
  }
}

class CheckpointTest : public testing::TempDirTest {};

// Grab the free bottom corner of a hanging cloth, lift it out of its plane and let go: grabbing
// at the particle's own position and releasing book their energy jumps (zero, then minus the
// handle's energy), the blend keeps H within its tolerance band of H* (apart from single steps
// where the capped velocity scale restores energy over two steps), and the cloth keeps swinging
// after the release where BE's stops.
TEST(Interaction, GrabDragReleaseOfAFreeCorner) {
  ClothGridParams p;
  p.nx = p.ny = 10;
  const Scene cloth = makeClothGrid(p);
  const int corner = p.nx * (p.ny - 1);  // bottom row, free
  struct Result {
    int outside_band = 0;
    double worst_gap = 0.0, late_kinetic = 0.0;
  };
  auto run = [&](Integrator integrator) {
    SimulatorOptions o;
    o.integrator = integrator;
    Simulator sim(cloth, o);
    const Eigen::Vector3d start = cloth.positions.row(corner).transpose();
    const double target_before = sim.target();
    const int handle = sim.grab(corner, 1e4);
    EXPECT_EQ(handle, 2);
    EXPECT_EQ(sim.target(), target_before);  // no jump: the handle starts where the particle is
    Result result;
    double released_energy = 0.0;
    for (int i = 0; i < 120; ++i) {
      const double t1 = (i + 1) * o.time_step;
      if (t1 <= 1.0)
        sim.setPinTarget(handle,
                         start + Eigen::Vector3d(0.1 * (1 - std::cos(kPi * t1)), 0.0, 0.3 * std::sin(0.5 * kPi * t1)));
      if (i == 40) {
        const double e_before = sim.energy().total();
        sim.release(handle);
        released_energy = sim.energy().total() - e_before;
        EXPECT_LT(released_energy, 0.0);
      }
      const StepReport& r = sim.step();
      // The event is H's jump; energy().total() sums the same terms in another order.
      EXPECT_NEAR(r.event_energy, i == 40 ? released_energy : 0.0, 1e-12 * sim.energyScale()) << "step " << i;
      const double gap = std::abs(r.energy.total() - r.target);
      const double band = testing::energyBand(sim, r);
      result.outside_band += gap > 2.0 * band;
      result.worst_gap = std::max(result.worst_gap, gap / sim.energyScale());
      if (i >= 90) result.late_kinetic += r.energy.kinetic / 30.0;
    }
    EXPECT_EQ(sim.scene().pins.size(), 3u);
    EXPECT_EQ(sim.scene().pins[handle].stiffness, 0.0);
    return result;
  };
  const Result blend = run(Integrator::EnergyBlend);
  const Result be = run(Integrator::BackwardEuler);
  std::printf("  blend: %d of 120 steps outside twice the band, worst gap %.3g E_scale, late K %.3g J (BE %.3g J)\n",
              blend.outside_band, blend.worst_gap, blend.late_kinetic, be.late_kinetic);
  EXPECT_LE(blend.outside_band, 6);
  EXPECT_LT(blend.worst_gap, 0.1);
  EXPECT_GT(be.worst_gap, 0.2);
  EXPECT_GT(blend.late_kinetic, 20.0 * be.late_kinetic)
      << "blend " << blend.late_kinetic << " J, BE " << be.late_kinetic << " J";
}

// Grabbing before the first step is the scene with that pin from the start, and releasing a
// scene pin the scene without its stiffness: the rank-1 updated factors solve the same systems
// as fresh factorizations, to round-off.
TEST(Interaction, GrabAndReleaseMatchScenesBuiltThatWay) {
  ClothGridParams p;
  p.nx = p.ny = 8;
  const Scene cloth = makeClothGrid(p);
  SimulatorOptions o;
  o.integrator = Integrator::BDF2;

  Simulator grabbed(cloth, o);
  grabbed.grab(5, 2e3);
  Scene with_pin = cloth;
  with_pin.pins.push_back(Pin{5, 2e3, PinTarget{cloth.positions.row(5).transpose()}});
  Simulator built(with_pin, o);

  Simulator released(cloth, o);
  released.release(1);
  Scene one_pin = cloth;
  one_pin.pins[1].stiffness = 0.0;
  Simulator built_released(one_pin, o);
  for (int i = 0; i < 40; ++i) {
    grabbed.step();
    built.step();
    released.step();
    built_released.step();
  }
  // Positions of about 1 m after 40 steps: differences are round-off of the factorizations.
  EXPECT_LT((grabbed.positions() - built.positions()).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((released.positions() - built_released.positions()).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT((released.positions() - built.positions()).cwiseAbs().maxCoeff(), 0.1) << "the pins should matter";
}

// A grab far stiffer than the particle's diagonal (1e140 N/m on a 0.25 g particle) and its release
// would spoil a rank-updated factor (the release's downdate cancels 1e140 against ~1e3): such a
// change refactors instead (GlobalSystem::kLargestRankUpdate). After the release, and after
// restoring a checkpoint taken before the grab, the simulator steps as a twin that never grabbed,
// to the round-off of a fresh factorization. Stiffnesses beyond 1e150 are refused.
TEST(Interaction, AHugeGrabAndItsReleaseLeaveAWorkingSimulator) {
  testing::ClothAndTwin c(1, 7);
  const Checkpoint before = c.sim.checkpoint();
  EXPECT_THROW(c.sim.grab(3, 1e151), InvalidInputError);
  const int handle = c.sim.grab(3, 1e140);
  for (int i = 0; i < 3; ++i) c.sim.step();
  c.sim.release(handle);
  for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(c.sim.step());
  c.sim.restore(before);
  c.both(10);
  EXPECT_LE((c.sim.positions() - c.twin.positions()).cwiseAbs().maxCoeff(), 1e-9 * c.size());
}

TEST(Interaction, BadGrabAndReleaseChangeNothing) {
  ClothGridParams p;
  p.nx = p.ny = 5;
  Simulator sim(makeClothGrid(p), {});
  EXPECT_THROW(sim.grab(25, 1e3), InvalidInputError);
  EXPECT_THROW(sim.grab(-1, 1e3), InvalidInputError);
  EXPECT_THROW(sim.grab(3, 0.0), InvalidInputError);
  EXPECT_THROW(sim.grab(3, std::nan("")), InvalidInputError);
  EXPECT_THROW(sim.release(2), InvalidInputError);
  EXPECT_EQ(sim.scene().pins.size(), 2u);
  sim.release(0);
  // A second release of the same pin is a mistake of the caller's, refused like the others.
  const double target = sim.target();
  EXPECT_THROW(sim.release(0), InvalidInputError);
  EXPECT_EQ(sim.target(), target);
  EXPECT_EQ(sim.scene().pins[0].stiffness, 0.0);
}

// A checkpoint taken while a handle is held restores into a fresh simulator (the pins follow)
// and continues to round-off; one taken before the grab undoes it.
TEST_F(CheckpointTest, CheckpointsCarryGrabbedHandles) {
  ClothGridParams p;
  p.nx = p.ny = 7;
  const Scene cloth = makeClothGrid(p);
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  Simulator sim(cloth, o);
  for (int i = 0; i < 5; ++i) sim.step();
  const Checkpoint before_grab = sim.checkpoint();
  const int handle = sim.grab(3, 5e3);
  sim.setPinTarget(handle, sim.positions().row(3).transpose() + Eigen::Vector3d(0.1, 0.0, 0.1));
  sim.step();
  const Checkpoint held = sim.checkpoint();
  std::vector<Eigen::MatrixX3d> original;
  for (int i = 0; i < 10; ++i) {
    sim.step();
    original.push_back(sim.positions());
  }

  Simulator fresh(cloth, o);
  fresh.restore(held);
  EXPECT_EQ(fresh.scene().pins.size(), 3u);
  for (int i = 0; i < 10; ++i) {
    fresh.step();
    EXPECT_LT((fresh.positions() - original[i]).cwiseAbs().maxCoeff(), 1e-9) << "step " << i;
  }
  sim.restore(before_grab);
  EXPECT_EQ(sim.scene().pins.size(), 2u);
  EXPECT_EQ(sim.stepCount(), 5);
}

// L-BFGS and Newton-CG keep nothing from one solve to the next, so their runs restore bit for bit too.
TEST_F(CheckpointTest, RestoredRunsContinueBitForBit) {
  for (const auto& [integrator, acceleration] :
       {std::pair{Integrator::EnergyBlend, Acceleration::None}, std::pair{Integrator::BDF2, Acceleration::None},
        std::pair{Integrator::EnergyBlend, Acceleration::LBFGS},
        std::pair{Integrator::EnergyBlend, Acceleration::Newton}}) {
    DrivenCloth d = drivenCloth(integrator);
    d.options.acceleration = acceleration;
    Simulator sim(d.scene, d.options);
    d.run(sim, 15);
    const Checkpoint c = sim.checkpoint();
    EXPECT_EQ(c.stepCount(), 15);
    EXPECT_EQ(c.time(), sim.time());
    const double target = sim.target();
    const std::vector<Eigen::MatrixX3d> original = d.run(sim, 15);

    // Into the same simulator, into a new one, and through a file.
    sim.restore(c);
    EXPECT_EQ(sim.stepCount(), 15);
    EXPECT_EQ(sim.target(), target);
    EXPECT_EQ(d.run(sim, 15), original) << integratorName(integrator);
    Simulator other(d.scene, d.options);
    other.restore(c);
    EXPECT_EQ(d.run(other, 15), original) << integratorName(integrator);
    const std::string path = (dir_ / "run.ckpt").string();
    c.save(path);
    Simulator from_file(d.scene, d.options);
    from_file.restore(Checkpoint::load(path));
    EXPECT_EQ(d.run(from_file, 15), original) << integratorName(integrator);
  }
}

TEST_F(CheckpointTest, BadCheckpointsAreNamedErrorsAndChangeNothing) {
  const DrivenCloth d = drivenCloth(Integrator::EnergyBlend);
  Simulator sim(d.scene, d.options);
  d.run(sim, 3);
  const Checkpoint c = sim.checkpoint();

  ClothGridParams p;
  p.nx = p.ny = 6;
  Simulator other_scene(makeClothGrid(p), d.options);
  EXPECT_THROW(other_scene.restore(c), InvalidInputError);
  Scene heavier = d.scene;
  heavier.masses *= 2.0;
  Simulator heavier_sim(heavier, d.options);
  EXPECT_THROW(heavier_sim.restore(c), InvalidInputError);
  EXPECT_EQ(heavier_sim.stepCount(), 0);

  auto expectFormatError = [](const std::string& bytes, const std::string& names) {
    try {
      Checkpoint::fromBytes(bytes, "test.ckpt");
      FAIL() << "accepted: " << names;
    } catch (const FileFormatError& e) {
      EXPECT_EQ(e.file(), "test.ckpt");
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  // Any change of the bytes breaks the checksum (FNV-1a 64 over all but the last 8 bytes).
  expectFormatError(c.bytes().substr(0, c.bytes().size() - 1), "checksum");
  expectFormatError(c.bytes() + "x", "checksum");
  expectFormatError(c.bytes().substr(0, 14), "truncated");
  expectFormatError("not a checkpoint", "wrong header");
  std::string other_version = c.bytes();
  other_version[8] = 7;
  expectFormatError(other_version, "format version 7");
  std::string flipped = c.bytes();
  flipped[120] ^= 0x10;  // a bit of a position
  expectFormatError(flipped, "checksum");
  // With the checksum made to match, every field is still checked by value, naming it.
  auto signedWith = [&](std::size_t offset, const auto& value) {
    std::string bytes = c.bytes();
    std::memcpy(&bytes[offset], &value, sizeof(value));
    checkpoint_properties::resign(bytes);
    return bytes;
  };
  // Header 8, version 4, fingerprint 8, particle and pin counts 8 each: the time at 36, the step
  // count at 44, the target at 52, the kinetic energy at 60; the positions' row count at 101, their
  // values from 109.
  expectFormatError(signedWith(8 + 4 + 8 + 7, std::uint8_t(0x7f)), "particle count");
  expectFormatError(signedWith(36, -1e300), "the time: beyond 1e150");
  expectFormatError(signedWith(36, std::nan("")), "the time: not finite");
  expectFormatError(signedWith(44, std::int64_t(std::numeric_limits<int>::max())),
                    "step count 2147483647 out of range");
  expectFormatError(signedWith(52, std::nan("")), "the target: not finite");
  expectFormatError(signedWith(60, -1.0), "kinetic energy is negative");
  expectFormatError(signedWith(109 + 8, std::nan("")), "positions: not finite");
  EXPECT_NO_THROW(Checkpoint::fromBytes(signedWith(36, 0.1), "retimed"));  // the helper signs right
  EXPECT_THROW(Checkpoint::load((dir_ / "missing.ckpt").string()), FileFormatError);
  EXPECT_THROW(Checkpoint::load(dir_.string()), FileFormatError);
  EXPECT_THROW(c.save((dir_ / "no" / "such" / "dir").string()), FileFormatError);
}

}  // namespace
}  // namespace stabint
