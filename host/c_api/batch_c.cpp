// The C API's batch: creation, stepping with per-scene reports and refusals, each scene's state
// and reports, per-frame input, element changes and checkpoints (include/stabint/stabint_c.h over
// stabint::BatchSimulator). The argument checks and copies are c_api.hpp's, shared with the
// simulator's entry points (simulator_c.cpp); the scene index is checked by the C++ batch, which
// names the call and the scene.
#include "c_api/c_api.hpp"

#include <string>
#include <vector>

using namespace stabint::c_api;

namespace {

const stabint::BatchSimulator& batchOf(const stabint_batch* batch) {
  require(batch, "batch");
  return batch->batch;
}
stabint::BatchSimulator& batchOf(stabint_batch* batch) {
  require(batch, "batch");
  return batch->batch;
}

// The C++ batch's check of a scene index, for the calls whose C arguments need the scene's size
// before the C++ call checks it: the same message, naming the C++ call.
void checkScene(const stabint::BatchSimulator& batch, int scene, const char* call) {
  if (scene < 0 || scene >= batch.size()) {
    throw stabint::InvalidInputError(std::string(call) + ": scene " + std::to_string(scene) +
                                     " out of range (the batch has " + std::to_string(batch.size()) + " scenes)");
  }
}

// An interleaved array of scene `scene`'s particle count (see rowsFrom).
Eigen::MatrixX3d sceneRows(const stabint::BatchSimulator& batch, int scene, const char* call, const double* values,
                           size_t count, const char* what) {
  checkScene(batch, scene, call);
  return rowsFrom(batch.numParticles(scene), values, count, what);
}

// A plain value from `get` (a getter that may throw), or `fallback` with the last error set.
template <class T, class Get>
T valueOr(T fallback, Get&& get) {
  T value = fallback;
  guarded([&] { value = get(); });
  return value;
}

// Scene `scene`'s positions or velocities into `out` (see copyRows).
template <class T>
stabint_status copyState(const stabint_batch* batch, int scene, bool positions, T* out, size_t capacity) {
  return guarded([&] {
    const stabint::BatchSimulator& b = batchOf(batch);
    copyRows(positions ? b.positions(scene) : b.velocities(scene), out, capacity,
             positions ? "positions" : "velocities");
  });
}

template <class T>
stabint_status copyAll(const stabint_batch* batch, T* out, size_t capacity) {
  return guarded([&] { copyRows(batchOf(batch).allPositions(), out, capacity, "all positions"); });
}

// The vector `get` returns (a getter of a pin's or collider's position) into `out`.
template <class Get>
stabint_status copyVectorOut(Get&& get, double* out) {
  return guarded([&] {
    const Eigen::Vector3d v = get();
    require(out, "out");
    copyVector3(v, out);
  });
}

// The scenes of a create call, copied; `count` >= 1 and no NULL among them.
std::vector<stabint::Scene> sceneList(const stabint_scene* const* scenes, int count) {
  if (count < 1) throw ArgumentError{"count: " + std::to_string(count) + " scenes, at least 1 needed"};
  require(scenes, "scenes");
  std::vector<stabint::Scene> list;
  list.reserve(static_cast<size_t>(count));
  for (int s = 0; s < count; ++s) {
    if (scenes[s] == nullptr) throw ArgumentError{"scenes[" + std::to_string(s) + "] is NULL"};
    list.push_back(scenes[s]->scene);
  }
  return list;
}

}  // namespace

extern "C" {

stabint_status stabint_batch_create(const stabint_scene* const* scenes, int count,
                                    const stabint_simulator_options* options, stabint_batch** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(options, "options");
    require(out, "out");
    const std::vector<stabint::Scene> list = sceneList(scenes, count);
    *out = new stabint_batch{stabint::BatchSimulator(list, fromC(*options)), {}};
  });
}

void stabint_batch_destroy(stabint_batch* batch) { delete batch; }

stabint_status stabint_batch_get_options(const stabint_batch* batch, stabint_simulator_options* out) {
  return guarded([&] {
    const stabint::BatchSimulator& b = batchOf(batch);
    require(out, "out");
    *out = toC(b.options());
  });
}

stabint_status stabint_batch_step(stabint_batch* batch, stabint_step_report* reports, size_t capacity) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    const size_t n = static_cast<size_t>(b.size());
    if (reports != nullptr || capacity > 0) {
      require(reports, "reports");
      requireCapacity(capacity, n, "reports");
    }
    batch->last = nullptr;
    batch->last = &b.step();
    if (reports != nullptr) {
      for (size_t s = 0; s < n; ++s) reports[s] = toC(batch->last->scenes[s]);
    }
  });
}

stabint_status stabint_batch_last_report(const stabint_batch* batch, int scene, stabint_step_report* out) {
  return guarded([&] {
    checkScene(batchOf(batch), scene, "lastReport");
    require(out, "out");
    *out = toC(batch->last ? batch->last->scenes[static_cast<size_t>(scene)] : stabint::StepReport{});
  });
}

stabint_status stabint_batch_refusal(const stabint_batch* batch, int scene, char* out, size_t capacity,
                                     size_t* length) {
  return guarded([&] {
    checkScene(batchOf(batch), scene, "refusal");
    if (capacity > 0) require(out, "out");
    const size_t full = copyText(batch->last ? batch->last->refusals[static_cast<size_t>(scene)] : "", out, capacity);
    if (length != nullptr) *length = full;
  });
}

int stabint_batch_size(const stabint_batch* batch) {
  return valueOr(-1, [&] { return batchOf(batch).size(); });
}
int stabint_batch_active(const stabint_batch* batch, int scene) {
  return valueOr(-1, [&] { return batchOf(batch).active(scene) ? 1 : 0; });
}
int stabint_batch_num_particles(const stabint_batch* batch, int scene) {
  return valueOr(-1, [&] { return batchOf(batch).numParticles(scene); });
}
int stabint_batch_first_particle(const stabint_batch* batch, int scene) {
  return valueOr(-1, [&] { return batchOf(batch).firstParticle(scene); });
}
double stabint_batch_time(const stabint_batch* batch) {
  return valueOr(kNaN, [&] { return batchOf(batch).time(); });
}
double stabint_batch_scene_time(const stabint_batch* batch, int scene) {
  return valueOr(kNaN, [&] { return batchOf(batch).time(scene); });
}
int stabint_batch_step_count(const stabint_batch* batch, int scene) {
  return valueOr(-1, [&] { return batchOf(batch).stepCount(scene); });
}
double stabint_batch_target(const stabint_batch* batch, int scene) {
  return valueOr(kNaN, [&] { return batchOf(batch).target(scene); });
}
double stabint_batch_energy_scale(const stabint_batch* batch, int scene) {
  return valueOr(kNaN, [&] { return batchOf(batch).energyScale(scene); });
}

stabint_status stabint_batch_energy(const stabint_batch* batch, int scene, stabint_energy* out) {
  return guarded([&] {
    const stabint::EnergyReport e = batchOf(batch).energy(scene);
    require(out, "out");
    *out = toC(e);
  });
}

size_t stabint_batch_backend_description(const stabint_batch* batch, char* out, size_t capacity) {
  if (batch == nullptr) return 0;
  return copyDescription([&] { return batch->batch.backendDescription(); }, out, capacity);
}

stabint_status stabint_batch_copy_positions(const stabint_batch* batch, int scene, double* out, size_t capacity) {
  return copyState(batch, scene, true, out, capacity);
}
stabint_status stabint_batch_copy_positions_float(const stabint_batch* batch, int scene, float* out, size_t capacity) {
  return copyState(batch, scene, true, out, capacity);
}
stabint_status stabint_batch_copy_velocities(const stabint_batch* batch, int scene, double* out, size_t capacity) {
  return copyState(batch, scene, false, out, capacity);
}
stabint_status stabint_batch_copy_velocities_float(const stabint_batch* batch, int scene, float* out, size_t capacity) {
  return copyState(batch, scene, false, out, capacity);
}
stabint_status stabint_batch_copy_all_positions(const stabint_batch* batch, double* out, size_t capacity) {
  return copyAll(batch, out, capacity);
}
stabint_status stabint_batch_copy_all_positions_float(const stabint_batch* batch, float* out, size_t capacity) {
  return copyAll(batch, out, capacity);
}

stabint_status stabint_batch_set_iterations(stabint_batch* batch, int iterations) {
  return guarded([&] { batchOf(batch).setIterations(iterations); });
}

stabint_status stabint_batch_set_state(stabint_batch* batch, int scene, const double* positions,
                                       const double* velocities, size_t count) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    const Eigen::MatrixX3d x = sceneRows(b, scene, "setState", positions, count, "positions");
    const Eigen::MatrixX3d v = sceneRows(b, scene, "setState", velocities, count, "velocities");
    b.setState(scene, x, v);
  });
}

stabint_status stabint_batch_set_states(stabint_batch* batch, const int* scenes, size_t scene_count,
                                        const double* positions, const double* velocities, size_t count) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    if (scene_count > 0) require(scenes, "scenes");
    const std::vector<int> list(scenes, scenes + scene_count);
    size_t needed = 0;
    for (int scene : list) {
      checkScene(b, scene, "setStates");
      needed += 3 * size_t(b.numParticles(scene));
    }
    if (count != needed)
      throw ArgumentError{"count is " + std::to_string(count) + ", the listed scenes take " + std::to_string(needed) +
                          " values in each of positions and velocities"};
    std::vector<Eigen::MatrixX3d> x, v;
    size_t offset = 0;
    for (int scene : list) {
      const size_t values = 3 * size_t(b.numParticles(scene));
      x.push_back(sceneRows(b, scene, "setStates", positions ? positions + offset : nullptr, values, "positions"));
      v.push_back(sceneRows(b, scene, "setStates", velocities ? velocities + offset : nullptr, values, "velocities"));
      offset += values;
    }
    b.setStates(list, x, v);
  });
}

stabint_status stabint_batch_set_pin_target(stabint_batch* batch, int scene, int pin, const double target[3]) {
  return guarded([&] { batchOf(batch).setPinTarget(scene, pin, vector3(target, "target")); });
}

stabint_status stabint_batch_pin_target(const stabint_batch* batch, int scene, int pin, double out[3]) {
  return copyVectorOut([&] { return batchOf(batch).pinTarget(scene, pin); }, out);
}

stabint_status stabint_batch_set_external_forces(stabint_batch* batch, int scene, const double* forces, size_t count) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    b.setExternalForces(scene, sceneRows(b, scene, "setExternalForces", forces, count, "forces"));
  });
}

stabint_status stabint_batch_set_collider_position(stabint_batch* batch, int scene, int collider,
                                                   const double position[3]) {
  return guarded([&] { batchOf(batch).setColliderPosition(scene, collider, vector3(position, "position")); });
}

stabint_status stabint_batch_set_collider_velocity(stabint_batch* batch, int scene, int collider,
                                                   const double velocity[3]) {
  return guarded([&] { batchOf(batch).setColliderVelocity(scene, collider, vector3(velocity, "velocity")); });
}

stabint_status stabint_batch_collider_position(const stabint_batch* batch, int scene, int collider, double out[3]) {
  return copyVectorOut([&] { return batchOf(batch).colliderPosition(scene, collider); }, out);
}

stabint_status stabint_batch_grab(stabint_batch* batch, int scene, int vertex, double stiffness, int* out_pin) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    require(out_pin, "out_pin");
    *out_pin = b.grab(scene, vertex, stiffness);
  });
}

stabint_status stabint_batch_release(stabint_batch* batch, int scene, int pin) {
  return guarded([&] { batchOf(batch).release(scene, pin); });
}

stabint_status stabint_batch_set_element_stiffness(stabint_batch* batch, int scene, const char* kind,
                                                   const int* indices, size_t count, double stiffness) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    require(kind, "kind");
    b.setElementStiffness(scene, stabint::parseElementKind(kind), indexList(indices, count), stiffness);
  });
}

stabint_status stabint_batch_set_element_enabled(stabint_batch* batch, int scene, const char* kind, const int* indices,
                                                 size_t count, int enabled) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    require(kind, "kind");
    b.setElementEnabled(scene, stabint::parseElementKind(kind), indexList(indices, count), enabled != 0);
  });
}

stabint_status stabint_batch_scene_checkpoint(const stabint_batch* batch, int scene, stabint_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    const stabint::BatchSimulator& b = batchOf(batch);
    require(out, "out");
    *out = new stabint_checkpoint{b.checkpoint(scene)};
  });
}

stabint_status stabint_batch_scene_restore(stabint_batch* batch, int scene, const stabint_checkpoint* checkpoint) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    require(checkpoint, "checkpoint");
    b.restore(scene, checkpoint->checkpoint);
  });
}

stabint_status stabint_batch_checkpoint_create(const stabint_batch* batch, stabint_batch_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    const stabint::BatchSimulator& b = batchOf(batch);
    require(out, "out");
    *out = new stabint_batch_checkpoint{b.checkpoint()};
  });
}

stabint_status stabint_batch_restore(stabint_batch* batch, const stabint_batch_checkpoint* checkpoint) {
  return guarded([&] {
    stabint::BatchSimulator& b = batchOf(batch);
    require(checkpoint, "checkpoint");
    b.restore(checkpoint->checkpoint);
  });
}

stabint_status stabint_batch_checkpoint_scene(const stabint_batch_checkpoint* checkpoint, int scene,
                                              stabint_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(checkpoint, "checkpoint");
    require(out, "out");
    *out = new stabint_checkpoint{checkpoint->checkpoint.scene(scene)};
  });
}

stabint_status stabint_batch_checkpoint_save(const stabint_batch_checkpoint* checkpoint, const char* path) {
  return saveCheckpoint(checkpoint, path);
}

stabint_status stabint_batch_checkpoint_load(const char* path, stabint_batch_checkpoint** out) {
  return loadCheckpoint(path, out);
}

const void* stabint_batch_checkpoint_data(const stabint_batch_checkpoint* checkpoint, size_t* size) {
  return checkpointData(checkpoint, size);
}

stabint_status stabint_batch_checkpoint_from_bytes(const void* data, size_t size, stabint_batch_checkpoint** out) {
  return checkpointFromBytes(data, size, out);
}

void stabint_batch_checkpoint_destroy(stabint_batch_checkpoint* checkpoint) { delete checkpoint; }

double stabint_batch_checkpoint_time(const stabint_batch_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.time() : kNaN;
}
int stabint_batch_checkpoint_size(const stabint_batch_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.size() : -1;
}

}  // extern "C"
