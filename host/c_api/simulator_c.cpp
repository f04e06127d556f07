// The C API's simulator: creation, stepping, the state and reports, per-frame input, element
// changes and checkpoints (include/stabint/stabint_c.h over stabint::Simulator).
#include "c_api/c_api.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace stabint::c_api;

namespace {

// Rows of an n by 3 matrix, interleaved x y z, converted to T.
template <class T>
stabint_status copyRows(const stabint_simulator* sim, bool positions, T* out, size_t capacity) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    const Eigen::MatrixX3d& m = positions ? sim->sim.positions() : sim->sim.velocities();
    const size_t n = static_cast<size_t>(m.rows());
    requireCapacity(capacity, 3 * n, positions ? "positions" : "velocities");
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) out[3 * i + k] = static_cast<T>(m(static_cast<Eigen::Index>(i), k));
    }
  });
}

// An interleaved x y z array of `count` values as an n by 3 matrix, n = the simulator's particle
// count; a NULL array or a count other than 3 n is API misuse.
Eigen::MatrixX3d rowsFrom(const stabint_simulator* sim, const double* values, size_t count, const char* what) {
  require(values, what);
  const size_t n = static_cast<size_t>(sim->sim.positions().rows());
  if (count != 3 * n) {
    throw ArgumentError{std::string(what) + ": " + std::to_string(count) + " values, " + std::to_string(3 * n) +
                        " expected (3 per particle)"};
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  return Eigen::Map<const RowMajor>(values, static_cast<Eigen::Index>(n), 3);
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A C array of element indices (NULL allowed when count is 0) as the C++ API takes them.
std::vector<int> indexList(const int* indices, size_t count) {
  if (count > 0) require(indices, "indices");
  return count > 0 ? std::vector<int>(indices, indices + count) : std::vector<int>{};
}

}  // namespace

extern "C" {

void stabint_simulator_options_default(stabint_simulator_options* options) {
  if (options == nullptr) return;
  // The C++ defaults are the only source of truth; static, so that a non-empty default string
  // would stay valid (the OpenCL selectors default to empty: NULL).
  static const stabint::SimulatorOptions defaults;
  *options = toC(defaults);
}

stabint_status stabint_simulator_get_options(const stabint_simulator* sim, stabint_simulator_options* out) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    *out = toC(sim->sim.options());
  });
}

stabint_status stabint_simulator_create(const stabint_scene* scene, const stabint_simulator_options* options,
                                        stabint_simulator** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(scene, "scene");
    require(options, "options");
    require(out, "out");
    const stabint::SimulatorOptions o = fromC(*options);
    *out = new stabint_simulator{stabint::Simulator(scene->scene, o)};
  });
}

void stabint_simulator_destroy(stabint_simulator* sim) { delete sim; }

stabint_status stabint_simulator_step(stabint_simulator* sim, stabint_step_report* report) {
  return guarded([&] {
    require(sim, "simulator");
    const stabint::StepReport& r = sim->sim.step();
    if (report != nullptr) *report = toC(r);
  });
}

int stabint_simulator_num_particles(const stabint_simulator* sim) {
  return sim ? static_cast<int>(sim->sim.positions().rows()) : -1;
}

stabint_status stabint_simulator_copy_positions(const stabint_simulator* sim, double* out, size_t capacity) {
  return copyRows(sim, true, out, capacity);
}
stabint_status stabint_simulator_copy_positions_float(const stabint_simulator* sim, float* out, size_t capacity) {
  return copyRows(sim, true, out, capacity);
}
stabint_status stabint_simulator_copy_velocities(const stabint_simulator* sim, double* out, size_t capacity) {
  return copyRows(sim, false, out, capacity);
}
stabint_status stabint_simulator_copy_velocities_float(const stabint_simulator* sim, float* out, size_t capacity) {
  return copyRows(sim, false, out, capacity);
}

stabint_status stabint_simulator_energy(const stabint_simulator* sim, stabint_energy* out) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    *out = toC(sim->sim.energy());
  });
}

stabint_status stabint_simulator_last_report(const stabint_simulator* sim, stabint_step_report* out) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    *out = toC(sim->sim.lastReport());
  });
}

double stabint_simulator_time(const stabint_simulator* sim) { return sim ? sim->sim.time() : kNaN; }
int stabint_simulator_step_count(const stabint_simulator* sim) { return sim ? sim->sim.stepCount() : -1; }
double stabint_simulator_target(const stabint_simulator* sim) { return sim ? sim->sim.target() : kNaN; }
double stabint_simulator_energy_scale(const stabint_simulator* sim) { return sim ? sim->sim.energyScale() : kNaN; }

size_t stabint_simulator_backend_description(const stabint_simulator* sim, char* out, size_t capacity) {
  if (sim == nullptr) return 0;
  std::string text;
  try {
    text = sim->sim.backendDescription();
  } catch (...) {
    return 0;  // a description is informational: never let it throw into C
  }
  if (out != nullptr && capacity > 0) {
    const size_t n = std::min(text.size(), capacity - 1);
    std::memcpy(out, text.data(), n);
    out[n] = '\0';
  }
  return text.size();
}

stabint_status stabint_simulator_set_pin_target(stabint_simulator* sim, int pin, const double target[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(target, "target");
    sim->sim.setPinTarget(pin, Eigen::Vector3d(target[0], target[1], target[2]));
  });
}

stabint_status stabint_simulator_pin_target(const stabint_simulator* sim, int pin, double out[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    const Eigen::Vector3d q = sim->sim.pinTarget(pin);
    for (int k = 0; k < 3; ++k) out[k] = q[k];
  });
}

stabint_status stabint_simulator_set_collider_position(stabint_simulator* sim, int collider, const double position[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(position, "position");
    sim->sim.setColliderPosition(collider, Eigen::Vector3d(position[0], position[1], position[2]));
  });
}

stabint_status stabint_simulator_set_collider_velocity(stabint_simulator* sim, int collider, const double velocity[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(velocity, "velocity");
    sim->sim.setColliderVelocity(collider, Eigen::Vector3d(velocity[0], velocity[1], velocity[2]));
  });
}

stabint_status stabint_simulator_collider_position(const stabint_simulator* sim, int collider, double out[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    const Eigen::Vector3d p = sim->sim.colliderPosition(collider);
    for (int k = 0; k < 3; ++k) out[k] = p[k];
  });
}

stabint_status stabint_simulator_set_external_forces(stabint_simulator* sim, const double* forces, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setExternalForces(rowsFrom(sim, forces, count, "forces"));
  });
}

stabint_status stabint_simulator_set_state(stabint_simulator* sim, const double* positions, const double* velocities,
                                           size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    const Eigen::MatrixX3d x = rowsFrom(sim, positions, count, "positions");
    const Eigen::MatrixX3d v = rowsFrom(sim, velocities, count, "velocities");
    sim->sim.setState(x, v);
  });
}

stabint_status stabint_simulator_set_positions(stabint_simulator* sim, const double* positions, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setPositions(rowsFrom(sim, positions, count, "positions"));
  });
}

stabint_status stabint_simulator_set_velocities(stabint_simulator* sim, const double* velocities, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setVelocities(rowsFrom(sim, velocities, count, "velocities"));
  });
}

stabint_status stabint_simulator_set_iterations(stabint_simulator* sim, int iterations) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setIterations(iterations);
  });
}

stabint_status stabint_simulator_grab(stabint_simulator* sim, int vertex, double stiffness, int* out_pin) {
  return guarded([&] {
    require(sim, "simulator");
    require(out_pin, "out_pin");
    *out_pin = sim->sim.grab(vertex, stiffness);
  });
}

stabint_status stabint_simulator_release(stabint_simulator* sim, int pin) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.release(pin);
  });
}

stabint_status stabint_simulator_set_element_stiffness(stabint_simulator* sim, const char* kind, const int* indices,
                                                       size_t count, double stiffness) {
  return guarded([&] {
    require(sim, "simulator");
    require(kind, "kind");
    sim->sim.setElementStiffness(stabint::parseElementKind(kind), indexList(indices, count), stiffness);
  });
}

stabint_status stabint_simulator_set_element_enabled(stabint_simulator* sim, const char* kind, const int* indices,
                                                     size_t count, int enabled) {
  return guarded([&] {
    require(sim, "simulator");
    require(kind, "kind");
    sim->sim.setElementEnabled(stabint::parseElementKind(kind), indexList(indices, count), enabled != 0);
  });
}

stabint_status stabint_simulator_checkpoint(const stabint_simulator* sim, stabint_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(sim, "simulator");
    require(out, "out");
    *out = new stabint_checkpoint{sim->sim.checkpoint()};
  });
}

stabint_status stabint_simulator_restore(stabint_simulator* sim, const stabint_checkpoint* checkpoint) {
  return guarded([&] {
    require(sim, "simulator");
    require(checkpoint, "checkpoint");
    sim->sim.restore(checkpoint->checkpoint);
  });
}

}  // extern "C"
