// The player of scripted events (include/stabint/events.hpp): every action goes through the
// per-frame input of a Simulator or of one scene of a batch, which validates it and books its
// energy; one player (EventScript::play) over a small adaptor of each.
#include <stabint/batch.hpp>
#include <stabint/events.hpp>

#include <cmath>
#include <cstddef>
#include <sstream>

namespace stabint {
namespace {

std::string eventName(std::size_t i, const ScriptedEvent& e) {
  return "event " + std::to_string(i) + " (frame " + std::to_string(e.frame) + ")";
}

// Visitor helper: one lambda per alternative.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

// Where a path that starts at `start` on `start_frame` is at `frame`: linear between the
// keyframes, constant after the last one. A path applied late (after its frame) may start at or
// after a keyframe: it goes straight to the next one.
Eigen::Vector3d pathAt(const std::vector<PathKey>& path, int start_frame, const Eigen::Vector3d& start, int frame) {
  int f0 = start_frame;
  Eigen::Vector3d q0 = start;
  for (const PathKey& k : path) {
    if (frame <= k.frame) {
      const double s = k.frame > f0 ? static_cast<double>(frame - f0) / static_cast<double>(k.frame - f0) : 1.0;
      return frame == k.frame ? k.position : Eigen::Vector3d((1.0 - s) * q0 + s * k.position);
    }
    f0 = k.frame;
    q0 = k.position;
  }
  return path.back().position;
}

// What the player calls, on a Simulator.
struct SimulatorTarget {
  Simulator& sim;
  int stepCount() const { return sim.stepCount(); }
  int grab(int vertex, double stiffness) { return sim.grab(vertex, stiffness); }
  Eigen::Vector3d position(int vertex) const { return sim.positions().row(vertex).transpose(); }
  void release(int pin) { sim.release(pin); }
  Eigen::MatrixX3d velocities() const { return sim.velocities(); }
  void setVelocities(const Eigen::MatrixX3d& v) { sim.setVelocities(v); }
  void setElementStiffness(ElementKind kind, const std::vector<int>& indices, double stiffness) {
    sim.setElementStiffness(kind, indices, stiffness);
  }
  void setElementEnabled(ElementKind kind, const std::vector<int>& indices, bool enabled) {
    sim.setElementEnabled(kind, indices, enabled);
  }
  void setPinTarget(int pin, const Eigen::Vector3d& q) { sim.setPinTarget(pin, q); }
  void setColliderPosition(int collider, const Eigen::Vector3d& p) { sim.setColliderPosition(collider, p); }
  void setColliderVelocity(int collider, const Eigen::Vector3d& v) { sim.setColliderVelocity(collider, v); }
  Eigen::Vector3d colliderPosition(int collider) const { return sim.colliderPosition(collider); }
  std::string where() const { return std::string(); }
};

// The same on scene `scene` of a batch: its calls with the scene first; the velocities are set by
// setState with the scene's positions (the batch has no setVelocities).
struct BatchSceneTarget {
  BatchSimulator& batch;
  int scene;
  int stepCount() const { return batch.stepCount(scene); }
  int grab(int vertex, double stiffness) { return batch.grab(scene, vertex, stiffness); }
  Eigen::Vector3d position(int vertex) const { return batch.positions(scene).row(vertex).transpose(); }
  void release(int pin) { batch.release(scene, pin); }
  Eigen::MatrixX3d velocities() const { return batch.velocities(scene); }
  void setVelocities(const Eigen::MatrixX3d& v) { batch.setState(scene, batch.positions(scene), v); }
  void setElementStiffness(ElementKind kind, const std::vector<int>& indices, double stiffness) {
    batch.setElementStiffness(scene, kind, indices, stiffness);
  }
  void setElementEnabled(ElementKind kind, const std::vector<int>& indices, bool enabled) {
    batch.setElementEnabled(scene, kind, indices, enabled);
  }
  void setPinTarget(int pin, const Eigen::Vector3d& q) { batch.setPinTarget(scene, pin, q); }
  void setColliderPosition(int collider, const Eigen::Vector3d& p) { batch.setColliderPosition(scene, collider, p); }
  void setColliderVelocity(int collider, const Eigen::Vector3d& v) { batch.setColliderVelocity(scene, collider, v); }
  Eigen::Vector3d colliderPosition(int collider) const { return batch.colliderPosition(scene, collider); }
  std::string where() const { return "scene " + std::to_string(scene) + ": "; }
};

}  // namespace

EventScript::EventScript(std::vector<ScriptedEvent> events) : events_(std::move(events)) {
  // Grabs seen so far by id, and whether each is still held; vertices of held grabs.
  std::vector<std::pair<std::string, bool>> grabs;
  std::vector<int> held_vertices;
  int previous_frame = 0;
  for (std::size_t i = 0; i < events_.size(); ++i) {
    const ScriptedEvent& e = events_[i];
    auto fail = [&](const std::string& what) { throw InvalidInputError(eventName(i, e) + ": " + what); };
    if (e.frame < 0) fail("frame must be >= 0");
    if (e.frame < previous_frame)
      fail("frames must not decrease (the previous event is at frame " + std::to_string(previous_frame) + ")");
    previous_frame = e.frame;
    auto checkPath = [&](const std::vector<PathKey>& path, const char* owner) {
      int last = e.frame;
      for (std::size_t k = 0; k < path.size(); ++k) {
        if (path[k].frame <= last)
          fail(std::string(owner) + " path keyframe " + std::to_string(k) + " must come after frame " +
               std::to_string(last));
        if (!path[k].position.allFinite())
          fail(std::string(owner) + " path keyframe " + std::to_string(k) + " is not finite");
        last = path[k].frame;
      }
    };
    std::visit(Overloaded{
                   [&](const GrabEvent& g) {
                     if (!std::isfinite(g.stiffness) || !(g.stiffness > 0.0))
                       fail("grab stiffness must be finite and > 0");
                     if (g.vertex < 0) fail("grab vertex " + std::to_string(g.vertex) + " must be >= 0");
                     checkPath(g.path, "grab");
                     if (!g.id.empty())
                       for (const auto& seen : grabs)
                         if (seen.first == g.id) fail("grab id '" + g.id + "' is used twice");
                     grabs.emplace_back(g.id, true);
                     held_vertices.push_back(g.vertex);
                   },
                   [&](const ReleaseEvent& r) {
                     if (!r.id.empty()) {
                       for (std::size_t k = 0; k < grabs.size(); ++k) {
                         if (grabs[k].first != r.id) continue;
                         if (!grabs[k].second) fail("grab '" + r.id + "' is already released");
                         grabs[k].second = false;
                         held_vertices[k] = -1;
                         return;
                       }
                       fail("release of '" + r.id + "': no earlier grab has that id");
                     }
                     for (std::size_t k = held_vertices.size(); k-- > 0;) {
                       if (held_vertices[k] != r.vertex) continue;
                       grabs[k].second = false;
                       held_vertices[k] = -1;
                       return;
                     }
                     fail("release of vertex " + std::to_string(r.vertex) + ": no handle is held there");
                   },
                   [&](const ImpulseEvent& im) {
                     if (im.vertices.empty()) fail("impulse lists no vertex");
                     if (!im.velocity.allFinite()) fail("impulse velocity is not finite");
                   },
                   [&](const ElementEvent& el) {
                     if (el.indices.empty()) fail("elements event lists no element");
                     if (!el.stiffness && !el.enabled)
                       fail("elements event needs a stiffness, an enabled flag or both");
                     if (el.stiffness && (!std::isfinite(*el.stiffness) || !(*el.stiffness >= 0.0)))
                       fail("elements event stiffness must be finite and >= 0");
                   },
                   [&](const ColliderEvent& c) {
                     if (c.collider < 0) fail("collider " + std::to_string(c.collider) + " must be >= 0");
                     if (c.path.empty() == !c.velocity) fail("collider event needs a path or a velocity (one of them)");
                     if (c.velocity && !c.velocity->allFinite()) fail("collider velocity is not finite");
                     checkPath(c.path, "collider");
                   },
               },
               e.action);
  }
}

int EventScript::handlePin(const std::string& id) const {
  for (const Handle& h : held_)
    if (std::get<GrabEvent>(events_[h.event].action).id == id) return h.pin;
  return -1;
}

void EventScript::apply(Simulator& sim) {
  SimulatorTarget target{sim};
  play(target);
}

void EventScript::apply(BatchSimulator& batch, int scene) {
  if (scene < 0 || scene >= batch.size())
    throw InvalidInputError("EventScript::apply: scene " + std::to_string(scene) + " out of range (the batch has " +
                            std::to_string(batch.size()) + " scenes)");
  BatchSceneTarget target{batch, scene};
  play(target);
}

template <typename Target>
void EventScript::play(Target& sim) {
  const int frame = sim.stepCount();
  for (; next_ < events_.size() && events_[next_].frame <= frame; ++next_) {
    const ScriptedEvent& e = events_[next_];
    try {
      std::visit(Overloaded{
                     [&](const GrabEvent& g) {
                       Handle h;
                       h.event = next_;
                       h.pin = sim.grab(g.vertex, g.stiffness);
                       h.start_frame = frame;
                       h.start = sim.position(g.vertex);
                       held_.push_back(h);
                     },
                     [&](const ReleaseEvent& r) {
                       for (std::size_t k = held_.size(); k-- > 0;) {
                         const GrabEvent& g = std::get<GrabEvent>(events_[held_[k].event].action);
                         if (r.id.empty() ? g.vertex != r.vertex : g.id != r.id) continue;
                         sim.release(held_[k].pin);
                         held_.erase(held_.begin() + static_cast<std::ptrdiff_t>(k));
                         return;
                       }
                     },
                     [&](const ImpulseEvent& im) {
                       Eigen::MatrixX3d v = sim.velocities();
                       for (int j : im.vertices) {
                         if (j < 0 || j >= v.rows())
                           throw InvalidInputError(sim.where() + "impulse vertex " + std::to_string(j) +
                                                   " out of range (the scene has " + std::to_string(v.rows()) +
                                                   " particles)");
                       }
                       for (int j : im.vertices) v.row(j) += im.velocity.transpose();
                       sim.setVelocities(v);
                     },
                     [&](const ElementEvent& el) {
                       if (el.stiffness) sim.setElementStiffness(el.kind, el.indices, *el.stiffness);
                       if (el.enabled) sim.setElementEnabled(el.kind, el.indices, *el.enabled);
                     },
                     [&](const ColliderEvent& c) {
                       // Validated by the simulator first, so a refused event leaves the path
                       // under way, if any, playing.
                       Handle path{next_, c.collider, frame, Eigen::Vector3d::Zero()};
                       if (c.velocity) {
                         sim.setColliderVelocity(c.collider, *c.velocity);
                       } else {
                         path.start = sim.colliderPosition(c.collider);
                       }
                       for (std::size_t k = collider_paths_.size(); k-- > 0;)
                         if (collider_paths_[k].pin == c.collider)
                           collider_paths_.erase(collider_paths_.begin() + static_cast<std::ptrdiff_t>(k));
                       if (!c.velocity) collider_paths_.push_back(path);
                     },
                 },
                 e.action);
    } catch (const InvalidInputError& error) {
      ++next_;  // not retried on the next call
      throw InvalidInputError(eventName(next_ - 1, e) + ": " + error.what());
    }
  }
  // Each held handle's target and each moving collider's position for the end of the coming step
  // (frame + 1), from their paths.
  const int f = frame + 1;
  for (const Handle& h : held_) {
    const GrabEvent& g = std::get<GrabEvent>(events_[h.event].action);
    if (!g.path.empty()) sim.setPinTarget(h.pin, pathAt(g.path, h.start_frame, h.start, f));
  }
  for (std::size_t k = 0; k < collider_paths_.size();) {
    const Handle& h = collider_paths_[k];
    const std::vector<PathKey>& path = std::get<ColliderEvent>(events_[h.event].action).path;
    sim.setColliderPosition(h.pin, pathAt(path, h.start_frame, h.start, f));
    // At its last keyframe the collider stays: the path is done.
    if (f >= path.back().frame) {
      collider_paths_.erase(collider_paths_.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
}

}  // namespace stabint
