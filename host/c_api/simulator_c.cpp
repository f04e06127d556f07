// The C API's simulator: creation, stepping, the state and reports, per-frame input, element
// changes and checkpoints (include/stabint/stabint_c.h over stabint::Simulator).
#include "c_api/c_api.hpp"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

using namespace stabint::c_api;

namespace {

// Positions or velocities into `out` (see copyRows).
template <class T>
stabint_status copyState(const stabint_simulator* sim, bool positions, T* out, size_t capacity) {
  return guarded([&] {
    require(sim, "simulator");
    copyRows(positions ? sim->sim.positions() : sim->sim.velocities(), out, capacity,
             positions ? "positions" : "velocities");
  });
}

// An interleaved array of the simulator's particle count (see rowsFrom).
Eigen::MatrixX3d rowsOf(const stabint_simulator* sim, const double* values, size_t count, const char* what) {
  return rowsFrom(sim->sim.positions().rows(), values, count, what);
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

stabint_status stabint_simulator_add_reporter(stabint_simulator* sim, stabint_reporter_fn fn, void* user_data,
                                              int every, int* id) {
  return guarded([&] {
    require(sim, "simulator");
    if (fn == nullptr) throw ArgumentError{"fn is NULL"};
    const int own = sim->next_reporter;
    const std::string name = "C reporter " + std::to_string(own);
    auto reporter = std::make_shared<stabint::CallbackReporter>(
        [sim, fn, user_data, name](const stabint::Simulator&, const stabint::StepReport& report) {
          const stabint_step_report c = toC(report);
          const int result = fn(sim, &c, user_data);
          if (result != 0) throw std::runtime_error(name + " returned " + std::to_string(result));
        },
        every, name);
    sim->sim.addReporter(reporter);
    sim->reporters.emplace_back(own, std::move(reporter));
    ++sim->next_reporter;
    if (id != nullptr) *id = own;
  });
}

stabint_status stabint_simulator_add_csv_reporter(stabint_simulator* sim, const char* path, int every, int initial_row,
                                                  int* id) {
  return guarded([&] {
    require(sim, "simulator");
    require(path, "path");
    auto reporter = std::make_shared<stabint::CsvReporter>(path, every);
    if (initial_row != 0) reporter->initialRow(sim->sim);
    sim->sim.addReporter(reporter);
    sim->reporters.emplace_back(sim->next_reporter, std::move(reporter));
    if (id != nullptr) *id = sim->next_reporter;
    ++sim->next_reporter;
  });
}

stabint_status stabint_simulator_remove_reporter(stabint_simulator* sim, int id) {
  return guarded([&] {
    require(sim, "simulator");
    const auto found = std::find_if(sim->reporters.begin(), sim->reporters.end(),
                                    [id](const auto& entry) { return entry.first == id; });
    if (found == sim->reporters.end()) throw ArgumentError{"no reporter of id " + std::to_string(id) + " is attached"};
    sim->sim.removeReporter(found->second);
    sim->reporters.erase(found);
  });
}

int stabint_simulator_num_particles(const stabint_simulator* sim) {
  return sim ? static_cast<int>(sim->sim.positions().rows()) : -1;
}

stabint_status stabint_simulator_copy_positions(const stabint_simulator* sim, double* out, size_t capacity) {
  return copyState(sim, true, out, capacity);
}
stabint_status stabint_simulator_copy_positions_float(const stabint_simulator* sim, float* out, size_t capacity) {
  return copyState(sim, true, out, capacity);
}
stabint_status stabint_simulator_copy_velocities(const stabint_simulator* sim, double* out, size_t capacity) {
  return copyState(sim, false, out, capacity);
}
stabint_status stabint_simulator_copy_velocities_float(const stabint_simulator* sim, float* out, size_t capacity) {
  return copyState(sim, false, out, capacity);
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
  return copyDescription([&] { return sim->sim.backendDescription(); }, out, capacity);
}

stabint_status stabint_simulator_set_pin_target(stabint_simulator* sim, int pin, const double target[3]) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setPinTarget(pin, vector3(target, "target"));
  });
}

stabint_status stabint_simulator_pin_target(const stabint_simulator* sim, int pin, double out[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    copyVector3(sim->sim.pinTarget(pin), out);
  });
}

stabint_status stabint_simulator_set_collider_position(stabint_simulator* sim, int collider, const double position[3]) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setColliderPosition(collider, vector3(position, "position"));
  });
}

stabint_status stabint_simulator_set_collider_velocity(stabint_simulator* sim, int collider, const double velocity[3]) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setColliderVelocity(collider, vector3(velocity, "velocity"));
  });
}

stabint_status stabint_simulator_collider_position(const stabint_simulator* sim, int collider, double out[3]) {
  return guarded([&] {
    require(sim, "simulator");
    require(out, "out");
    copyVector3(sim->sim.colliderPosition(collider), out);
  });
}

stabint_status stabint_simulator_set_external_forces(stabint_simulator* sim, const double* forces, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setExternalForces(rowsOf(sim, forces, count, "forces"));
  });
}

stabint_status stabint_simulator_set_state(stabint_simulator* sim, const double* positions, const double* velocities,
                                           size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    const Eigen::MatrixX3d x = rowsOf(sim, positions, count, "positions");
    const Eigen::MatrixX3d v = rowsOf(sim, velocities, count, "velocities");
    sim->sim.setState(x, v);
  });
}

stabint_status stabint_simulator_set_positions(stabint_simulator* sim, const double* positions, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setPositions(rowsOf(sim, positions, count, "positions"));
  });
}

stabint_status stabint_simulator_set_velocities(stabint_simulator* sim, const double* velocities, size_t count) {
  return guarded([&] {
    require(sim, "simulator");
    sim->sim.setVelocities(rowsOf(sim, velocities, count, "velocities"));
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
