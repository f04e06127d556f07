// Colliders moved at run time (Simulator::setColliderPosition, setColliderVelocity;
// docs/method.md, "Per-frame input" and "Contact"), on every backend: a collider dragged per frame
// pushes a body with its work booked in H*, a per-frame ramp is the scene's constant velocity
// when given the same positions, checkpoints carry the motion, bad input changes nothing.
#include "backend_suite.hpp"
#include "contact_scenes.hpp"
#include "energy_band.hpp"

#include <stabint/simulator.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <tuple>

namespace stabint {
namespace {

using testing::boxCollider;
using testing::freeBar;
using testing::groundPlane;

class ColliderMotion : public testing::BackendTest {};

// The tet bar on the ground with a box (collider 1) beside it, at x in [-0.55, -0.05] (the bar
// spans x in [0, 1]); `box_velocity` is the box's scene velocity.
Scene barAndBox(const Eigen::Vector3d& box_velocity = Eigen::Vector3d::Zero()) {
  Scene s = freeBar(0.0);
  s.colliders.push_back(groundPlane(0.0, 1e4));
  s.colliders.push_back(
      boxCollider(Eigen::Vector3d(-0.3, 0.125, 0.125), Eigen::Vector3d(0.25, 0.1, 0.5), 1e4, box_velocity));
  return s;
}

// The tool's path: along +x at 0.6 m/s, swaying +-5 cm in z once a second (a hand's drag).
Eigen::Vector3d toolAt(double t) {
  return Eigen::Vector3d(-0.3 + 0.6 * t, 0.125, 0.125 + 0.05 * std::sin(2.0 * M_PI * t));
}

SimulatorOptions contactOptions(SimulatorOptions o = {}) {
  o.contact_tolerance = 0.03;
  return o;
}

// A box moved per frame like a mouse-driven tool pushes the bar along, its work is booked
// (forcing > 0), and the blend keeps H within its band of H*.
TEST_P(ColliderMotion, ColliderMovedPerFramePushesABodyWithinTheBand) {
  const SimulatorOptions o = options(contactOptions());
  Simulator sim(barAndBox(), o);
  double forcing = 0.0, worst = 0.0;
  for (int i = 0; i < 40; ++i) {
    sim.setColliderPosition(1, toolAt(sim.time() + o.time_step));
    const StepReport& r = sim.step();
    forcing += r.forcing;
    const double band = testing::energyBand(sim, r);
    worst = std::max(worst, std::abs(r.energy.total() - r.target) / band);
    // The position given is where the collider is at the end of the step, exactly.
    ASSERT_EQ(sim.colliderPosition(1), toolAt(sim.time())) << i;
  }
  EXPECT_GT(forcing, 0.0);
  // Pushed along: an elastic push by a wall at 0.6 m/s leaves the bar at up to 1.2 m/s (measured
  // 1.27 mean, the sway adds a little); a tool that did not push would leave it at rest.
  EXPECT_GT(sim.velocities().col(0).mean(), 0.6);
  // The blend's invariant: within its band (measured 0.77 of it on every backend).
  EXPECT_LT(worst, 1.0);
}

// Given the positions center + velocity t at each step's end, a driven collider is the scene's
// constant-velocity one: the same positions at every step's start and end, the same velocity to
// round-off. Inside a step (IM's midpoint) the ramp interpolates and the law extrapolates, which
// differ by round-off of the position (~1e-16 m), and the ramp's velocity (end - start) / h is
// the law's to round-off (friction reads it); over 30 steps of contact that grew to 2.5e-14 m
// (velocities 7.5e-13 m/s) in double. The tolerance is 1e-10 m in double; in float the state
// rounds to 6e-8 relative each step, which hides these differences (measured 0), and 1e-5 m
// allows a few roundings of the 1 m scene amplified by the stiff contact.
TEST_P(ColliderMotion, SetPositionEqualsTheSceneVelocityGivenTheSamePositions) {
  const SimulatorOptions o = options(contactOptions());
  const Eigen::Vector3d velocity(0.5, 0.0, 0.0);
  const Scene moving = barAndBox(velocity);
  Simulator law(moving, o), driven(barAndBox(), o);
  const Collider& box = moving.colliders[1];
  for (int i = 0; i < 30; ++i) {
    driven.setColliderPosition(1, box.center + (driven.time() + o.time_step) * velocity);
    law.step();
    driven.step();
    ASSERT_EQ(driven.colliderPosition(1), law.colliderPosition(1)) << i;
    ASSERT_TRUE(driven.colliderVelocity(1).isApprox(velocity, 1e-12)) << i;
  }
  EXPECT_EQ(law.colliderPosition(1), box.center + law.time() * velocity) << "the scene's law, bit for bit";
  const double tolerance = backend().isFloat() ? 1e-5 : 1e-10;
  EXPECT_LT((driven.positions() - law.positions()).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_LT((driven.velocities() - law.velocities()).cwiseAbs().maxCoeff(), 1e3 * tolerance);
  EXPECT_GT(law.velocities().col(0).mean(), 0.5) << "the box pushed the bar (measured 1.06 m/s)";
}

// A checkpoint holds each collider's motion: restored into a fresh simulator (in memory and
// through its bytes), the run continues bit for bit, including a ramp set before the checkpoint
// for the coming step and a velocity set earlier.
TEST_P(ColliderMotion, CheckpointRestoreContinuesBitIdentically) {
  const SimulatorOptions o = options(contactOptions());
  const Scene s = barAndBox();
  Simulator sim(s, o);
  auto input = [&](Simulator& target, int frame) {
    if (frame < 10) target.setColliderPosition(1, toolAt(target.time() + o.time_step));
    if (frame == 10) target.setColliderVelocity(1, Eigen::Vector3d(0.4, 0.0, -0.1));
    if (frame == 20) target.setColliderVelocity(0, Eigen::Vector3d(0.0, 0.0, 0.2));  // the ground slides
    if (frame >= 25) target.setColliderPosition(1, toolAt(target.time() + o.time_step));
  };
  Checkpoint at_15, at_27;
  for (int frame = 0; frame < 35; ++frame) {
    if (frame == 15) at_15 = sim.checkpoint();
    input(sim, frame);
    if (frame == 27) at_27 = sim.checkpoint();  // after this frame's ramp was set
    sim.step();
  }
  for (const auto& [checkpoint, first_frame, input_done] :
       {std::make_tuple(at_15, 15, false), std::make_tuple(at_27, 27, true)}) {
    for (const bool through_bytes : {false, true}) {
      Simulator other(s, o);
      other.restore(through_bytes ? Checkpoint::fromBytes(checkpoint.bytes()) : checkpoint);
      for (int frame = first_frame; frame < 35; ++frame) {
        if (!(input_done && frame == first_frame)) input(other, frame);
        other.step();
      }
      EXPECT_EQ(other.positions(), sim.positions()) << first_frame << through_bytes;
      EXPECT_EQ(other.velocities(), sim.velocities()) << first_frame << through_bytes;
      EXPECT_EQ(other.target(), sim.target()) << first_frame << through_bytes;
      EXPECT_EQ(other.colliderPosition(0), sim.colliderPosition(0));
      EXPECT_EQ(other.colliderPosition(1), sim.colliderPosition(1));
    }
  }
}

STABINT_ON_EVERY_BACKEND(ColliderMotion);

// setColliderVelocity: the collider moves on from where it is with that velocity, until set
// again; zeros stop it.
TEST(ColliderMotionApi, SetVelocityMovesOnFromWhereTheColliderIs) {
  const SimulatorOptions o = contactOptions();
  Simulator sim(barAndBox(Eigen::Vector3d(0.5, 0.0, 0.0)), o);
  for (int i = 0; i < 5; ++i) sim.step();
  const Eigen::Vector3d p5 = sim.colliderPosition(1);
  const Eigen::Vector3d v(-0.2, 0.1, 0.3);
  sim.setColliderVelocity(1, v);
  EXPECT_EQ(sim.colliderPosition(1), p5) << "no jump";
  for (int i = 0; i < 10; ++i) sim.step();
  EXPECT_TRUE(sim.colliderPosition(1).isApprox(p5 + 10 * o.time_step * v, 1e-14));
  EXPECT_EQ(sim.colliderVelocity(1), v);
  sim.setColliderVelocity(1, Eigen::Vector3d::Zero());
  const Eigen::Vector3d stopped = sim.colliderPosition(1);
  sim.step();
  EXPECT_EQ(sim.colliderPosition(1), stopped);
  EXPECT_EQ(sim.colliderVelocity(1), Eigen::Vector3d::Zero());
  // A position ramp ends where it was told and stays: its velocity over the step, then zero.
  sim.setColliderPosition(1, stopped + Eigen::Vector3d(0.0, 0.0, 0.1));
  sim.step();
  EXPECT_EQ(sim.colliderPosition(1), stopped + Eigen::Vector3d(0.0, 0.0, 0.1));
  EXPECT_TRUE(sim.colliderVelocity(1).isApprox(Eigen::Vector3d(0.0, 0.0, 0.1 / o.time_step), 1e-12));
  sim.step();
  EXPECT_EQ(sim.colliderPosition(1), stopped + Eigen::Vector3d(0.0, 0.0, 0.1));
  EXPECT_EQ(sim.colliderVelocity(1), Eigen::Vector3d::Zero());
}

// Bad input is refused naming the problem, and changes nothing: the run continues exactly as
// one that never saw the calls.
TEST(ColliderMotionApi, BadInputIsRefusedAndChangesNothing) {
  const SimulatorOptions o = contactOptions();
  Simulator sim(barAndBox(), o), untouched(barAndBox(), o);
  sim.step();
  untouched.step();
  const double nan = std::nan(""), inf = INFINITY;
  auto refused = [&](auto&& call, const std::string& names) {
    try {
      call();
      ADD_FAILURE() << "accepted; expected " << names;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  refused([&] { sim.setColliderPosition(2, Eigen::Vector3d::Zero()); }, "collider 2 out of range (the scene has 2");
  refused([&] { sim.setColliderPosition(-1, Eigen::Vector3d::Zero()); }, "collider -1 out of range");
  refused([&] { sim.setColliderVelocity(5, Eigen::Vector3d::Zero()); }, "collider 5 out of range");
  refused([&] { sim.setColliderPosition(1, Eigen::Vector3d(0.0, nan, 0.0)); }, "collider 1: position is not finite");
  refused([&] { sim.setColliderPosition(1, Eigen::Vector3d(1e200, 0.0, 0.0)); }, "exceeds 1e+150");
  refused([&] { sim.setColliderVelocity(0, Eigen::Vector3d(inf, 0.0, 0.0)); }, "collider 0: velocity is not finite");
  refused([&] { sim.colliderPosition(2); }, "collider 2 out of range");
  refused([&] { sim.colliderVelocity(-1); }, "collider -1 out of range");
  EXPECT_EQ(sim.colliderPosition(1), untouched.colliderPosition(1));
  for (int i = 0; i < 5; ++i) {
    sim.step();
    untouched.step();
  }
  EXPECT_EQ(sim.positions(), untouched.positions());
  EXPECT_EQ(sim.target(), untouched.target());
}

// A version 2 checkpoint (before collider motion and the contact set's log existed) is still
// read: its colliders follow their scene laws, which is all they could do then, and its log is
// empty. Made from a version 3 one of a scene whose colliders were never driven by dropping the
// motion section and the log (an int64 count of int32 entries, the last section) and writing
// version 2. Without the log the restore factors L from the current contact set where the
// original's factor was rank-updated to it: the same matrix, other round-off, so the runs agree
// to round-off amplified by 10 steps (1e-9 m on a bar of 1 m, measured ~1e-13), not bit for bit.
TEST(ColliderMotionApi, VersionTwoCheckpointsAreStillRead) {
  const SimulatorOptions o = contactOptions();
  const Scene s = barAndBox(Eigen::Vector3d(0.5, 0.0, 0.0));
  Simulator sim(s, o);
  for (int i = 0; i < 10; ++i) sim.step();
  // The log's size in bytes: the shortest tail whose leading int64 counts the int32s after it.
  auto logBytes = [](const std::string& bytes) {
    for (std::size_t entries = 0; 8 + 4 * entries <= bytes.size(); ++entries) {
      std::int64_t count = 0;
      std::memcpy(&count, &bytes[bytes.size() - 8 - 4 * entries], sizeof(count));
      if (count == static_cast<std::int64_t>(entries)) return 8 + 4 * entries;
    }
    return std::size_t(0);
  };
  // Version 4 and later end in an 8-byte checksum; without it the layout is version 3's.
  auto asVersion = [](std::string bytes, std::uint32_t version) {
    bytes.resize(bytes.size() - 8);
    std::memcpy(&bytes[8], &version, sizeof(version));
    return bytes;
  };
  std::string bytes = asVersion(sim.checkpoint().bytes(), 3);
  const std::size_t log_bytes = logBytes(bytes);
  ASSERT_GT(log_bytes, 0u);
  const std::size_t motion_bytes = 8 + s.colliders.size() * (11 * sizeof(double) + 1);
  bytes.resize(bytes.size() - log_bytes - motion_bytes);
  const std::uint32_t version = 2;
  std::memcpy(&bytes[8], &version, sizeof(version));
  Simulator other(s, o);
  other.restore(Checkpoint::fromBytes(bytes, "v2"));
  for (int i = 0; i < 10; ++i) {
    sim.step();
    other.step();
  }
  EXPECT_LT((other.positions() - sim.positions()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(other.colliderPosition(1), sim.colliderPosition(1));
  // A version 3 one cut short is refused, naming the section.
  std::string cut = asVersion(sim.checkpoint().bytes(), 3);
  cut.resize(cut.size() - logBytes(cut) - 5);
  try {
    Checkpoint::fromBytes(cut, "cut");
    ADD_FAILURE() << "a truncated checkpoint was accepted";
  } catch (const FileFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("collider"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace stabint
