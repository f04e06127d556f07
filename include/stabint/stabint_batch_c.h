/** @file
 * The C API's batch of scenes (stabint::BatchSimulator): the simulator's calls with a leading
 * scene index, per-scene reports and refusals, and checkpoints per scene and of the whole batch.
 * Status codes, the last error, ownership and threads are stabint_c.h's, which includes this
 * header (include either). */
#ifndef STABINT_STABINT_BATCH_C_H
#define STABINT_STABINT_BATCH_C_H

#include <stabint/stabint_c.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- batches (stabint::BatchSimulator, stabint/batch.hpp; docs/method.md "Batches") ----
 * Many independent scenes stepped as one: one local/global solve and one block-diagonal factor
 * for all, and per scene its own energies, H*, blend decisions, forcing, damping, refusals and
 * per-frame input, so that every scene follows the trajectory its own simulator would (bit for bit
 * for a batch of one scene on the CPU reference; with more scenes, to the round-off of the
 * factor's ordering). Scenes are numbered from 0 in the order passed to stabint_batch_create; each
 * per-scene call takes the scene's own indices (its particles, pins, colliders and elements,
 * numbered from 0 as in the scene passed in).
 *
 * Errors: the calls follow the simulator's (stabint_simulator_*): NULL pointers and wrong array
 * sizes are INVALID_ARGUMENT naming the argument; a scene out of range and values the library
 * rejects are INVALID_INPUT with a message naming the call, the scene and the field or index
 * ("grab: scene 2: vertex 40 out of range ..."). Either way nothing changes. Getters that return a
 * plain value return -1 or NaN for a NULL handle or a scene out of range, and then also set the
 * last error (stabint_last_error_message() names the problem).
 *
 * Refusals: a scene whose step blows up or exceeds options.energy_limit does not fail the batch's
 * step. Its step is refused (stabint_batch_refusal gives the message its own simulator's step
 * would have returned), its last accepted state is kept, and it stays inactive (stabint_batch_active
 * is 0) while the other scenes step on, until stabint_batch_set_state or stabint_batch_scene_restore
 * restarts it from the batch's time. An inactive scene takes per-frame input as an active one does. */
/** An opaque batch of scenes (a stabint::BatchSimulator), from stabint_batch_create. */
typedef struct stabint_batch stabint_batch;

/** Validates and copies `count` (>= 1) scenes and the options, all scenes sharing the options.
 * INVALID_INPUT for a bad scene or option, or one outside a batch's constraints (the message names
 * the scene at fault): the same gravity in every scene. Every solver option runs per scene (each
 * acceleration, the stops by accuracy, tolerance and gradient_tolerance, and CG on each scene's
 * block): each scene stops where its own simulator would.
 * The scenes may be destroyed as soon as the batch exists. */
stabint_status stabint_batch_create(const stabint_scene* const* scenes, int count,
                                    const stabint_simulator_options* options, stabint_batch** out);
/** Releases a batch (NULL is ignored). */
void stabint_batch_destroy(stabint_batch* batch);
/** The options the batch was built with (strings point into the batch, as for a simulator). */
stabint_status stabint_batch_get_options(const stabint_batch* batch, stabint_simulator_options* out);

/** Advances every active scene one step and fills `reports` with one report per scene, in scene
 * order (`capacity` reports, at least stabint_batch_size; `reports` may be NULL with capacity 0).
 * Returns STABINT_OK when some scenes were refused: see "Refusals" above; a refused or inactive
 * scene's report describes its kept state. A refused call (a short buffer) does not step. */
stabint_status stabint_batch_step(stabint_batch* batch, stabint_step_report* reports, size_t capacity);
/** Scene `scene`'s report of the last stabint_batch_step (zeros before the first). */
stabint_status stabint_batch_last_report(const stabint_batch* batch, int scene, stabint_step_report* out);
/** Why scene `scene`'s last step was refused (the text its own simulator's step would fail with,
 * which stabint_last_error_message() would give after "<Class>: "), or that it is inactive since a
 * refused step: "" when it stepped (and before the first step). Copied truncated to `capacity` bytes with a terminating
 * NUL (`out` may be NULL with capacity 0); the full length (without NUL) goes to `length` (may be
 * NULL). */
stabint_status stabint_batch_refusal(const stabint_batch* batch, int scene, char* out, size_t capacity, size_t* length);

/** Number of scenes; -1 for NULL. */
int stabint_batch_size(const stabint_batch* batch);
/** 1 while scene `scene` steps, 0 after a refused step until set_state or scene_restore; -1 for NULL or a
 * scene out of range. */
int stabint_batch_active(const stabint_batch* batch, int scene);
/** Number of particles of scene `scene`; -1 for NULL or a scene out of range. */
int stabint_batch_num_particles(const stabint_batch* batch, int scene);
/** Where scene `scene`'s particles start among all the batch's (stabint_batch_copy_all_positions);
 * -1 for NULL or a scene out of range. */
int stabint_batch_first_particle(const stabint_batch* batch, int scene);
/** The batch's time (every active scene's); NaN for NULL. */
double stabint_batch_time(const stabint_batch* batch);
/** Time of scene `scene`'s last accepted state; NaN for NULL or a scene out of range. */
double stabint_batch_scene_time(const stabint_batch* batch, int scene);
/** Steps scene `scene` has taken (of its last accepted state); -1 for NULL or a scene out of range. */
int stabint_batch_step_count(const stabint_batch* batch, int scene);
/** H* of scene `scene`; NaN for NULL or a scene out of range. */
double stabint_batch_target(const stabint_batch* batch, int scene);
/** E_scale of scene `scene`'s blend (of the scene alone); NaN for NULL or a scene out of range. */
double stabint_batch_energy_scale(const stabint_batch* batch, int scene);
/** Energies of scene `scene`'s current state. */
stabint_status stabint_batch_energy(const stabint_batch* batch, int scene, stabint_energy* out);
/** The backend and device description, as stabint_simulator_backend_description. */
size_t stabint_batch_backend_description(const stabint_batch* batch, char* out, size_t capacity);

/** Scene `scene`'s state copied interleaved, x y z per particle, into `out` with room for
 * `capacity` values (at least 3 * stabint_batch_num_particles(batch, scene)). */
/** @{ */
stabint_status stabint_batch_copy_positions(const stabint_batch* batch, int scene, double* out, size_t capacity);
stabint_status stabint_batch_copy_positions_float(const stabint_batch* batch, int scene, float* out, size_t capacity);
stabint_status stabint_batch_copy_velocities(const stabint_batch* batch, int scene, double* out, size_t capacity);
stabint_status stabint_batch_copy_velocities_float(const stabint_batch* batch, int scene, float* out, size_t capacity);
/** @} */
/** Every scene's positions, one after another (one vertex buffer for a renderer): scene s's
 * particles start at stabint_batch_first_particle(batch, s). `capacity` values, at least 3 times
 * the total particle count. */
/** @{ */
stabint_status stabint_batch_copy_all_positions(const stabint_batch* batch, double* out, size_t capacity);
stabint_status stabint_batch_copy_all_positions_float(const stabint_batch* batch, float* out, size_t capacity);
/** @} */

/* Per-frame input of one scene, as the simulator's (see "per-frame input" above): arrays are
 * interleaved x y z per particle of that scene, `count` values, exactly
 * 3 * stabint_batch_num_particles(batch, scene). Changes, events and the work of forcing are booked
 * in that scene's H* only. */

/** Replaces scene `scene`'s positions and velocities, as stabint_simulator_set_state; a scene
 * inactive after a refused step steps again, from the batch's time. With BDF2 only in a batch of
 * one scene. `count` applies to each array. */
stabint_status stabint_batch_set_state(stabint_batch* batch, int scene, const double* positions,
                                       const double* velocities, size_t count);
/** stabint_batch_set_state of `scene_count` scenes at once (`scenes`, each at most once), as
 * BatchSimulator::setStates: the same events bit for bit, with one wait on a device. `positions`
 * and `velocities` hold the listed scenes' arrays one after another in the list's order; `count`,
 * for each of the two, is their total length, 3 times the listed scenes' particles. Everything is
 * checked first: on an error no scene changes. */
stabint_status stabint_batch_set_states(stabint_batch* batch, const int* scenes, size_t scene_count,
                                        const double* positions, const double* velocities, size_t count);
/** Local/global iterations per solve of every later step of every scene (>= 1), as
 * stabint_simulator_set_iterations. */
stabint_status stabint_batch_set_iterations(stabint_batch* batch, int iterations);
/** Pin `pin` of scene `scene` moves to `target`, as stabint_simulator_set_pin_target. */
stabint_status stabint_batch_set_pin_target(stabint_batch* batch, int scene, int pin, const double target[3]);
/** Current target of pin `pin` of scene `scene` into `out`. */
stabint_status stabint_batch_pin_target(const stabint_batch* batch, int scene, int pin, double out[3]);
/** Scene `scene`'s per-particle external forces, as stabint_simulator_set_external_forces. */
stabint_status stabint_batch_set_external_forces(stabint_batch* batch, int scene, const double* forces, size_t count);
/** Collider `collider` of scene `scene` moves to `position` over the next step, or on with
 * `velocity`, as stabint_simulator_set_collider_position and set_collider_velocity; it acts on its
 * own scene's particles only, wherever the scenes lie in space. */
/** @{ */
stabint_status stabint_batch_set_collider_position(stabint_batch* batch, int scene, int collider,
                                                   const double position[3]);
stabint_status stabint_batch_set_collider_velocity(stabint_batch* batch, int scene, int collider,
                                                   const double velocity[3]);
/** @} */
/** Where collider `collider` of scene `scene` is at the batch's time, into `out`. */
stabint_status stabint_batch_collider_position(const stabint_batch* batch, int scene, int collider, double out[3]);
/** Attaches a handle to particle `vertex` of scene `scene`, as stabint_simulator_grab: its index
 * among that scene's pins goes to `out_pin`. */
stabint_status stabint_batch_grab(stabint_batch* batch, int scene, int vertex, double stiffness, int* out_pin);
/** Detaches pin `pin` of scene `scene`, as stabint_simulator_release. */
stabint_status stabint_batch_release(stabint_batch* batch, int scene, int pin);
/** Element changes of scene `scene`, as stabint_simulator_set_element_stiffness and
 * set_element_enabled (the same `kind` names; indices into that scene's lists). */
/** @{ */
stabint_status stabint_batch_set_element_stiffness(stabint_batch* batch, int scene, const char* kind,
                                                   const int* indices, size_t count, double stiffness);
stabint_status stabint_batch_set_element_enabled(stabint_batch* batch, int scene, const char* kind, const int* indices,
                                                 size_t count, int enabled);
/** @} */

/** A snapshot of scene `scene` into a new checkpoint, in the simulator's format: it restores into
 * a simulator of that scene (same options and backend), which continues as the scene did (to the
 * round-off of the batch's factor against its own), and into scene `scene` of a batch of the same
 * scenes. Its time is the scene's (stabint_batch_scene_time). */
stabint_status stabint_batch_scene_checkpoint(const stabint_batch* batch, int scene, stabint_checkpoint** out);
/** Continues scene `scene` from `checkpoint` (of that scene, from stabint_batch_checkpoint or a
 * simulator's of the same scene and options); an inactive scene becomes active. The scenes share
 * the batch's time, so the checkpoint's time must be stabint_batch_time. INVALID_INPUT naming the
 * scene for a checkpoint of another scene, time or history; the batch is then unchanged. */
stabint_status stabint_batch_scene_restore(stabint_batch* batch, int scene, const stabint_checkpoint* checkpoint);

/* A snapshot of a whole batch (stabint::BatchCheckpoint): the batch's time and one checkpoint per
 * scene in the simulator's format. Restoring it into a batch of the same scenes (in the same
 * order) and options continues bit for bit as the batch did from that moment when the batch
 * restored into has the same pins and element stiffnesses as the checkpoint (the same batch, or a
 * new one when no pin or element was changed before the checkpoint); otherwise to round-off. A
 * scene that was inactive is restored inactive. The serialized form is one file: a versioned
 * header, the time and each scene's checkpoint. */
/** An opaque checkpoint of a whole batch (a stabint::BatchCheckpoint). */
typedef struct stabint_batch_checkpoint stabint_batch_checkpoint;

/** A snapshot of every scene of the batch into a new batch checkpoint. */
stabint_status stabint_batch_checkpoint_create(const stabint_batch* batch, stabint_batch_checkpoint** out);
/** Continues every scene from `checkpoint`: the batch's time, each scene's state, H*, pins,
 * elements, forcing and contact set, BDF2's history and which scenes are inactive. INVALID_INPUT
 * for another number of scenes, or a scene's checkpoint of another scene (the message names the
 * scene); the batch is then unchanged. */
stabint_status stabint_batch_restore(stabint_batch* batch, const stabint_batch_checkpoint* checkpoint);
/** Scene `scene`'s checkpoint in it, copied into a new simulator checkpoint (it restores into a
 * simulator of that scene, as stabint_batch_scene_checkpoint's does); INVALID_INPUT out of range. */
stabint_status stabint_batch_checkpoint_scene(const stabint_batch_checkpoint* checkpoint, int scene,
                                              stabint_checkpoint** out);
/** As stabint_checkpoint_save and stabint_checkpoint_load, for a batch checkpoint. */
/** @{ */
stabint_status stabint_batch_checkpoint_save(const stabint_batch_checkpoint* checkpoint, const char* path);
stabint_status stabint_batch_checkpoint_load(const char* path, stabint_batch_checkpoint** out);
/** @} */
/** The serialized bytes, as stabint_checkpoint_data (valid while the checkpoint exists). */
const void* stabint_batch_checkpoint_data(const stabint_batch_checkpoint* checkpoint, size_t* size);
/** A batch checkpoint from serialized bytes; FILE_FORMAT when they are malformed. */
stabint_status stabint_batch_checkpoint_from_bytes(const void* data, size_t size, stabint_batch_checkpoint** out);
/** Releases a batch checkpoint (NULL is ignored). */
void stabint_batch_checkpoint_destroy(stabint_batch_checkpoint* checkpoint);
double stabint_batch_checkpoint_time(const stabint_batch_checkpoint* checkpoint); /**< the batch's time; NaN for NULL */
int stabint_batch_checkpoint_size(const stabint_batch_checkpoint* checkpoint);    /**< scenes; -1 for NULL */

#ifdef __cplusplus
}
#endif

#endif /**< STABINT_STABINT_BATCH_C_H */
