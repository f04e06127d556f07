/** @file
 * The C API of stabint: opaque handles, status codes and a thread-local last-error message.
 *
 * Every function that can fail returns a stabint_status. STABINT_OK is 0; any other value names
 * the C++ exception class that the call raised inside the library (no exception crosses this
 * boundary), and stabint_last_error_message() returns "<ClassName>: <text>" for the last failed
 * call on the calling thread. A successful call leaves the last error as it was.
 *
 * Getters that return a plain value (counts, time, H*) return -1 (counts) or NaN for a NULL
 * handle instead of a status.
 *
 * Threads: the last error is per thread; one handle must not be used by two threads at once.
 *
 * Ownership: a handle returned through an out-parameter belongs to the caller and is released
 * with the matching *_destroy function (which accepts NULL); a create that fails sets it to NULL
 * (nothing to destroy). A simulator or batch copies its scenes, so a
 * scene may be destroyed as soon as the simulators and batches built from it exist.
 *
 * Per-frame input (pin targets, external forces, state replacement, iteration budget) and
 * checkpoints are the C++ Simulator's (stabint/simulator.hpp, docs/method.md "Per-frame input"):
 * a call that returns anything but STABINT_OK changed nothing. */
#ifndef STABINT_STABINT_C_H
#define STABINT_STABINT_C_H

#include <stddef.h>
#include <stdint.h>

#include <stabint/options_table.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Every enum below ends with two sentinels that are not values: they make the enum as wide as
 * int, so that any int an application stores in it (a bad value from a config file or a binding)
 * is well-defined in C and C++ and is rejected with STABINT_INVALID_INPUT (Vulkan's *_MAX_ENUM
 * idiom). */
#define STABINT_ENUM_INT_WIDE_(prefix) prefix##_MIN_ENUM_ = -0x7FFFFFFF - 1, prefix##_MAX_ENUM_ = 0x7FFFFFFF

/** Status codes, one per class of stabint/errors.hpp, plus the failures of the C layer itself.
 * The C++ hierarchy is kept by stabint_status_is(): ENERGY_LIMIT is a NON_FINITE_STATE, the
 * three OpenCL subtypes are OPENCL, and every code except OK is ERROR. */
typedef enum stabint_status {
  STABINT_OK = 0,
  STABINT_ERROR = 1,                 /**< stabint::Error of no more specific class */
  STABINT_INVALID_INPUT = 2,         /**< InvalidInputError: scene or option failed validation */
  STABINT_FILE_FORMAT = 3,           /**< FileFormatError: file missing or malformed */
  STABINT_NON_FINITE_STATE = 4,      /**< NonFiniteStateError: step refused, last state kept */
  STABINT_ENERGY_LIMIT = 5,          /**< EnergyLimitError: step over options.energy_limit */
  STABINT_OPENCL = 6,                /**< OpenCLError */
  STABINT_NO_OPENCL_DEVICE = 7,      /**< NoOpenCLDeviceError: fall back to STABINT_BACKEND_CPU */
  STABINT_KERNEL_BUILD = 8,          /**< KernelBuildError (message carries the build log) */
  STABINT_UNSUPPORTED_PRECISION = 9, /**< UnsupportedPrecisionError */
  STABINT_INVALID_ARGUMENT = 10,     /**< misuse of the C API: NULL handle, buffer too small */
  STABINT_OUT_OF_MEMORY = 11,        /**< std::bad_alloc */
  STABINT_INTERNAL = 12,             /**< any other exception: a bug in stabint */
  STABINT_ENUM_INT_WIDE_(STABINT_STATUS)
} stabint_status;

/** "OK", "Error", "InvalidInputError", ... (the C++ class name); "unknown" for other values. */
const char* stabint_status_name(stabint_status status);
/** 1 when `status` is `base` or one of its subtypes (see stabint_status), else 0. */
int stabint_status_is(stabint_status status, stabint_status base);
/** Message of the last failed call on this thread, "" when none failed yet. Valid until the next
 * failing call on this thread. */
const char* stabint_last_error_message(void);
/** Status of the last failed call on this thread (STABINT_OK when none). */
stabint_status stabint_last_error_status(void);
/** For a last error of NON_FINITE_STATE or ENERGY_LIMIT, the index of the refused step; else -1. */
int stabint_last_error_step(void);

/* ---- enumerations: values equal the C++ enums'. Each C++ enum is generated from its list in
 * stabint/types.hpp (STABINT_INTEGRATORS, ...), whose entries name their C enumerator here; the
 * library's build checks every one against its C++ value. ---- */
/** stabint::Integrator. */
typedef enum stabint_integrator {
  STABINT_FORWARD_EULER = 0,
  STABINT_SYMPLECTIC_EULER = 1,
  STABINT_BACKWARD_EULER = 2,
  STABINT_BDF2 = 3,
  STABINT_IMPLICIT_MIDPOINT = 4,
  STABINT_ENERGY_BLEND = 5,
  STABINT_ENUM_INT_WIDE_(STABINT_INTEGRATOR)
} stabint_integrator;
/** stabint::BackendKind. */
typedef enum stabint_backend {
  STABINT_BACKEND_CPU = 0,
  STABINT_BACKEND_OPENCL = 1,
  STABINT_BACKEND_AUTO = 2, /**< a GPU for a scene large enough for it, else the CPU (BackendKind::Auto) */
  STABINT_ENUM_INT_WIDE_(STABINT_BACKEND)
} stabint_backend;
/** stabint::Precision, of the OpenCL backend. */
typedef enum stabint_precision {
  STABINT_PRECISION_DOUBLE = 0,
  STABINT_PRECISION_FLOAT = 1,
  STABINT_ENUM_INT_WIDE_(STABINT_PRECISION)
} stabint_precision;
/** stabint::Acceleration. */
typedef enum stabint_acceleration {
  STABINT_ACCELERATION_NONE = 0,
  STABINT_ACCELERATION_CHEBYSHEV = 1,
  STABINT_ACCELERATION_ANDERSON = 2,
  STABINT_ACCELERATION_LBFGS = 3,
  STABINT_ACCELERATION_NEWTON = 4,
  STABINT_ENUM_INT_WIDE_(STABINT_ACCELERATION)
} stabint_acceleration;
/** stabint::GlobalSolve. */
typedef enum stabint_global_solve {
  STABINT_GLOBAL_SOLVE_FACTOR = 0,
  STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT = 1,
  STABINT_ENUM_INT_WIDE_(STABINT_GLOBAL_SOLVE)
} stabint_global_solve;
/** stabint::BlendBranch: what the blend did in a step. */
typedef enum stabint_blend_branch {
  STABINT_BRANCH_NONE = 0,
  STABINT_BRANCH_IMPLICIT_MIDPOINT = 1,
  STABINT_BRANCH_BACKWARD_EULER = 2,
  STABINT_BRANCH_VELOCITY_SCALE = 3,
  STABINT_ENUM_INT_WIDE_(STABINT_BRANCH)
} stabint_blend_branch;

/** The C++ names (stabint::integratorName, blendBranchName: "FE", "blend", ...; "-", "IM", ...);
 * NULL for any other int. */
/** @{ */
const char* stabint_integrator_name(stabint_integrator integrator);
const char* stabint_blend_branch_name(stabint_blend_branch branch);
/** @} */

/* ---- scenes ---- */
/** An opaque scene (a stabint::Scene), from stabint_scene_create_builtin or stabint_scene_load. */
typedef struct stabint_scene stabint_scene;

/** A built-in scene ("oscillator", "chain", "cloth", "tetbar") with its builder's parameters as
 * the text of a JSON object (NULL or "{}" for the defaults), e.g. "{\"nx\": 30}" for a 30 x 30
 * cloth; the keys are the fields of the builder's parameter struct (stabint/builders.hpp).
 * Unknown names or parameters: STABINT_FILE_FORMAT naming the key. */
stabint_status stabint_scene_create_builtin(const char* name, const char* params_json, stabint_scene** out);
/** A JSON scene file (docs/scene-format.md), which may itself load OBJ, TetGen or Medit meshes. */
stabint_status stabint_scene_load(const char* path, stabint_scene** out);
/** Releases a scene (NULL is ignored). */
void stabint_scene_destroy(stabint_scene* scene);
/** Number of particles and of surface triangles (0 for scenes without a surface, e.g. the chain). */
/** @{ */
int stabint_scene_num_particles(const stabint_scene* scene);
int stabint_scene_num_triangles(const stabint_scene* scene);
/** @} */
/** Copies the surface triangles, 3 particle indices each, into `out` (capacity in int32 entries,
 * at least 3 * stabint_scene_num_triangles). */
stabint_status stabint_scene_copy_triangles(const stabint_scene* scene, int32_t* out, size_t capacity);

/* ---- simulators ---- */
/** An opaque simulator (a stabint::Simulator), from stabint_simulator_create. */
typedef struct stabint_simulator stabint_simulator;

/** @cond */
#define STABINT_C_OPTION_(type, name, default_value, rule, doc) type name;
#define STABINT_C_OPTION_NESTED_(type, name, fields, doc) fields(STABINT_C_OPTION_SUB_, name)
#define STABINT_C_OPTION_SUB_(parent, type, name, default_value, rule, doc) type parent##_##name;
/** @endcond */
/** The fields of stabint::SimulatorOptions, generated from their rows
 * (STABINT_SIMULATOR_OPTIONS_TABLE in stabint/options_table.h, which documents each): the same
 * names, in the same order, with C types (int, double, the C enums above, and `const char*` for a
 * string: NULL or "" is empty); a nested struct's fields are spelled opencl_platform and so on.
 * Fill with stabint_simulator_options_default() first, then change what you need. */
typedef struct stabint_simulator_options {
  STABINT_SIMULATOR_OPTIONS_TABLE(STABINT_C_OPTION_, STABINT_C_OPTION_NESTED_, STABINT_OPTION_C_TYPE_)
} stabint_simulator_options;

/** The C++ defaults (blend, h = 1/30, 10 iterations, CPU reference backend, ...). */
void stabint_simulator_options_default(stabint_simulator_options* options);
/** The options a simulator was built with (its iteration budget as last set). The two OpenCL
 * selectors point into the simulator (valid until it is destroyed), NULL when empty. */
stabint_status stabint_simulator_get_options(const stabint_simulator* sim, stabint_simulator_options* out);

/** Energies of a state, as stabint::EnergyReport (J). */
typedef struct stabint_energy {
  double kinetic;  /**< K(v) */
  double elastic;  /**< springs, tets, triangles, hinges, pins */
  double external; /**< gravity and force fields */
  double total;    /**< kinetic + elastic + external */
} stabint_energy;

/** Wall-clock seconds per phase, as stabint::PhaseTimes (`total` is their sum). */
typedef struct stabint_phase_times {
  /** @{ */
  /** Seconds in one phase (stabint::PhaseTimes), or in all of them (`total`). */
  double local, gather, transfer, global, energy, bookkeeping, total;
  /** @} */
} stabint_phase_times;

/** The fields of stabint::StepReport. */
typedef struct stabint_step_report {
  int step;                    /**< index of this step (0 = first) */
  double time;                 /**< time at the end of the step */
  stabint_energy energy;       /**< of the state after the step */
  double target;               /**< H* after the step */
  double forcing;              /**< energy added to H* by time-dependent potentials */
  double damping;              /**< kinetic energy removed by damping (>= 0) */
  stabint_blend_branch branch; /**< what the blend did */
  double alpha;                /**< blend weight of the BE partner */
  double velocity_scale;       /**< factor the blend applied to the velocities */
  double event_energy;         /**< jump of H booked in H* by set_state/positions/velocities before it */
  /** Colliders (scene files' "colliders"): kinetic energy friction removed (taken from H*;
   * negative when a moving collider drags particles along), and the energy the contact booked
   * as lost (<= 0, added to H*): the final projection's removal beyond what the colliders'
   * restitution keeps, and the step's half-spaces' (docs/method.md, "Contact"). */
  /** @{ */
  double friction;
  double contact_projection;
  /** @} */
  int iterations;            /**< local/global iterations of all solves in the step */
  int energy_evaluations;    /**< element energy passes */
  stabint_phase_times times; /**< wall-clock seconds per phase */
} stabint_step_report;

/** Validates and copies the scene. INVALID_INPUT for a bad scene or option (the message names
 * the field), OPENCL subtypes for the OpenCL backend (NO_OPENCL_DEVICE when none matches). */
stabint_status stabint_simulator_create(const stabint_scene* scene, const stabint_simulator_options* options,
                                        stabint_simulator** out);
/** Releases a simulator (NULL is ignored). */
void stabint_simulator_destroy(stabint_simulator* sim);

/** Advances one step; fills `report` (may be NULL). A refused step returns NON_FINITE_STATE or
 * ENERGY_LIMIT, keeps the last accepted state, and stabint_last_error_step() tells which. */
stabint_status stabint_simulator_step(stabint_simulator* sim, stabint_step_report* report);

/** A reporter function (stabint_simulator_add_reporter), in the spirit of OpenMM's reporters:
 * called after every `every`-th accepted step with the simulator in the state after the step and
 * that step's report, and `user_data` as given. A nonzero return fails the report, not the step:
 * stabint_simulator_step returns STABINT_ERROR with a message naming the reporter and the step,
 * and the step stays accepted (a C++ reporter that throws: ReporterError). */
typedef int (*stabint_reporter_fn)(const stabint_simulator* sim, const stabint_step_report* report, void* user_data);
/** Attaches `fn` after the reporters already attached, called after the steps whose count is a
 * multiple of `every` (>= 1, else INVALID_INPUT); `*id` (may be NULL) receives the id that
 * stabint_simulator_remove_reporter takes. INVALID_ARGUMENT for a NULL simulator or function. */
stabint_status stabint_simulator_add_reporter(stabint_simulator* sim, stabint_reporter_fn fn, void* user_data,
                                              int every, int* id);
/** Attaches a CSV reporter (stabint::CsvReporter): creates or truncates `path`, writes its header
 * and, with `initial_row` nonzero, the current state as frame 0, then one row every `every`-th
 * step. FILE_FORMAT when the file cannot be written (nothing is attached). */
stabint_status stabint_simulator_add_csv_reporter(stabint_simulator* sim, const char* path, int every, int initial_row,
                                                  int* id);
/** Detaches the reporter `id`; INVALID_ARGUMENT when none of that id is attached. */
stabint_status stabint_simulator_remove_reporter(stabint_simulator* sim, int id);

/** Number of particles; -1 for NULL. */
int stabint_simulator_num_particles(const stabint_simulator* sim);
/** Current state copied interleaved, x y z per particle (ready for a vertex buffer), into `out`
 * with room for `capacity` values (at least 3 * stabint_simulator_num_particles). */
/** @{ */
stabint_status stabint_simulator_copy_positions(const stabint_simulator* sim, double* out, size_t capacity);
stabint_status stabint_simulator_copy_positions_float(const stabint_simulator* sim, float* out, size_t capacity);
stabint_status stabint_simulator_copy_velocities(const stabint_simulator* sim, double* out, size_t capacity);
stabint_status stabint_simulator_copy_velocities_float(const stabint_simulator* sim, float* out, size_t capacity);
/** @} */

/** Energies of the current state; the report of the last completed step (zeros before the first). */
/** @{ */
stabint_status stabint_simulator_energy(const stabint_simulator* sim, stabint_energy* out);
stabint_status stabint_simulator_last_report(const stabint_simulator* sim, stabint_step_report* out);
/** @} */
/** Time of the current state; NaN for NULL. */
double stabint_simulator_time(const stabint_simulator* sim);
/** Steps taken; -1 for NULL. */
int stabint_simulator_step_count(const stabint_simulator* sim);
double stabint_simulator_target(const stabint_simulator* sim);       /**< H* */
double stabint_simulator_energy_scale(const stabint_simulator* sim); /**< E_scale of the blend */
/** The backend and device description, truncated to `capacity` bytes with a terminating NUL;
 * returns the full length (without NUL), so a call with capacity 0 asks for the size. */
size_t stabint_simulator_backend_description(const stabint_simulator* sim, char* out, size_t capacity);

/* ---- per-frame input, between steps (docs/method.md, "Per-frame input") ----
 * Arrays are interleaved x y z per particle, `count` values in all, which must be exactly
 * 3 * stabint_simulator_num_particles (else INVALID_ARGUMENT, as for a NULL pointer). Values the
 * library rejects (a pin index out of range, a non-finite value, iterations < 1) give
 * INVALID_INPUT with a message naming them. Either way nothing changes. */

/** Pin `pin`'s target (an index into the scene's pins) moves linearly from its current value to
 * `target` (x y z) over the next step and stays there; its scripted law is no longer used. Call it
 * every frame with the hand's position to drag. */
stabint_status stabint_simulator_set_pin_target(stabint_simulator* sim, int pin, const double target[3]);
/** Current target of pin `pin` (its law's or the last set value at the current time) into `out`. */
stabint_status stabint_simulator_pin_target(const stabint_simulator* sim, int pin, double out[3]);
/** Collider `collider` (an index into the scene's colliders) translates linearly from where it is
 * to `position` (x y z: where its reference point, the collider's center, goes; the rest of its
 * shape moves with it) over the next step and stays there; its scene velocity is no longer used.
 * Call it every frame with a tool's or the mouse's position; its work is booked in H* like a
 * dragged pin's. */
stabint_status stabint_simulator_set_collider_position(stabint_simulator* sim, int collider, const double position[3]);
/** Collider `collider` translates with `velocity` (m/s; zeros stop it) from where it is now on,
 * until the next set_collider_position or set_collider_velocity. */
stabint_status stabint_simulator_set_collider_velocity(stabint_simulator* sim, int collider, const double velocity[3]);
/** Where collider `collider`'s reference point is now, into `out`. */
stabint_status stabint_simulator_collider_position(const stabint_simulator* sim, int collider, double out[3]);
/** Per-particle external forces in newtons (on top of gravity and force fields): they ramp from
 * their current value to `forces` over the next step and persist until the next call (set zeros
 * to remove them). */
stabint_status stabint_simulator_set_external_forces(stabint_simulator* sim, const double* forces, size_t count);
/** Replace positions and velocities (teleport, reset): H* moves by the jump of H, reported as the
 * next step's event_energy, and BDF2 restarts from the new state. `count` applies to each array. */
stabint_status stabint_simulator_set_state(stabint_simulator* sim, const double* positions, const double* velocities,
                                           size_t count);
/** As stabint_simulator_set_state, replacing the positions only. */
stabint_status stabint_simulator_set_positions(stabint_simulator* sim, const double* positions, size_t count);
/** As stabint_simulator_set_state, replacing the velocities only. */
stabint_status stabint_simulator_set_velocities(stabint_simulator* sim, const double* velocities, size_t count);
/** Local/global iterations per solve of every later step (>= 1); time, state and H* are kept. */
stabint_status stabint_simulator_set_iterations(stabint_simulator* sim, int iterations);
/** Attaches a handle to particle `vertex`: a new pin of `stiffness` (> 0) whose target is the
 * particle's current position; its pin index goes to `out_pin` (for set_pin_target and release).
 * The global factors get a rank-1 update, no refactorization. */
stabint_status stabint_simulator_grab(stabint_simulator* sim, int vertex, double stiffness, int* out_pin);
/** Detaches pin `pin` (stiffness 0, index kept); the pin's energy leaves H and H* (event_energy). */
stabint_status stabint_simulator_release(stabint_simulator* sim, int pin);
/** Element changes (Simulator::setElementStiffness, setElementEnabled): `kind` names an element
 * list ("spring", "tet", "triangle_strain", "bending_hinge", "pin", or the plural); `count`
 * indices into it get `stiffness` (finite, >= 0) or are enabled (`enabled` != 0) or disabled
 * (weight 0, stiffness kept). The energy jump is booked in H and H* (event_energy); the global
 * factors get rank updates. All indices are checked first: INVALID_INPUT changes nothing. */
/** @{ */
stabint_status stabint_simulator_set_element_stiffness(stabint_simulator* sim, const char* kind, const int* indices,
                                                       size_t count, double stiffness);
stabint_status stabint_simulator_set_element_enabled(stabint_simulator* sim, const char* kind, const int* indices,
                                                     size_t count, int enabled);
/** @} */

/* ---- checkpoints ----
 * A snapshot of a running simulation (time, step count, state, BDF2 history, H*, the per-frame
 * forcing; not the options). Restoring it into a simulator of the same scene, options and backend
 * continues bit for bit as the original did. The serialized form is versioned and specific to this
 * library version and byte order. */
/** An opaque checkpoint (a stabint::Checkpoint). */
typedef struct stabint_checkpoint stabint_checkpoint;

/** A snapshot of the simulator's current state into a new checkpoint. */
stabint_status stabint_simulator_checkpoint(const stabint_simulator* sim, stabint_checkpoint** out);
/** INVALID_INPUT when the checkpoint belongs to another scene (particle or pin count, masses, rest
 * shape); the simulator is then unchanged. */
stabint_status stabint_simulator_restore(stabint_simulator* sim, const stabint_checkpoint* checkpoint);
/** FILE_FORMAT when the file cannot be written completely, or (load) is missing or malformed; the
 * message names the path. */
/** @{ */
stabint_status stabint_checkpoint_save(const stabint_checkpoint* checkpoint, const char* path);
stabint_status stabint_checkpoint_load(const char* path, stabint_checkpoint** out);
/** @} */
/** The serialized bytes (what save writes): `size` bytes at the returned pointer, valid while the
 * checkpoint exists; NULL (and size 0) for a NULL handle. `size` may be NULL. */
const void* stabint_checkpoint_data(const stabint_checkpoint* checkpoint, size_t* size);
/** A checkpoint from serialized bytes (e.g. kept in memory or sent over a network); FILE_FORMAT
 * when they are malformed. */
stabint_status stabint_checkpoint_from_bytes(const void* data, size_t size, stabint_checkpoint** out);
/** Releases a checkpoint (NULL is ignored). */
void stabint_checkpoint_destroy(stabint_checkpoint* checkpoint);
double stabint_checkpoint_time(const stabint_checkpoint* checkpoint);    /**< NaN for NULL */
int stabint_checkpoint_step_count(const stabint_checkpoint* checkpoint); /**< -1 for NULL */

#ifdef __cplusplus
}
#endif

/* The batch of scenes, in its own header (included here, so that stabint_c.h is the whole C API). */
#include <stabint/stabint_batch_c.h>

#endif /**< STABINT_STABINT_C_H */
