/* The C API (include/stabint/stabint_c.h) from a C program: compiled as C99, no C++ in sight.
 * Each check prints on failure; the program ends with "N passed, N failed" and exits non-zero
 * when any check failed. Run by ctest (label cpu). */
/* mkstemp, fdopen and close (POSIX) for temporary files (a checkpoint, a scene). */
#define _POSIX_C_SOURCE 200809L

#include <stabint/stabint_c.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int passed = 0;
static int failed = 0;

#define CHECK(cond)                                                                           \
  do {                                                                                        \
    if (cond) {                                                                               \
      ++passed;                                                                               \
    } else {                                                                                  \
      ++failed;                                                                               \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__, __LINE__, #cond, \
              stabint_last_error_message());                                                  \
    }                                                                                         \
  } while (0)

static int starts_with(const char* text, const char* prefix) { return strncmp(text, prefix, strlen(prefix)) == 0; }

/* The chain's swing energy m g L / 2 with the builder's defaults (0.1 kg, 9.81, 1 m): the
 * energy the pendulum turns into motion, the unit of tests/test_stability.cpp. */
static const double kSwingEnergy = 0.1 * 9.81 * 1.0 / 2.0;

/* Runs the default chain for `frames` steps; returns the largest |H - H*| seen, or -1 when a
 * step was refused. */
static double chain_max_deviation(stabint_integrator integrator, int frames) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_step_report report;
  double max_dev = 0.0;
  int f;
  CHECK(stabint_scene_create_builtin("chain", NULL, &scene) == STABINT_OK);
  stabint_simulator_options_default(&options);
  options.integrator = integrator;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  stabint_scene_destroy(scene); /* the simulator holds its own copy */
  for (f = 0; f < frames; ++f) {
    if (stabint_simulator_step(sim, &report) != STABINT_OK) {
      max_dev = -1.0;
      break;
    }
    if (fabs(report.energy.total - report.target) > max_dev) max_dev = fabs(report.energy.total - report.target);
  }
  stabint_simulator_destroy(sim);
  return max_dev;
}

/* The blend tracks H* on the stiff chain where IM alone explodes (docs/main_job.md, motion table: max
 * |H - H*| 0.3 % of the available energy). Bound: 5 % of the swing energy over 300 frames, a
 * margin of 10x over the measured figure; IM's deviation exceeds it by orders of magnitude, so
 * the bound also shows that the report's fields are the blend's, not zeros. */
static void test_blend_tracks_target_on_chain(void) {
  const double blend = chain_max_deviation(STABINT_ENERGY_BLEND, 300);
  const double im = chain_max_deviation(STABINT_IMPLICIT_MIDPOINT, 300);
  printf("chain, 300 frames: max |H - H*| blend %.3g J, IM %.3g J (swing energy %.3g J)\n", blend, im, kSwingEnergy);
  CHECK(blend >= 0.0 && blend < 0.05 * kSwingEnergy);
  CHECK(im > 100.0 * kSwingEnergy);
}

static void test_defaults_and_names(void) {
  stabint_simulator_options options;
  stabint_simulator_options_default(&options);
  CHECK(options.integrator == STABINT_ENERGY_BLEND);
  CHECK(fabs(options.time_step - 1.0 / 30.0) < 1e-15);
  CHECK(options.iterations == 10);
  CHECK(options.backend == STABINT_BACKEND_CPU);
  CHECK(strcmp(stabint_integrator_name(STABINT_BDF2), "BDF2") == 0);
  CHECK(strcmp(stabint_blend_branch_name(STABINT_BRANCH_VELOCITY_SCALE), "scale") == 0);
  CHECK(stabint_integrator_name((stabint_integrator)17) == NULL);
  CHECK(stabint_integrator_name((stabint_integrator)-1) == NULL);
  CHECK(stabint_blend_branch_name((stabint_blend_branch)4) == NULL);
  CHECK(stabint_status_is(STABINT_ENERGY_LIMIT, STABINT_NON_FINITE_STATE));
  CHECK(stabint_status_is(STABINT_NO_OPENCL_DEVICE, STABINT_OPENCL));
  CHECK(stabint_status_is(STABINT_FILE_FORMAT, STABINT_ERROR));
  CHECK(!stabint_status_is(STABINT_FILE_FORMAT, STABINT_INVALID_INPUT));
  CHECK(!stabint_status_is(STABINT_OK, STABINT_ERROR));
}

/* A simulator gives back the options it was built with (tests/test_options_fields.cpp does every
 * field; this is the C user's view). */
static void test_options_read_back(void) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_simulator_options back;
  CHECK(stabint_scene_create_builtin("oscillator", NULL, &scene) == STABINT_OK);
  stabint_simulator_options_default(&options);
  options.lbfgs_history = 7;
  options.global_solve = STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT;
  options.opencl_device = "1";
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  CHECK(stabint_simulator_get_options(sim, &back) == STABINT_OK);
  CHECK(back.lbfgs_history == 7 && back.global_solve == STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT);
  CHECK(back.time_step == options.time_step && back.iterations == options.iterations);
  CHECK(back.opencl_platform == NULL && back.opencl_device != NULL && strcmp(back.opencl_device, "1") == 0);
  CHECK(stabint_simulator_get_options(NULL, &back) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_get_options(sim, NULL) == STABINT_INVALID_ARGUMENT);
  stabint_simulator_destroy(sim);
  stabint_scene_destroy(scene);
}

static void test_bad_options_are_reported(void) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  CHECK(stabint_scene_create_builtin("oscillator", NULL, &scene) == STABINT_OK);

  stabint_simulator_options_default(&options);
  options.time_step = -0.1;
  sim = (stabint_simulator*)&options; /* a stale value: a failed create sets it to NULL */
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(sim == NULL);
  CHECK(stabint_last_error_status() == STABINT_INVALID_INPUT);
  CHECK(starts_with(stabint_last_error_message(), "InvalidInputError: "));
  CHECK(strstr(stabint_last_error_message(), "time_step") != NULL);

  /* An out-of-range enum value must not reach the C++ enum. */
  stabint_simulator_options_default(&options);
  options.integrator = (stabint_integrator)42;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "options.integrator") != NULL);
  stabint_simulator_options_default(&options);
  options.backend = (stabint_backend)-3;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "options.backend") != NULL);

  /* A device selector that matches nothing: NoOpenCLDeviceError whether or not OpenCL exists. */
  stabint_simulator_options_default(&options);
  options.backend = STABINT_BACKEND_OPENCL;
  options.opencl_device = "no-such-device-anywhere";
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_NO_OPENCL_DEVICE);
  CHECK(starts_with(stabint_last_error_message(), "NoOpenCLDeviceError: "));

  CHECK(stabint_simulator_create(NULL, &options, &sim) == STABINT_INVALID_ARGUMENT);
  stabint_scene_destroy(scene);
}

/* SE is unstable on the stiff chain (omega h ~ 30 > 2): the refused step comes back as
 * NON_FINITE_STATE with its index, and the simulator keeps the last finite state. */
static void test_blow_up_is_reported(void) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_status status = STABINT_OK;
  int f, i, n, all_finite = 1;
  double* x;
  CHECK(stabint_scene_create_builtin("chain", NULL, &scene) == STABINT_OK);
  stabint_simulator_options_default(&options);
  options.integrator = STABINT_SYMPLECTIC_EULER;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  for (f = 0; f < 300 && status == STABINT_OK; ++f) status = stabint_simulator_step(sim, NULL);
  CHECK(status == STABINT_NON_FINITE_STATE || status == STABINT_ENERGY_LIMIT);
  CHECK(stabint_status_is(status, STABINT_NON_FINITE_STATE));
  CHECK(stabint_last_error_step() == stabint_simulator_step_count(sim));
  n = stabint_simulator_num_particles(sim);
  x = (double*)malloc(3 * (size_t)n * sizeof(double));
  CHECK(stabint_simulator_copy_positions(sim, x, 3 * (size_t)n) == STABINT_OK);
  for (i = 0; i < 3 * n; ++i) all_finite = all_finite && isfinite(x[i]);
  CHECK(all_finite);
  free(x);
  stabint_simulator_destroy(sim);
  stabint_scene_destroy(scene);
}

/* Interleaved positions in double and float agree with each other, move under gravity, and a
 * short buffer is refused without writing. Cloth triangles index the particles. */
static void test_buffers_and_triangles(void) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_step_report report;
  stabint_energy energy;
  double *x0, *x1, *v;
  float* xf;
  int32_t* tris;
  int i, n, nt, in_range = 1, agree = 1;
  char description[256];
  CHECK(stabint_scene_create_builtin("cloth", "{\"nx\": 6, \"ny\": 5}", &scene) == STABINT_OK);
  n = stabint_scene_num_particles(scene);
  nt = stabint_scene_num_triangles(scene);
  CHECK(n == 30);
  CHECK(nt == 2 * 5 * 4);
  tris = (int32_t*)malloc(3 * (size_t)nt * sizeof(int32_t));
  CHECK(stabint_scene_copy_triangles(scene, tris, 3 * (size_t)nt) == STABINT_OK);
  for (i = 0; i < 3 * nt; ++i) in_range = in_range && tris[i] >= 0 && tris[i] < n;
  CHECK(in_range);
  free(tris);

  stabint_simulator_options_default(&options);
  options.integrator = STABINT_BACKWARD_EULER;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  stabint_scene_destroy(scene);
  x0 = (double*)malloc(3 * (size_t)n * sizeof(double));
  x1 = (double*)malloc(3 * (size_t)n * sizeof(double));
  v = (double*)malloc(3 * (size_t)n * sizeof(double));
  xf = (float*)malloc(3 * (size_t)n * sizeof(float));
  CHECK(stabint_simulator_copy_positions(sim, x0, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(report.step == 0);
  CHECK(fabs(report.time - options.time_step) < 1e-15);
  CHECK(report.branch == STABINT_BRANCH_NONE); /* BE has no blend branch */
  CHECK(report.iterations == options.iterations);
  CHECK(report.times.total >= 0.0);
  CHECK(stabint_simulator_copy_positions(sim, x1, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions_float(sim, xf, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_simulator_copy_velocities(sim, v, 3 * (size_t)n) == STABINT_OK);
  /* float rounding of coordinates of order 1 m: relative 6e-8, so 1e-6 m is ample. */
  for (i = 0; i < 3 * n; ++i) agree = agree && fabs((double)xf[i] - x1[i]) < 1e-6;
  CHECK(agree);
  /* A free particle (the last one: the bottom corner, not pinned) falls: y and v_y go down. */
  CHECK(x1[3 * (n - 1) + 1] < x0[3 * (n - 1) + 1]);
  CHECK(v[3 * (n - 1) + 1] < 0.0);
  CHECK(stabint_simulator_copy_positions(sim, x1, 3 * (size_t)n - 1) == STABINT_INVALID_ARGUMENT);
  CHECK(strstr(stabint_last_error_message(), "needed") != NULL);
  CHECK(stabint_simulator_energy(sim, &energy) == STABINT_OK);
  CHECK(fabs(energy.total - report.energy.total) <= 1e-12 * fabs(energy.total));
  CHECK(stabint_simulator_backend_description(sim, description, sizeof description) > 0);
  free(x0);
  free(x1);
  free(v);
  free(xf);
  stabint_simulator_destroy(sim);
}

static void test_files(const char* scene_dir) {
  stabint_scene* scene = NULL;
  char path[1024];
  CHECK(stabint_scene_load("/nonexistent/scene.json", &scene) == STABINT_FILE_FORMAT);
  CHECK(scene == NULL);
  CHECK(strstr(stabint_last_error_message(), "/nonexistent/scene.json") != NULL);
  CHECK(stabint_scene_create_builtin("cloth", "{\"no_such_param\": 1}", &scene) == STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), "no_such_param") != NULL);
  snprintf(path, sizeof path, "%s/chain.json", scene_dir);
  CHECK(stabint_scene_load(path, &scene) == STABINT_OK);
  CHECK(stabint_scene_num_particles(scene) == 6); /* scenes/chain.json: six masses */
  stabint_scene_destroy(scene);
}

/* A cloth simulator (BE unless told) on a 6 x 5 grid pinned at its two top corners (pins 0, 1). */
static stabint_simulator* small_cloth(stabint_integrator integrator) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  CHECK(stabint_scene_create_builtin("cloth", "{\"nx\": 6, \"ny\": 5}", &scene) == STABINT_OK);
  stabint_simulator_options_default(&options);
  options.integrator = integrator;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  stabint_scene_destroy(scene);
  return sim;
}

static double* new_rows(int n) { return (double*)calloc(3 * (size_t)n, sizeof(double)); }

/* A hand drags pin 0 along x, its target set every frame: the target reads back exactly as set
 * (the ramp ends on it bit for bit), the pinned corner follows it and the other pin stays. */
static void test_pin_target_set_every_frame_moves_the_pin(void) {
  stabint_simulator* sim = small_cloth(STABINT_BACKWARD_EULER);
  const int n = stabint_simulator_num_particles(sim);
  double q0[3], q1[3], q[3], back[3];
  double* x = new_rows(n);
  int f, i, corner = -1, exact = 1;
  CHECK(stabint_simulator_pin_target(sim, 0, q0) == STABINT_OK);
  CHECK(stabint_simulator_pin_target(sim, 1, q1) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, x, 3 * (size_t)n) == STABINT_OK);
  for (i = 0; i < n && corner < 0; ++i) /* the particle that pin 0 holds starts on its target */
    if (x[3 * i] == q0[0] && x[3 * i + 1] == q0[1] && x[3 * i + 2] == q0[2]) corner = i;
  CHECK(corner >= 0);
  if (corner < 0) corner = 0;
  for (f = 1; f <= 30; ++f) {
    q[0] = q0[0] + 0.01 * f; /* 0.3 m/s, reached at 1 s */
    q[1] = q0[1];
    q[2] = q0[2];
    CHECK(stabint_simulator_set_pin_target(sim, 0, q) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
    CHECK(stabint_simulator_pin_target(sim, 0, back) == STABINT_OK);
    exact = exact && memcmp(back, q, sizeof q) == 0;
  }
  CHECK(exact);
  CHECK(stabint_simulator_pin_target(sim, 1, back) == STABINT_OK);
  CHECK(memcmp(back, q1, sizeof q1) == 0);
  /* The corner follows its pin (k = 1e5 N/m against a few newtons of cloth: under 1 cm off). */
  CHECK(stabint_simulator_copy_positions(sim, x, 3 * (size_t)n) == STABINT_OK);
  printf("dragged corner: x moved %.4f m for a pin moved 0.3 m\n", x[3 * corner] - q0[0]);
  CHECK(fabs(x[3 * corner] - (q0[0] + 0.3)) < 0.01);
  free(x);
  stabint_simulator_destroy(sim);
}

/* Rejected input: INVALID_INPUT naming the value (library rules) or INVALID_ARGUMENT (C misuse:
 * NULL, wrong array size); neither changes the simulator, which then runs as an untouched twin. */
static void test_bad_input_is_rejected_and_changes_nothing(void) {
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  stabint_simulator* twin = small_cloth(STABINT_ENERGY_BLEND);
  const int n = stabint_simulator_num_particles(sim);
  const size_t count = 3 * (size_t)n;
  double* x = new_rows(n);
  double* y = new_rows(n);
  double q[3] = {0.0, 0.0, 0.0}, q0[3], back[3];
  stabint_step_report a, b;
  int f;
  CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  CHECK(stabint_simulator_step(twin, NULL) == STABINT_OK);
  CHECK(stabint_simulator_pin_target(sim, 0, q0) == STABINT_OK);

  CHECK(stabint_simulator_set_pin_target(sim, 2, q) == STABINT_INVALID_INPUT);
  CHECK(starts_with(stabint_last_error_message(), "InvalidInputError: "));
  CHECK(strstr(stabint_last_error_message(), "pin 2 out of range") != NULL);
  CHECK(stabint_simulator_set_pin_target(sim, -1, q) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "pin -1") != NULL);
  CHECK(stabint_simulator_pin_target(sim, 5, back) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "pin 5") != NULL);
  q[1] = NAN;
  CHECK(stabint_simulator_set_pin_target(sim, 0, q) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "pin 0: target is not finite") != NULL);
  CHECK(stabint_simulator_set_pin_target(sim, 0, NULL) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_iterations(sim, 0) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "iterations = 0") != NULL);

  /* Wrong sizes, one value short and one particle too many, and NULL arrays. */
  CHECK(stabint_simulator_set_external_forces(sim, x, count - 1) == STABINT_INVALID_ARGUMENT);
  CHECK(starts_with(stabint_last_error_message(), "InvalidArgument: forces"));
  CHECK(strstr(stabint_last_error_message(), "expected") != NULL);
  CHECK(stabint_simulator_set_positions(sim, x, count + 3) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_velocities(sim, x, 0) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_state(sim, x, y, count - 3) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_state(sim, x, NULL, count) == STABINT_INVALID_ARGUMENT);
  CHECK(strstr(stabint_last_error_message(), "velocities is NULL") != NULL);
  CHECK(stabint_simulator_set_external_forces(NULL, x, count) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_iterations(NULL, 3) == STABINT_INVALID_ARGUMENT);

  /* A non-finite row: the right size, so the library's own check names it. */
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  x[3 * 3 + 1] = NAN;
  CHECK(stabint_simulator_set_positions(sim, x, count) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "positions: row 3 is not finite") != NULL);

  CHECK(stabint_simulator_pin_target(sim, 0, back) == STABINT_OK);
  CHECK(memcmp(back, q0, sizeof q0) == 0);
  CHECK(stabint_simulator_target(sim) == stabint_simulator_target(twin));
  for (f = 0; f < 5; ++f) {
    CHECK(stabint_simulator_step(sim, &a) == STABINT_OK);
    CHECK(stabint_simulator_step(twin, &b) == STABINT_OK);
    CHECK(a.target == b.target && a.iterations == b.iterations);
    CHECK(a.event_energy == 0.0);
  }
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(twin, y, count) == STABINT_OK);
  CHECK(memcmp(x, y, count * sizeof(double)) == 0);
  free(x);
  free(y);
  stabint_simulator_destroy(sim);
  stabint_simulator_destroy(twin);
}

/* Setting the state books the jump of H in H* at once and reports it as the next step's
 * event_energy; external forces push the cloth; the iteration budget reaches the next report. */
static void test_state_forces_and_iterations(void) {
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  const int n = stabint_simulator_num_particles(sim);
  const size_t count = 3 * (size_t)n;
  double* x = new_rows(n);
  double* v = new_rows(n);
  double* f = new_rows(n);
  double* back = new_rows(n);
  stabint_energy before, after;
  stabint_step_report report;
  stabint_checkpoint* ckpt = NULL;
  double target_before, jump, x_unforced;
  int i, low = 0;
  for (i = 0; i < 5; ++i) CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_velocities(sim, v, count) == STABINT_OK);
  for (i = 0; i < n; ++i) {
    x[3 * i + 2] += 0.01; /* pushed out of the pins' plane */
    v[3 * i] = 0.2;
  }
  CHECK(stabint_simulator_energy(sim, &before) == STABINT_OK);
  target_before = stabint_simulator_target(sim);
  CHECK(stabint_simulator_set_state(sim, x, v, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, back, count) == STABINT_OK);
  CHECK(memcmp(back, x, count * sizeof(double)) == 0);
  CHECK(stabint_simulator_copy_velocities(sim, back, count) == STABINT_OK);
  CHECK(memcmp(back, v, count * sizeof(double)) == 0);
  CHECK(stabint_simulator_energy(sim, &after) == STABINT_OK);
  jump = after.total - before.total;
  CHECK(jump > 0.0);
  CHECK(fabs(stabint_simulator_target(sim) - (target_before + jump)) <= 1e-12 * fabs(target_before + jump));
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(report.event_energy == jump);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(report.event_energy == 0.0);

  /* set_velocities alone: zero velocities remove the kinetic energy, booked as a negative event. */
  memset(v, 0, count * sizeof(double));
  CHECK(stabint_simulator_energy(sim, &before) == STABINT_OK);
  CHECK(stabint_simulator_set_velocities(sim, v, count) == STABINT_OK);
  CHECK(stabint_simulator_energy(sim, &after) == STABINT_OK);
  CHECK(after.kinetic == 0.0);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(report.event_energy == after.total - before.total && report.event_energy < 0.0);

  /* set_positions alone keeps the velocities. The lowest particle is a free one (the pins hold
   * the top corners). */
  CHECK(stabint_simulator_copy_velocities(sim, v, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  for (i = 1; i < n; ++i)
    if (x[3 * i + 1] < x[3 * low + 1]) low = i;
  x[3 * low + 1] += 0.05;
  CHECK(stabint_simulator_set_positions(sim, x, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_velocities(sim, back, count) == STABINT_OK);
  CHECK(memcmp(back, v, count * sizeof(double)) == 0);

  /* 1 N along +x on that free particle for 10 steps, against the same 10
   * steps from a checkpoint without it: the corner ends further along +x. */
  CHECK(stabint_simulator_set_iterations(sim, 7) == STABINT_OK);
  CHECK(stabint_simulator_checkpoint(sim, &ckpt) == STABINT_OK);
  for (i = 0; i < 10; ++i) CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(report.iterations >= 7); /* the blend adds its BE partner's solves to IM's */
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  x_unforced = x[3 * low];
  CHECK(stabint_simulator_restore(sim, ckpt) == STABINT_OK);
  f[3 * low] = 1.0;
  CHECK(stabint_simulator_set_external_forces(sim, f, count) == STABINT_OK);
  for (i = 0; i < 10; ++i) CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  printf("1 N on a free particle for 1/3 s: x moved %.4f m further\n", x[3 * low] - x_unforced);
  CHECK(x[3 * low] - x_unforced > 0.01);
  stabint_checkpoint_destroy(ckpt);
  free(x);
  free(v);
  free(f);
  free(back);
  stabint_simulator_destroy(sim);
}

/* Steps `frames` times with pin 0 dragged around `corner` (its rest target) and a force set, as
 * in a game loop, both functions of time only; leaves the final positions in `x` (3 n values). */
static void drive(stabint_simulator* sim, const double corner[3], int frames, double* x) {
  const int n = stabint_simulator_num_particles(sim);
  double* f = new_rows(n);
  double q[3];
  int i;
  for (i = 0; i < frames; ++i) {
    const double t1 = stabint_simulator_time(sim) + 1.0 / 30.0;
    q[0] = corner[0] + 0.1 * sin(3.0 * t1);
    q[1] = corner[1];
    q[2] = corner[2] + 0.05 * t1;
    f[2] = 0.5 * cos(5.0 * t1); /* particle 0: a free bottom corner */
    CHECK(stabint_simulator_set_pin_target(sim, 0, q) == STABINT_OK);
    CHECK(stabint_simulator_set_external_forces(sim, f, 3 * (size_t)n) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  }
  CHECK(stabint_simulator_copy_positions(sim, x, 3 * (size_t)n) == STABINT_OK);
  free(f);
}

/* A checkpoint restored into the same simulator, into a new one, from its bytes and from a file
 * continues bit for bit; bad files and another scene's checkpoint are refused. */
/* Grab a free particle, drag it, release it: the handle is a new pin (index 2), the grab books no
 * energy jump, the release books minus the handle's energy, and bad calls are INVALID_INPUT. */
static void test_grab_and_release(void) {
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  const int n = stabint_simulator_num_particles(sim);
  const size_t count = 3 * (size_t)n;
  double* x = new_rows(n);
  double target[3], target_before;
  stabint_energy before, after;
  stabint_step_report report;
  const int low = n - 6; /* bottom-left corner of the 6-wide grid: no pin holds it */
  int handle = -1, i;
  CHECK(stabint_simulator_copy_positions(sim, x, count) == STABINT_OK);
  target_before = stabint_simulator_target(sim);
  CHECK(stabint_simulator_grab(sim, low, 1e4, &handle) == STABINT_OK);
  CHECK(handle == 2);
  CHECK(stabint_simulator_target(sim) == target_before);
  for (i = 0; i < 10; ++i) {
    target[0] = x[3 * low] + 0.01 * i;
    target[1] = x[3 * low + 1];
    target[2] = x[3 * low + 2] + 0.02 * i;
    CHECK(stabint_simulator_set_pin_target(sim, handle, target) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  }
  CHECK(stabint_simulator_energy(sim, &before) == STABINT_OK);
  CHECK(stabint_simulator_release(sim, handle) == STABINT_OK);
  CHECK(stabint_simulator_energy(sim, &after) == STABINT_OK);
  CHECK(after.total < before.total);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(fabs(report.event_energy - (after.total - before.total)) <= 1e-12);
  CHECK(stabint_simulator_grab(sim, n, 1e4, &handle) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "vertex") != NULL);
  CHECK(stabint_simulator_grab(sim, 0, -1.0, &handle) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_grab(sim, 0, 1.0, NULL) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_release(sim, 3) == STABINT_INVALID_INPUT);
  free(x);
  stabint_simulator_destroy(sim);
}

/* Stiffen springs and disable one: each change books its energy jump as an event; bad kinds,
 * indices and stiffnesses are INVALID_INPUT and change nothing. */
static void test_element_changes(void) {
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  const int springs[3] = {0, 1, 2};
  const int bad[2] = {0, 100000};
  stabint_energy e0, e1, e2;
  stabint_step_report report;
  double target0;
  int i;
  for (i = 0; i < 5; ++i) CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  CHECK(stabint_simulator_energy(sim, &e0) == STABINT_OK);
  target0 = stabint_simulator_target(sim);
  CHECK(stabint_simulator_set_element_stiffness(sim, "springs", springs, 3, 5e3) == STABINT_OK);
  CHECK(stabint_simulator_set_element_enabled(sim, "spring", springs + 2, 1, 0) == STABINT_OK);
  CHECK(stabint_simulator_energy(sim, &e1) == STABINT_OK);
  CHECK(e1.total != e0.total);
  /* H* moved by the jump: round-off of sums of energies of about 1 J. */
  CHECK(fabs((stabint_simulator_target(sim) - target0) - (e1.total - e0.total)) <= 1e-12);
  CHECK(stabint_simulator_set_element_stiffness(sim, "colliders", springs, 1, 1.0) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "unknown element kind") != NULL);
  CHECK(stabint_simulator_set_element_stiffness(sim, "springs", bad, 2, 1.0) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "spring 100000 out of range") != NULL);
  CHECK(stabint_simulator_set_element_stiffness(sim, "springs", springs, 1, -2.0) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_set_element_enabled(sim, "tets", springs, 1, 0) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_set_element_enabled(sim, "springs", NULL, 1, 0) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_set_element_stiffness(sim, NULL, springs, 1, 1.0) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_energy(sim, &e2) == STABINT_OK);
  CHECK(e2.total == e1.total);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(fabs(report.event_energy - (e1.total - e0.total)) <= 1e-12);
  stabint_simulator_destroy(sim);
}

static void test_checkpoints_continue_bit_for_bit(void) {
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  stabint_simulator* other = small_cloth(STABINT_ENERGY_BLEND);
  stabint_simulator* chain = NULL;
  stabint_scene* chain_scene = NULL;
  stabint_simulator_options options;
  stabint_checkpoint *ckpt = NULL, *loaded = NULL, *copy = NULL;
  const int n = stabint_simulator_num_particles(sim);
  const size_t bytes = 3 * (size_t)n * sizeof(double);
  double* original = new_rows(n);
  double* again = new_rows(n);
  double target, time, corner[3];
  const void *data, *loaded_data;
  size_t size = 0, loaded_size = 0;
  char path[1024];
  const char* tmp = getenv("TMPDIR");
  int fd;
  FILE* file;

  CHECK(stabint_simulator_pin_target(sim, 0, corner) == STABINT_OK);
  drive(sim, corner, 12, again);
  CHECK(stabint_simulator_checkpoint(sim, &ckpt) == STABINT_OK);
  CHECK(stabint_checkpoint_step_count(ckpt) == 12);
  CHECK(stabint_checkpoint_time(ckpt) == stabint_simulator_time(sim));
  target = stabint_simulator_target(sim);
  time = stabint_simulator_time(sim);
  drive(sim, corner, 20, original);

  CHECK(stabint_simulator_restore(sim, ckpt) == STABINT_OK);
  CHECK(stabint_simulator_step_count(sim) == 12);
  CHECK(stabint_simulator_time(sim) == time);
  CHECK(stabint_simulator_target(sim) == target);
  drive(sim, corner, 20, again);
  CHECK(memcmp(again, original, bytes) == 0);

  CHECK(stabint_simulator_restore(other, ckpt) == STABINT_OK);
  drive(other, corner, 20, again);
  CHECK(memcmp(again, original, bytes) == 0);

  /* In memory: the bytes make an equal checkpoint. */
  data = stabint_checkpoint_data(ckpt, &size);
  CHECK(data != NULL && size > 0);
  CHECK(stabint_checkpoint_from_bytes(data, size, &copy) == STABINT_OK);
  CHECK(stabint_checkpoint_step_count(copy) == 12);
  CHECK(stabint_simulator_restore(other, copy) == STABINT_OK);
  drive(other, corner, 20, again);
  CHECK(memcmp(again, original, bytes) == 0);
  CHECK(stabint_checkpoint_from_bytes("not a checkpoint", 16, &loaded) == STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), "wrong header") != NULL);
  CHECK(stabint_checkpoint_from_bytes(data, size - 1, &loaded) == STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), "checksum") != NULL); /* a cut checkpoint fails its checksum */
  CHECK(loaded == NULL);

  /* Through a file in a fresh temporary path. */
  if (tmp == NULL || tmp[0] == '\0') tmp = "/tmp";
  snprintf(path, sizeof path, "%s/stabint_c_api_XXXXXX", tmp);
  fd = mkstemp(path);
  CHECK(fd >= 0);
  if (fd >= 0) close(fd);
  CHECK(stabint_checkpoint_save(ckpt, path) == STABINT_OK);
  CHECK(stabint_checkpoint_load(path, &loaded) == STABINT_OK);
  loaded_data = stabint_checkpoint_data(loaded, &loaded_size);
  CHECK(loaded_size == size && memcmp(loaded_data, data, size) == 0);
  CHECK(stabint_checkpoint_time(loaded) == time);
  CHECK(stabint_checkpoint_step_count(loaded) == 12);
  stabint_simulator_destroy(other);
  other = small_cloth(STABINT_ENERGY_BLEND);
  CHECK(stabint_simulator_restore(other, loaded) == STABINT_OK);
  drive(other, corner, 20, again);
  CHECK(memcmp(again, original, bytes) == 0);
  /* The same file cut short is malformed, and names its path. */
  file = fopen(path, "wb");
  CHECK(file != NULL);
  if (file != NULL) {
    fwrite(data, 1, size / 2, file);
    fclose(file);
  }
  stabint_checkpoint_destroy(loaded);
  loaded = NULL;
  CHECK(stabint_checkpoint_load(path, &loaded) == STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), path) != NULL);
  CHECK(loaded == NULL);
  remove(path);
  CHECK(stabint_checkpoint_load(path, &loaded) == STABINT_FILE_FORMAT);
  CHECK(stabint_checkpoint_save(ckpt, "/nonexistent/dir/run.ckpt") == STABINT_FILE_FORMAT);
  CHECK(stabint_checkpoint_save(NULL, path) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_restore(sim, NULL) == STABINT_INVALID_ARGUMENT);

  /* Another scene's checkpoint: INVALID_INPUT, and the simulator keeps its step count. */
  CHECK(stabint_scene_create_builtin("chain", NULL, &chain_scene) == STABINT_OK);
  stabint_simulator_options_default(&options);
  CHECK(stabint_simulator_create(chain_scene, &options, &chain) == STABINT_OK);
  stabint_scene_destroy(chain_scene);
  CHECK(stabint_simulator_restore(chain, ckpt) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "another scene") != NULL);
  CHECK(stabint_simulator_step_count(chain) == 0);

  CHECK(stabint_checkpoint_time(NULL) != stabint_checkpoint_time(NULL)); /* NaN */
  CHECK(stabint_checkpoint_step_count(NULL) == -1);
  CHECK(stabint_checkpoint_data(NULL, &size) == NULL && size == 0);
  stabint_checkpoint_destroy(NULL);
  stabint_checkpoint_destroy(ckpt);
  stabint_checkpoint_destroy(copy);
  stabint_simulator_destroy(chain);
  stabint_simulator_destroy(sim);
  stabint_simulator_destroy(other);
  free(original);
  free(again);
}

/* Colliders come from scene files; the report books what they do. A 6 x 5 cloth hangs through a
 * sphere (friction 0.5) that cuts 5 cm into it: pushed out, it slides along the sphere. With the
 * blend and static pins, H* moves by exactly the reported friction and projection (round-off of
 * 30 terms of size up to H0). contact_tolerance reaches the simulator and is checked. */
static void test_colliders_from_a_scene_file(void) {
  const char* tmp = getenv("TMPDIR");
  char path[1024];
  FILE* file;
  int fd, f;
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_step_report report;
  stabint_energy start;
  double friction = 0.0, projection = 0.0;
  if (tmp == NULL || tmp[0] == '\0') tmp = "/tmp";
  snprintf(path, sizeof path, "%s/stabint_c_api_XXXXXX", tmp);
  fd = mkstemp(path);
  CHECK(fd >= 0);
  if (fd < 0) return;
  file = fdopen(fd, "w");
  CHECK(file != NULL);
  if (file == NULL) return;
  fputs(
      "{\"builtin\": {\"name\": \"cloth\", \"nx\": 6, \"ny\": 5},\n"
      " \"colliders\": [{\"shape\": \"sphere\", \"center\": [0.5, 0.5, 0.1], \"radius\": 0.15, "
      "\"friction\": 0.5}]}\n",
      file);
  fclose(file);
  CHECK(stabint_scene_load(path, &scene) == STABINT_OK);
  unlink(path);

  stabint_simulator_options_default(&options);
  CHECK(options.contact_tolerance == 1e-2); /* the C++ default */
  options.contact_tolerance = -1.0;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "contact_tolerance") != NULL);
  options.contact_tolerance = 0.02;
  /* The global solve's options reach the simulator and are checked too. */
  CHECK(options.global_solve == STABINT_GLOBAL_SOLVE_FACTOR && options.cg_iterations == 20);
  options.global_solve = (stabint_global_solve)5;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "global_solve") != NULL);
  options.global_solve = STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT;
  options.cg_iterations = 0;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "cg_iterations") != NULL);
  options.global_solve = STABINT_GLOBAL_SOLVE_FACTOR;
  options.cg_iterations = 20;
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  stabint_scene_destroy(scene);
  if (sim == NULL) return;
  CHECK(stabint_simulator_energy(sim, &start) == STABINT_OK);
  for (f = 0; f < 30; ++f) {
    CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
    CHECK(report.contact_projection <= 0.0);
    friction += report.friction;
    projection += report.contact_projection;
  }
  CHECK(friction > 0.0);
  CHECK(fabs(stabint_simulator_target(sim) - (start.total - friction + projection)) <= 1e-12 * 30 * fabs(start.total));
  stabint_simulator_destroy(sim);
}

/* A collider moved every frame (scenes/cloth_poke.json's sphere, behind the hanging cloth) is
 * where it was told at each step's end, pushes the cloth with its work booked (forcing > 0), and
 * bad input changes nothing. */
static void test_collider_moved_every_frame(const char* scene_dir) {
  char path[1024];
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_step_report report;
  double p[3], q[3], forcing = 0.0;
  const double bad[3] = {0.0, NAN, 0.0};
  int f, k;
  snprintf(path, sizeof path, "%s/cloth_poke.json", scene_dir);
  CHECK(stabint_scene_load(path, &scene) == STABINT_OK);
  if (scene == NULL) return;
  stabint_simulator_options_default(&options);
  CHECK(stabint_simulator_create(scene, &options, &sim) == STABINT_OK);
  stabint_scene_destroy(scene);
  if (sim == NULL) return;
  CHECK(stabint_simulator_collider_position(sim, 0, p) == STABINT_OK);
  CHECK(p[0] == 0.5 && p[1] == 0.5 && p[2] == -0.4);
  for (f = 1; f <= 30; ++f) {
    /* 1.5 cm a frame toward and into the cloth at z = 0 (the sphere's radius is 0.15 m). */
    q[0] = 0.5, q[1] = 0.5, q[2] = -0.4 + 0.015 * f;
    CHECK(stabint_simulator_set_collider_position(sim, 0, q) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
    forcing += report.forcing;
    CHECK(stabint_simulator_collider_position(sim, 0, p) == STABINT_OK);
    for (k = 0; k < 3; ++k) CHECK(p[k] == q[k]);
  }
  CHECK(forcing > 0.0);
  CHECK(stabint_simulator_set_collider_position(sim, 1, q) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "collider 1 out of range") != NULL);
  CHECK(stabint_simulator_set_collider_position(sim, 0, bad) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_set_collider_velocity(sim, 0, bad) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_set_collider_velocity(sim, 0, NULL) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_collider_position(sim, -1, p) == STABINT_INVALID_INPUT);
  q[0] = 0.0, q[1] = 0.0, q[2] = 0.6;
  CHECK(stabint_simulator_set_collider_velocity(sim, 0, q) == STABINT_OK);
  CHECK(stabint_simulator_step(sim, &report) == STABINT_OK);
  CHECK(stabint_simulator_collider_position(sim, 0, p) == STABINT_OK);
  CHECK(fabs(p[2] - (0.05 + 0.6 * options.time_step)) <= 1e-15);
  stabint_simulator_destroy(sim);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s SCENE_DIR\n", argv[0]);
    return 2;
  }
  test_defaults_and_names();
  test_options_read_back();
  test_bad_options_are_reported();
  test_blow_up_is_reported();
  test_buffers_and_triangles();
  test_files(argv[1]);
  test_blend_tracks_target_on_chain();
  test_pin_target_set_every_frame_moves_the_pin();
  test_bad_input_is_rejected_and_changes_nothing();
  test_state_forces_and_iterations();
  test_checkpoints_continue_bit_for_bit();
  test_grab_and_release();
  test_colliders_from_a_scene_file();
  test_collider_moved_every_frame(argv[1]);
  test_element_changes();
  printf("%d passed, %d failed\n", passed, failed);
  return failed == 0 ? 0 : 1;
}
