// The player of scripted events (include/stabint/events.hpp): every action goes through the
// Simulator's per-frame input, which validates it and books its energy.
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
    std::visit(
        Overloaded{
            [&](const GrabEvent& g) {
              if (!std::isfinite(g.stiffness) || !(g.stiffness > 0.0)) fail("grab stiffness must be finite and > 0");
              if (g.vertex < 0) fail("grab vertex " + std::to_string(g.vertex) + " must be >= 0");
              int last = e.frame;
              for (std::size_t k = 0; k < g.path.size(); ++k) {
                if (g.path[k].frame <= last)
                  fail("grab path keyframe " + std::to_string(k) + " must come after frame " + std::to_string(last));
                if (!g.path[k].position.allFinite()) fail("grab path keyframe " + std::to_string(k) + " is not finite");
                last = g.path[k].frame;
              }
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
              if (!el.stiffness && !el.enabled) fail("elements event needs a stiffness, an enabled flag or both");
              if (el.stiffness && (!std::isfinite(*el.stiffness) || !(*el.stiffness >= 0.0)))
                fail("elements event stiffness must be finite and >= 0");
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
                       h.start = sim.positions().row(g.vertex).transpose();
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
                           throw InvalidInputError("impulse vertex " + std::to_string(j) +
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
                 },
                 e.action);
    } catch (const InvalidInputError& error) {
      ++next_;  // not retried on the next call
      throw InvalidInputError(eventName(next_ - 1, e) + ": " + error.what());
    }
  }
  // Each held handle's target for the end of the coming step (frame + 1): linear between the
  // grab's position at its frame and the keyframes, constant after the last one.
  for (const Handle& h : held_) {
    const GrabEvent& g = std::get<GrabEvent>(events_[h.event].action);
    if (g.path.empty()) continue;
    const int f = frame + 1;
    int f0 = h.start_frame;
    Eigen::Vector3d q0 = h.start, q = g.path.back().position;
    for (const PathKey& k : g.path) {
      if (f <= k.frame) {
        // A grab applied late (after its frame) may start at or after a keyframe: go straight to it.
        const double s = k.frame > f0 ? static_cast<double>(f - f0) / static_cast<double>(k.frame - f0) : 1.0;
        q = f == k.frame ? k.position : Eigen::Vector3d((1.0 - s) * q0 + s * k.position);
        break;
      }
      f0 = k.frame;
      q0 = k.position;
    }
    sim.setPinTarget(h.pin, q);
  }
}

}  // namespace stabint
