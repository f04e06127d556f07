// The C API (include/stabint/stabint_c.h) over the C++ API. Every entry point that can fail runs
// its body through guarded(), which turns every exception into a status code and the thread's
// last-error message, so that no exception unwinds into C frames.
#include <stabint/stabint.hpp>
#include <stabint/stabint_c.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

struct stabint_scene {
  stabint::Scene scene;
};
struct stabint_simulator {
  stabint::Simulator sim;
};
struct stabint_checkpoint {
  stabint::Checkpoint checkpoint;
};

namespace {

struct LastError {
  stabint_status status = STABINT_OK;
  std::string message;
  int step = -1;
};
thread_local LastError last_error;

stabint_status fail(stabint_status status, const char* class_name, const std::string& text, int step = -1) {
  last_error.status = status;
  last_error.message = std::string(class_name) + ": " + text;
  last_error.step = step;
  return status;
}

// Raised by the C layer itself for API misuse (NULL handles, short buffers).
struct ArgumentError {
  std::string text;
};

// Most specific class first: each catch below must precede the catches of its bases.
template <class Body>
stabint_status guarded(Body&& body) noexcept {
  try {
    body();
    return STABINT_OK;
  } catch (const ArgumentError& e) {
    return fail(STABINT_INVALID_ARGUMENT, "InvalidArgument", e.text);
  } catch (const stabint::EnergyLimitError& e) {
    return fail(STABINT_ENERGY_LIMIT, "EnergyLimitError", e.what(), e.step());
  } catch (const stabint::NonFiniteStateError& e) {
    return fail(STABINT_NON_FINITE_STATE, "NonFiniteStateError", e.what(), e.step());
  } catch (const stabint::InvalidInputError& e) {
    return fail(STABINT_INVALID_INPUT, "InvalidInputError", e.what());
  } catch (const stabint::FileFormatError& e) {
    return fail(STABINT_FILE_FORMAT, "FileFormatError", e.what());
  } catch (const stabint::NoOpenCLDeviceError& e) {
    return fail(STABINT_NO_OPENCL_DEVICE, "NoOpenCLDeviceError", e.what());
  } catch (const stabint::KernelBuildError& e) {
    return fail(STABINT_KERNEL_BUILD, "KernelBuildError", e.what());
  } catch (const stabint::UnsupportedPrecisionError& e) {
    return fail(STABINT_UNSUPPORTED_PRECISION, "UnsupportedPrecisionError", e.what());
  } catch (const stabint::OpenCLError& e) {
    return fail(STABINT_OPENCL, "OpenCLError", e.what());
  } catch (const stabint::OutOfMemoryError& e) {
    return fail(STABINT_OUT_OF_MEMORY, "OutOfMemoryError", e.what());
  } catch (const stabint::Error& e) {
    return fail(STABINT_ERROR, "Error", e.what());
  } catch (const std::bad_alloc&) {
    return fail(STABINT_OUT_OF_MEMORY, "OutOfMemory", "allocation failed");
  } catch (const std::exception& e) {
    return fail(STABINT_INTERNAL, "InternalError", e.what());
  } catch (...) {
    return fail(STABINT_INTERNAL, "InternalError", "unknown exception");
  }
}

template <class T>
void require(const T* pointer, const char* what) {
  if (pointer == nullptr) throw ArgumentError{std::string(what) + " is NULL"};
}

void requireCapacity(size_t capacity, size_t needed, const char* what) {
  if (capacity < needed) {
    throw ArgumentError{std::string(what) + ": buffer holds " + std::to_string(capacity) + " values, " +
                        std::to_string(needed) + " needed"};
  }
}

// ---- options: the C struct <-> SimulatorOptions, generated from the field list -----------------
// (stabint/options_fields.hpp). The C header is plain C and lists the fields itself; the checks
// below fail the build when a C field is missing or has another type, or when a C enum's values
// drift from the C++ enum's.

// The C enum of each public C++ enum with its count (its values run from 0), and the check,
// generated from the enum's list (stabint/types.hpp), that every C enumerator equals its C++
// value: a value added to the list without its C enumerator, or a C value that drifts, fails the
// build here. With the values equal, a conversion either way is a cast.
template <class Enum>
struct CEnum;
#define STABINT_C_ENUM(cpp_enum, c_enum, LIST)              \
  template <>                                               \
  struct CEnum<stabint::cpp_enum> {                         \
    using Enum = stabint::cpp_enum;                         \
    using type = c_enum;                                    \
    static constexpr int count = 0 LIST(STABINT_ENUM_ONE_); \
    LIST(STABINT_C_SAME_VALUE)                              \
  };
#define STABINT_C_SAME_VALUE(enumerator, name, doc, c_enumerator)                     \
  static_assert(static_cast<int>(c_enumerator) == static_cast<int>(Enum::enumerator), \
                #c_enumerator " differs from the C++ value " #enumerator);
STABINT_C_ENUM(Integrator, stabint_integrator, STABINT_INTEGRATORS)
STABINT_C_ENUM(BackendKind, stabint_backend, STABINT_BACKENDS)
STABINT_C_ENUM(Precision, stabint_precision, STABINT_PRECISIONS)
STABINT_C_ENUM(Acceleration, stabint_acceleration, STABINT_ACCELERATIONS)
STABINT_C_ENUM(GlobalSolve, stabint_global_solve, STABINT_GLOBAL_SOLVES)
STABINT_C_ENUM(BlendBranch, stabint_blend_branch, STABINT_BLEND_BRANCHES)
#undef STABINT_C_ENUM
#undef STABINT_C_SAME_VALUE

// The C type of a field of C++ type T: the same for int and double, the C enum for an enum, a
// NUL-terminated string (NULL: empty) for a std::string.
template <class T, class = void>
struct CField {
  using type = T;
};
template <class T>
struct CField<T, std::enable_if_t<std::is_enum_v<T>>> {
  using type = typename CEnum<T>::type;
};
template <>
struct CField<std::string> {
  using type = const char*;
};
template <class T>
using CType = typename CField<T>::type;

// Every field of the list is in the C struct, with its C type. A nested struct's fields are
// spelled <member>_<field> in C (opencl_platform).
#define STABINT_C_CHECK_FIELD(type, name, doc)                                          \
  static_assert(std::is_same_v<decltype(stabint_simulator_options::name), CType<type>>, \
                "stabint_simulator_options::" #name " has the wrong type");
#define STABINT_C_CHECK_NESTED(type, name, fields, doc) fields(STABINT_C_CHECK_SUB, name)
#define STABINT_C_CHECK_SUB(parent, type, name, doc)                                               \
  static_assert(std::is_same_v<decltype(stabint_simulator_options::parent##_##name), CType<type>>, \
                "stabint_simulator_options::" #parent "_" #name " has the wrong type");
STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_C_CHECK_FIELD, STABINT_C_CHECK_NESTED)
#undef STABINT_C_CHECK_FIELD
#undef STABINT_C_CHECK_NESTED
#undef STABINT_C_CHECK_SUB

// Whether a C enum value (any int) is a value of the C++ enum.
template <class Enum>
bool isValue(typename CEnum<Enum>::type value) {
  return value >= 0 && value < CEnum<Enum>::count;
}
// The C++ name of a C enum value; NULL for any other int.
template <class Enum>
const char* nameOf(typename CEnum<Enum>::type value, const char* (*name)(Enum)) {
  return isValue<Enum>(value) ? name(static_cast<Enum>(value)) : nullptr;
}

// C -> C++, one field. C enums arrive as plain ints: the range is checked before the cast (the
// message names the C field).
void fromC(int value, int& out, const char*) { out = value; }
void fromC(double value, double& out, const char*) { out = value; }
void fromC(const char* value, std::string& out, const char*) { out = value ? value : ""; }
template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
void fromC(typename CEnum<Enum>::type value, Enum& out, const char* field) {
  if (!isValue<Enum>(value)) {
    throw stabint::InvalidInputError(std::string("options.") + field + ": invalid value " +
                                     std::to_string(static_cast<int>(value)));
  }
  out = static_cast<Enum>(value);
}

// C++ -> C, one field. A string points into `value` (NULL when empty), so the C struct is valid
// as long as the C++ options it came from.
void toC(int value, int& out) { out = value; }
void toC(double value, double& out) { out = value; }
void toC(const std::string& value, const char*& out) { out = value.empty() ? nullptr : value.c_str(); }
template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
void toC(Enum value, typename CEnum<Enum>::type& out) {
  out = static_cast<typename CEnum<Enum>::type>(value);
}

stabint::SimulatorOptions fromC(const stabint_simulator_options& c) {
  stabint::SimulatorOptions o;
#define STABINT_FROM_C_FIELD(type, name, doc) fromC(c.name, o.name, #name);
#define STABINT_FROM_C_NESTED(type, name, fields, doc) fields(STABINT_FROM_C_SUB, name)
#define STABINT_FROM_C_SUB(parent, type, name, doc) fromC(c.parent##_##name, o.parent.name, #parent "_" #name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_FROM_C_FIELD, STABINT_FROM_C_NESTED)
#undef STABINT_FROM_C_FIELD
#undef STABINT_FROM_C_NESTED
#undef STABINT_FROM_C_SUB
  return o;
}

stabint_simulator_options toC(const stabint::SimulatorOptions& o) {
  stabint_simulator_options c{};
#define STABINT_TO_C_FIELD(type, name, doc) toC(o.name, c.name);
#define STABINT_TO_C_NESTED(type, name, fields, doc) fields(STABINT_TO_C_SUB, name)
#define STABINT_TO_C_SUB(parent, type, name, doc) toC(o.parent.name, c.parent##_##name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_TO_C_FIELD, STABINT_TO_C_NESTED)
#undef STABINT_TO_C_FIELD
#undef STABINT_TO_C_NESTED
#undef STABINT_TO_C_SUB
  return c;
}

stabint_energy toC(const stabint::EnergyReport& e) { return {e.kinetic, e.elastic, e.external, e.total()}; }

stabint_step_report toC(const stabint::StepReport& r) {
  stabint_step_report c{};
  c.step = r.step;
  c.time = r.time;
  c.energy = toC(r.energy);
  c.target = r.target;
  c.forcing = r.forcing;
  c.damping = r.damping;
  toC(r.branch, c.branch);
  c.alpha = r.alpha;
  c.velocity_scale = r.velocity_scale;
  c.event_energy = r.event_energy;
  c.friction = r.friction;
  c.contact_projection = r.contact_projection;
  c.iterations = r.iterations;
  c.energy_evaluations = r.energy_evaluations;
  const stabint::PhaseTimes& t = r.times;
  c.times = {t.local, t.gather, t.transfer, t.global, t.energy, t.bookkeeping, t.total()};
  return c;
}

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

const char* stabint_status_name(stabint_status status) {
  switch (status) {
    case STABINT_OK: return "OK";
    case STABINT_ERROR: return "Error";
    case STABINT_INVALID_INPUT: return "InvalidInputError";
    case STABINT_FILE_FORMAT: return "FileFormatError";
    case STABINT_NON_FINITE_STATE: return "NonFiniteStateError";
    case STABINT_ENERGY_LIMIT: return "EnergyLimitError";
    case STABINT_OPENCL: return "OpenCLError";
    case STABINT_NO_OPENCL_DEVICE: return "NoOpenCLDeviceError";
    case STABINT_KERNEL_BUILD: return "KernelBuildError";
    case STABINT_UNSUPPORTED_PRECISION: return "UnsupportedPrecisionError";
    case STABINT_INVALID_ARGUMENT: return "InvalidArgument";
    case STABINT_OUT_OF_MEMORY: return "OutOfMemory";
    case STABINT_INTERNAL: return "InternalError";
    default: break;  // the sentinels and any other int
  }
  return "unknown";
}

int stabint_status_is(stabint_status status, stabint_status base) {
  if (status == base) return 1;
  if (status == STABINT_OK) return 0;
  switch (base) {
    case STABINT_ERROR: return 1;
    case STABINT_NON_FINITE_STATE: return status == STABINT_ENERGY_LIMIT;
    case STABINT_OPENCL:
      return status == STABINT_NO_OPENCL_DEVICE || status == STABINT_KERNEL_BUILD ||
             status == STABINT_UNSUPPORTED_PRECISION;
    default: return 0;
  }
}

const char* stabint_last_error_message(void) { return last_error.message.c_str(); }
stabint_status stabint_last_error_status(void) { return last_error.status; }
int stabint_last_error_step(void) { return last_error.step; }

const char* stabint_integrator_name(stabint_integrator integrator) {
  return nameOf<stabint::Integrator>(integrator, stabint::integratorName);
}

const char* stabint_blend_branch_name(stabint_blend_branch branch) {
  return nameOf<stabint::BlendBranch>(branch, stabint::blendBranchName);
}

stabint_status stabint_scene_create_builtin(const char* name, const char* params_json, stabint_scene** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(name, "name");
    require(out, "out");
    *out = new stabint_scene{stabint::builtinScene(name, params_json ? params_json : "{}")};
  });
}

stabint_status stabint_scene_load(const char* path, stabint_scene** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(path, "path");
    require(out, "out");
    *out = new stabint_scene{stabint::loadSceneFile(path)};
  });
}

void stabint_scene_destroy(stabint_scene* scene) { delete scene; }

int stabint_scene_num_particles(const stabint_scene* scene) { return scene ? scene->scene.numParticles() : -1; }

int stabint_scene_num_triangles(const stabint_scene* scene) {
  return scene ? static_cast<int>(scene->scene.triangles.size()) : -1;
}

stabint_status stabint_scene_copy_triangles(const stabint_scene* scene, int32_t* out, size_t capacity) {
  return guarded([&] {
    require(scene, "scene");
    const auto& triangles = scene->scene.triangles;
    requireCapacity(capacity, 3 * triangles.size(), "triangles");
    if (!triangles.empty()) require(out, "out");
    for (size_t t = 0; t < triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) out[3 * t + k] = triangles[t][k];
    }
  });
}

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

stabint_status stabint_checkpoint_save(const stabint_checkpoint* checkpoint, const char* path) {
  return guarded([&] {
    require(checkpoint, "checkpoint");
    require(path, "path");
    checkpoint->checkpoint.save(path);
  });
}

stabint_status stabint_checkpoint_load(const char* path, stabint_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(path, "path");
    require(out, "out");
    *out = new stabint_checkpoint{stabint::Checkpoint::load(path)};
  });
}

const void* stabint_checkpoint_data(const stabint_checkpoint* checkpoint, size_t* size) {
  if (size != nullptr) *size = checkpoint ? checkpoint->checkpoint.bytes().size() : 0;
  return checkpoint ? checkpoint->checkpoint.bytes().data() : nullptr;
}

stabint_status stabint_checkpoint_from_bytes(const void* data, size_t size, stabint_checkpoint** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    if (size > 0) require(data, "data");
    require(out, "out");
    std::string bytes;
    if (size > 0) bytes.assign(static_cast<const char*>(data), size);
    *out = new stabint_checkpoint{stabint::Checkpoint::fromBytes(std::move(bytes))};
  });
}

void stabint_checkpoint_destroy(stabint_checkpoint* checkpoint) { delete checkpoint; }

double stabint_checkpoint_time(const stabint_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.time() : kNaN;
}
int stabint_checkpoint_step_count(const stabint_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.stepCount() : -1;
}

}  // extern "C"
