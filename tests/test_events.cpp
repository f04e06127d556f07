// Scripted events in scene files (docs/scene-format.md, "Events") and their player
// (include/stabint/events.hpp): a scripted grab-drag-release replays the same states as the same
// calls made by hand, the format round-trips exactly, and bad events are errors naming their
// JSON path.
#include <stabint/stabint.hpp>

#include "temp_dir_test.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>
#include <variant>
#include <vector>

namespace stabint {
namespace {

class EventsTest : public testing::TempDirTest {
 protected:
  // A 6 x 6 spring cloth (particle 30 is its free bottom-left corner, 35 the bottom-right one)
  // with `events` (the text of a JSON list).
  std::string sceneWith(const std::string& events) const {
    return write("scene.json", R"({"format": "stabint-scene", "version": 1,
      "builtin": {"name": "cloth", "nx": 6, "ny": 6}, "events": )" +
                                   events + "}");
  }

  // The same cloth with a sphere (collider 0) behind it and the ground (collider 1) far below.
  std::string sceneWithColliders(const std::string& events) const {
    return write("colliders.json", R"({"format": "stabint-scene", "version": 1,
      "builtin": {"name": "cloth", "nx": 6, "ny": 6},
      "colliders": [{"shape": "sphere", "center": [0.5, -0.5, -0.3], "radius": 0.2},
                    {"shape": "plane", "center": [0, -3, 0]}],
      "events": )" + events + "}");
  }

  void expectError(const std::string& events, const std::string& names, bool colliders = false) const {
    const std::string path = colliders ? sceneWithColliders(events) : sceneWith(events);
    try {
      loadSceneFileWithEvents(path);
      ADD_FAILURE() << "accepted: " << events;
    } catch (const FileFormatError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  }
};

const char* kDragEvents = R"([
  {"frame": 5, "grab": {"id": "hand", "vertex": 30, "stiffness": 2000,
                        "path": [[10, 0.1, 0.2, 0.3], [15, -0.1, 0.3, 0.2]]}},
  {"frame": 20, "release": "hand"},
  {"frame": 22, "impulse": {"where": {"axis": "y", "max": 0.01}, "velocity": [0, 0, 0.4]}},
  {"frame": 25, "elements": {"kind": "springs", "indices": [0, 1, 2], "stiffness": 50}},
  {"frame": 25, "elements": {"kind": "pins", "indices": [1], "enabled": false}}
])";

// The same interaction by hand: the handle's target at the end of each step is linear between
// the grab position (frame 5) and the keyframes (frames 10, 15), the documented rule.
TEST_F(EventsTest, ScriptedDragReplaysTheSameCallsMadeByHand) {
  const SceneFile file = loadSceneFileWithEvents(sceneWith(kDragEvents));
  ASSERT_EQ(file.events.events().size(), 5u);
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  Simulator scripted(file.scene, o), by_hand(file.scene, o);
  EventScript script = file.events;
  const std::vector<int> bottom_row = {30, 31, 32, 33, 34, 35};
  int pin = -1;
  Eigen::Vector3d start;
  const Eigen::Vector3d key1(0.1, 0.2, 0.3), key2(-0.1, 0.3, 0.2);
  for (int frame = 0; frame < 40; ++frame) {
    script.apply(scripted);
    if (frame == 5) {
      pin = by_hand.grab(30, 2000.0);
      start = by_hand.positions().row(30).transpose();
    }
    if (frame >= 5 && frame < 20) {
      const int f = frame + 1;
      Eigen::Vector3d q = key2;
      if (f < 10) q = (1.0 - (f - 5) / 5.0) * start + ((f - 5) / 5.0) * key1;
      if (f == 10) q = key1;
      if (f > 10 && f < 15) q = (1.0 - (f - 10) / 5.0) * key1 + ((f - 10) / 5.0) * key2;
      by_hand.setPinTarget(pin, q);
      EXPECT_EQ(script.handlePin("hand"), pin);
    }
    if (frame == 20) by_hand.release(pin);
    if (frame == 22) {
      Eigen::MatrixX3d v = by_hand.velocities();
      for (int j : bottom_row) v(j, 2) += 0.4;
      by_hand.setVelocities(v);
    }
    if (frame == 25) {
      by_hand.setElementStiffness(ElementKind::Spring, {0, 1, 2}, 50.0);
      by_hand.setElementEnabled(ElementKind::Pin, 1, false);
    }
    const StepReport a = scripted.step();
    const StepReport b = by_hand.step();
    ASSERT_EQ(scripted.positions(), by_hand.positions()) << "frame " << frame;
    ASSERT_EQ(scripted.velocities(), by_hand.velocities()) << "frame " << frame;
    EXPECT_EQ(a.event_energy, b.event_energy) << "frame " << frame;
    EXPECT_EQ(a.target, b.target) << "frame " << frame;
    // The handle reached its last keyframe at frame 15: the corner followed it (a 2000 N/m
    // handle on a 0.1 kg cloth holds it within a few cm).
    if (frame == 19) {
      EXPECT_LT((scripted.positions().row(30).transpose() - key2).norm(), 0.05);
    }
  }
  EXPECT_EQ(script.handlePin("hand"), -1) << "released";
}

// The impulse's kinetic energy jump is booked as the next step's event energy.
TEST_F(EventsTest, ImpulsesBookTheirKineticEnergyJump) {
  const SceneFile file = loadSceneFileWithEvents(
      sceneWith(R"([{"frame": 3, "impulse": {"vertices": [30, 35], "velocity": [0.5, 0, 0]}}])"));
  Simulator sim(file.scene, {});
  EventScript script = file.events;
  for (int i = 0; i < 3; ++i) {
    script.apply(sim);
    sim.step();
  }
  const double k_before = sim.energy().kinetic;
  Eigen::MatrixX3d v = sim.velocities();
  script.apply(sim);
  v(30, 0) += 0.5;
  v(35, 0) += 0.5;
  EXPECT_EQ(sim.velocities(), v);
  const double jump = sim.energy().kinetic - k_before;
  EXPECT_GT(jump, 0.0);
  // The booking sums K + P in another order than energy(): round-off of H's terms.
  EXPECT_NEAR(sim.step().event_energy, jump, 1e-12 * sim.energyScale());
}

// Saved and loaded again: the same events, field by field, and the same text once more.
TEST_F(EventsTest, EventsRoundTripExactly) {
  const SceneFile file = loadSceneFileWithEvents(sceneWith(kDragEvents));
  const std::string path = (dir_ / "saved.json").string();
  saveSceneFileWithEvents(file.scene, file.events, path);
  const SceneFile again = loadSceneFileWithEvents(path);
  const auto& a = file.events.events();
  const auto& b = again.events.events();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].frame, b[i].frame);
    ASSERT_EQ(a[i].action.index(), b[i].action.index()) << i;
  }
  const auto& g0 = std::get<GrabEvent>(a[0].action);
  const auto& g1 = std::get<GrabEvent>(b[0].action);
  EXPECT_EQ(g0.id, g1.id);
  EXPECT_EQ(g0.vertex, g1.vertex);
  EXPECT_EQ(g0.stiffness, g1.stiffness);
  ASSERT_EQ(g1.path.size(), 2u);
  EXPECT_EQ(g1.path[1].frame, 15);
  EXPECT_EQ(g1.path[1].position, Eigen::Vector3d(-0.1, 0.3, 0.2));
  EXPECT_EQ(std::get<ReleaseEvent>(b[1].action).id, "hand");
  EXPECT_EQ(std::get<ImpulseEvent>(b[2].action).vertices, (std::vector<int>{30, 31, 32, 33, 34, 35}));
  EXPECT_EQ(std::get<ImpulseEvent>(b[2].action).velocity, Eigen::Vector3d(0, 0, 0.4));
  EXPECT_EQ(std::get<ElementEvent>(b[3].action).stiffness, 50.0);
  EXPECT_FALSE(std::get<ElementEvent>(b[3].action).enabled.has_value());
  EXPECT_EQ(std::get<ElementEvent>(b[4].action).kind, ElementKind::Pin);
  EXPECT_EQ(std::get<ElementEvent>(b[4].action).enabled, false);
  const std::string path2 = (dir_ / "saved2.json").string();
  saveSceneFileWithEvents(again.scene, again.events, path2);
  std::ifstream f1(path), f2(path2);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(f1), {}), std::string(std::istreambuf_iterator<char>(f2), {}));
  // A scene file without events loads as before, and with events loadSceneFile still accepts it.
  EXPECT_EQ(loadSceneFile(path).numParticles(), 36);
}

const char* kColliderEvents = R"([
  {"frame": 2, "collider": {"index": 0, "path": [[6, 0.5, -0.5, 0.1], [10, 0.3, -0.4, 0.2]]}},
  {"frame": 3, "grab": {"id": "hand", "vertex": 30, "stiffness": 2000, "path": [[12, 0.1, -0.8, 0.3]]}},
  {"frame": 14, "collider": {"index": 0, "velocity": [0, 0.5, 0]}},
  {"frame": 16, "collider": {"index": 1, "path": [[20, 0, -2.9, 0]]}},
  {"frame": 18, "release": "hand"}
])";

// A scripted collider path is the same setColliderPosition calls made by hand (the grab's
// keyframe rule), a velocity event is setColliderVelocity, and the collider is exactly at each
// keyframe at its frame.
TEST_F(EventsTest, ColliderEventsReplayTheSameCallsMadeByHand) {
  const SceneFile file = loadSceneFileWithEvents(sceneWithColliders(kColliderEvents));
  SimulatorOptions o;
  Simulator scripted(file.scene, o), by_hand(file.scene, o);
  EventScript script = file.events;
  const Eigen::Vector3d start = file.scene.colliders[0].center, key1(0.5, -0.5, 0.1), key2(0.3, -0.4, 0.2);
  const Eigen::Vector3d ground = file.scene.colliders[1].center, ground_key(0.0, -2.9, 0.0);
  int pin = -1;
  Eigen::Vector3d grabbed;
  for (int frame = 0; frame < 24; ++frame) {
    script.apply(scripted);
    const int f = frame + 1;
    if (frame >= 2 && frame < 10) {
      Eigen::Vector3d q = key2;
      if (f < 6) q = (1.0 - (f - 2) / 4.0) * start + ((f - 2) / 4.0) * key1;
      if (f == 6) q = key1;
      if (f > 6 && f < 10) q = (1.0 - (f - 6) / 4.0) * key1 + ((f - 6) / 4.0) * key2;
      by_hand.setColliderPosition(0, q);
    }
    if (frame == 3) {
      pin = by_hand.grab(30, 2000.0);
      grabbed = by_hand.positions().row(30).transpose();
    }
    if (frame >= 3 && frame < 18) {
      const double s = std::min(1.0, (f - 3) / 9.0);
      by_hand.setPinTarget(pin, f >= 12 ? Eigen::Vector3d(0.1, -0.8, 0.3)
                                        : Eigen::Vector3d((1.0 - s) * grabbed + s * Eigen::Vector3d(0.1, -0.8, 0.3)));
    }
    if (frame == 14) by_hand.setColliderVelocity(0, Eigen::Vector3d(0.0, 0.5, 0.0));
    if (frame >= 16 && frame < 20)
      by_hand.setColliderPosition(
          1, f == 20 ? ground_key : Eigen::Vector3d((1.0 - (f - 16) / 4.0) * ground + ((f - 16) / 4.0) * ground_key));
    if (frame == 18) by_hand.release(pin);
    scripted.step();
    by_hand.step();
    ASSERT_EQ(scripted.positions(), by_hand.positions()) << "frame " << frame;
    ASSERT_EQ(scripted.target(), by_hand.target()) << "frame " << frame;
    ASSERT_EQ(scripted.colliderPosition(0), by_hand.colliderPosition(0)) << "frame " << frame;
    ASSERT_EQ(scripted.colliderPosition(1), by_hand.colliderPosition(1)) << "frame " << frame;
    if (scripted.stepCount() == 6) {
      EXPECT_EQ(scripted.colliderPosition(0), key1);
    }
    if (scripted.stepCount() == 10) {
      EXPECT_EQ(scripted.colliderPosition(0), key2);
    }
  }
  EXPECT_EQ(scripted.colliderPosition(1), ground_key) << "stays at its last keyframe";
  EXPECT_EQ(scripted.colliderVelocity(0), Eigen::Vector3d(0.0, 0.5, 0.0));
}

// A checkpoint holds the simulator, not the script's progress (handles held, collider paths
// under way): the documented way is to copy the script with the checkpoint and play the copy
// after restoring. That continues in the middle of a drag and a collider path, to round-off here
// (a fresh simulator restoring a grab; bit for bit where the pins are the same).
TEST_F(EventsTest, ACopyOfTheScriptTakenWithACheckpointContinues) {
  const SceneFile file = loadSceneFileWithEvents(sceneWithColliders(kColliderEvents));
  SimulatorOptions o;
  Simulator sim(file.scene, o);
  EventScript script = file.events;
  Checkpoint checkpoint;
  EventScript saved;
  for (int frame = 0; frame < 24; ++frame) {
    if (frame == 8) {  // the hand is dragging, the sphere is on its path
      checkpoint = sim.checkpoint();
      saved = script;
    }
    script.apply(sim);
    sim.step();
  }
  Simulator restored(file.scene, o);
  restored.restore(Checkpoint::fromBytes(checkpoint.bytes()));
  for (int frame = 8; frame < 24; ++frame) {
    saved.apply(restored);
    restored.step();
  }
  // The restore refactors L with the grab's pin in it where the original rank-updated its factor
  // (with colliders a restore always assembles and factors anew, docs/method.md "Per-frame
  // input"): the same matrix, other round-off, amplified over 16 steps (measured 7e-13 m).
  EXPECT_LT((restored.positions() - sim.positions()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(restored.target(), sim.target(), 1e-9 * std::abs(sim.target()) + 1e-9);
  EXPECT_EQ(restored.colliderPosition(0), sim.colliderPosition(0));
}

TEST_F(EventsTest, ColliderEventsRoundTripAndBadOnesNameTheirPath) {
  const SceneFile file = loadSceneFileWithEvents(sceneWithColliders(kColliderEvents));
  const std::string path = (dir_ / "saved.json").string();
  saveSceneFileWithEvents(file.scene, file.events, path);
  const SceneFile again = loadSceneFileWithEvents(path);
  ASSERT_EQ(again.events.events().size(), 5u);
  const auto& c0 = std::get<ColliderEvent>(again.events.events()[0].action);
  EXPECT_EQ(c0.collider, 0);
  ASSERT_EQ(c0.path.size(), 2u);
  EXPECT_EQ(c0.path[1].frame, 10);
  EXPECT_EQ(c0.path[1].position, Eigen::Vector3d(0.3, -0.4, 0.2));
  EXPECT_FALSE(c0.velocity.has_value());
  const auto& c2 = std::get<ColliderEvent>(again.events.events()[2].action);
  EXPECT_EQ(c2.velocity, Eigen::Vector3d(0.0, 0.5, 0.0));
  EXPECT_TRUE(c2.path.empty());

  expectError(R"([{"frame": 1, "collider": {"index": 2, "velocity": [0, 0, 1]}}])",
              "events[0].collider.index: collider 2 out of range [0, 2)", true);
  expectError(R"([{"frame": 1, "collider": {"index": 0, "velocity": [0, 0, 1]}}])",
              "events[0].collider.index: collider 0 out of range [0, 0)");
  expectError(R"([{"frame": 1, "collider": {"index": 0}}])", "events[0].collider: needs path or velocity", true);
  expectError(R"([{"frame": 1, "collider": {"index": 0, "velocity": [0, 0, 1], "path": [[3, 0, 0, 0]]}}])",
              "events[0].collider.velocity: give either path or velocity, not both", true);
  expectError(R"([{"frame": 4, "collider": {"index": 0, "path": [[4, 0, 0, 0]]}}])",
              "events[0].collider.path[0][0]: keyframe frame 4 must be after 4 (the event's frame)", true);
  expectError(R"([{"frame": 4, "collider": {"index": 0, "path": []}}])", "events[0].collider.path: lists no keyframe",
              true);
  expectError(R"([{"frame": 4, "collider": {"index": 0, "velocity": [0, 1]}}])", "events[0].collider.velocity", true);
  expectError(R"([{"frame": 4, "collider": {"index": 0, "spin": 1}}])", "events[0].collider: unknown field 'spin'",
              true);
  // The script's own checks, and the simulator's refusal of a collider it does not have.
  EXPECT_THROW(EventScript({ScriptedEvent{0, ColliderEvent{0, {}, std::nullopt}}}), InvalidInputError);
  EXPECT_THROW(
      EventScript({ScriptedEvent{0, ColliderEvent{0, {PathKey{1, Eigen::Vector3d::Zero()}}, Eigen::Vector3d::Zero()}}}),
      InvalidInputError);
  EventScript far({ScriptedEvent{0, ColliderEvent{3, {}, Eigen::Vector3d::UnitX()}}});
  Simulator sim(file.scene, {});
  try {
    far.apply(sim);
    ADD_FAILURE() << "moved collider 3";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("event 0 (frame 0): collider 3 out of range"), std::string::npos) << e.what();
  }
}

TEST_F(EventsTest, BadEventsNameTheirPath) {
  expectError(R"([{"frame": 1, "grab": {"vertex": 36, "stiffness": 1}}])", "events[0].grab.vertex: particle index 36");
  EXPECT_THROW(loadSceneFile(sceneWith(R"([{"frame": 1, "release": "nobody"}])")), FileFormatError)
      << "loadSceneFile checks the events too";
  expectError(R"([{"frame": 1, "grab": {"vertex": 3, "stiffness": 0}}])", "events[0].grab.stiffness: must be > 0");
  expectError(R"([{"frame": 4, "grab": {"vertex": 3, "stiffness": 1, "path": [[6, 0, 0, 0], [6, 1, 0, 0]]}}])",
              "events[0].grab.path[1][0]: keyframe frame 6 must be after 6");
  expectError(R"([{"frame": 4, "grab": {"vertex": 3, "stiffness": 1, "path": [[6, 0, 0]]}}])",
              "events[0].grab.path[0]: expected a keyframe [frame, x, y, z]");
  expectError(R"([{"frame": 1, "release": "nobody"}])", "event 0 (frame 1): release of 'nobody'");
  expectError(R"([{"frame": 1, "release": 4}])", "release of vertex 4: no handle is held there");
  expectError(R"([{"frame": 5, "impulse": {"vertices": [1], "velocity": [0, 0, 1]}}, {"frame": 2, "release": 1}])",
              "frames must not decrease");
  expectError(R"([{"frame": -1, "impulse": {"vertices": [1], "velocity": [0, 0, 1]}}])",
              "events[0].frame: must be >= 0");
  expectError(R"([{"frame": 1, "impulse": {"velocity": [0, 0, 1]}}])", "events[0].impulse: needs vertices or where");
  expectError(R"([{"frame": 1, "elements": {"kind": "tets", "indices": [0], "stiffness": 1}}])",
              "events[0].elements.indices[0]: tet 0 out of range [0, 0)");
  expectError(R"([{"frame": 1, "elements": {"kind": "colliders", "indices": [0], "stiffness": 1}}])",
              "events[0].elements.kind: unknown element kind");
  expectError(R"([{"frame": 1, "elements": {"kind": "springs", "indices": [0]}}])", "needs stiffness, enabled or both");
  expectError(R"([{"frame": 1, "grab": {"vertex": 1, "stiffness": 1}, "release": 1}])", "exactly one of");
  expectError(R"([{"frame": 1, "teleport": {}}])", "events[0]: unknown field 'teleport'");
  // Values beyond 1e150 (the rule of every per-frame input) are refused at load, naming the event.
  expectError(R"([{"frame": 4, "grab": {"vertex": 3, "stiffness": 1, "path": [[6, 0, 1e300, 0]]}}])",
              "events[0].grab.path[0][2]: 1e+300 exceeds 1e150");
  expectError(R"([{"frame": 1, "grab": {"vertex": 3, "stiffness": 1e300}}])",
              "events[0].grab.stiffness: 1e+300 exceeds 1e150");
  expectError(R"([{"frame": 1, "impulse": {"vertices": [1], "velocity": [0, -1e300, 0]}}])",
              "events[0].impulse.velocity[1]: -1e+300 exceeds 1e150");
  expectError(R"([{"frame": 1, "elements": {"kind": "springs", "indices": [0], "stiffness": 1e200}}])",
              "events[0].elements.stiffness: 1e+200 exceeds 1e150");
  expectError(R"([{"frame": 1, "grab": {"id": "a", "vertex": 1, "stiffness": 1}},
                  {"frame": 2, "grab": {"id": "a", "vertex": 2, "stiffness": 1}}])",
              "grab id 'a' is used twice");
  // The player refuses what the simulator refuses, naming the event; the script itself too.
  EXPECT_THROW(EventScript({ScriptedEvent{0, GrabEvent{"", 1, -1.0, {}}}}), InvalidInputError);
  EventScript far({ScriptedEvent{0, ImpulseEvent{{1000}, Eigen::Vector3d::UnitX()}}});
  Simulator sim(loadSceneFile(sceneWith("[]")), {});
  try {
    far.apply(sim);
    ADD_FAILURE() << "applied an impulse on particle 1000";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("event 0 (frame 0): impulse vertex 1000 out of range"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace stabint
