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

/* A fresh empty temporary file under $TMPDIR (or /tmp), its path into `path`; returns its file
 * descriptor, -1 (and a failed check) when none could be made. */
static int temp_file(char* path, size_t size) {
  const char* tmp = getenv("TMPDIR");
  int fd;
  if (tmp == NULL || tmp[0] == '\0') tmp = "/tmp";
  snprintf(path, size, "%s/stabint_c_api_XXXXXX", tmp);
  fd = mkstemp(path);
  CHECK(fd >= 0);
  return fd;
}

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
  fd = temp_file(path, sizeof path);
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
 * sphere (friction 0.5) that cuts 5 cm into it: pushed out by a soft contact (elastic_ratio 0: the
 * per-mass weight alone; the default would throw the cloth off in one step), it slides along it. With the
 * blend and static pins, H* moves by exactly the reported friction and projection (round-off of
 * 30 terms of size up to H0). contact_tolerance reaches the simulator and is checked. */
static void test_colliders_from_a_scene_file(void) {
  char path[1024];
  FILE* file;
  int fd, f;
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  stabint_step_report report;
  stabint_energy start;
  double friction = 0.0, projection = 0.0;
  fd = temp_file(path, sizeof path);
  if (fd < 0) return;
  file = fdopen(fd, "w");
  CHECK(file != NULL);
  if (file == NULL) return;
  fputs(
      "{\"builtin\": {\"name\": \"cloth\", \"nx\": 6, \"ny\": 5},\n"
      " \"colliders\": [{\"shape\": \"sphere\", \"center\": [0.5, 0.5, 0.1], \"radius\": 0.15, "
      "\"friction\": 0.5, \"elastic_ratio\": 0}]}\n",
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

/* ---- batches ---- */

static stabint_scene* builtin(const char* name, const char* params) {
  stabint_scene* scene = NULL;
  CHECK(stabint_scene_create_builtin(name, params, &scene) == STABINT_OK);
  return scene;
}

static const char* const kSmallCloth = "{\"nx\": 6, \"ny\": 5}";

static double max_abs_diff(const double* a, const double* b, size_t count) {
  double d = 0.0;
  size_t i;
  for (i = 0; i < count; ++i)
    if (fabs(a[i] - b[i]) > d) d = fabs(a[i] - b[i]);
  return d;
}

/* The diagonal of the bounding box of `n` particles (x y z each): a scene's size, the unit of the
 * batch tests' state tolerance (tests/batch_scenes.hpp, test_scene_batch.cpp). */
static double extent(const double* x, int n) {
  double lo[3], hi[3], d = 0.0;
  int i, k;
  for (k = 0; k < 3; ++k) lo[k] = hi[k] = x[k];
  for (i = 1; i < n; ++i) {
    for (k = 0; k < 3; ++k) {
      if (x[3 * i + k] < lo[k]) lo[k] = x[3 * i + k];
      if (x[3 * i + k] > hi[k]) hi[k] = x[3 * i + k];
    }
  }
  for (k = 0; k < 3; ++k) d += (hi[k] - lo[k]) * (hi[k] - lo[k]);
  return sqrt(d);
}

/* A batch of the scenes `scenes[0..count)`; NULL (and a failed check) when refused. */
static stabint_batch* batch_of(stabint_scene* const* scenes, int count, const stabint_simulator_options* options) {
  const stabint_scene* list[4];
  stabint_batch* batch = NULL;
  int s;
  for (s = 0; s < count; ++s) list[s] = scenes[s];
  CHECK(stabint_batch_create(list, count, options, &batch) == STABINT_OK);
  return batch;
}

/* Scene s of `batch` against the simulator `sim`: |x - x_own| within `tolerance` (0: bit for bit,
 * positions and velocities); returns the largest position difference. */
static double batch_scene_vs_simulator(const stabint_batch* batch, int s, const stabint_simulator* sim,
                                       double tolerance) {
  const int n = stabint_simulator_num_particles(sim);
  const size_t count = 3 * (size_t)n;
  double *x = new_rows(n), *y = new_rows(n), d;
  CHECK(stabint_batch_num_particles(batch, s) == n);
  CHECK(stabint_batch_copy_positions(batch, s, x, count) == STABINT_OK);
  CHECK(stabint_simulator_copy_positions(sim, y, count) == STABINT_OK);
  d = max_abs_diff(x, y, count);
  CHECK(tolerance > 0.0 ? d <= tolerance : memcmp(x, y, count * sizeof(double)) == 0);
  if (tolerance == 0.0) {
    CHECK(stabint_batch_copy_velocities(batch, s, x, count) == STABINT_OK);
    CHECK(stabint_simulator_copy_velocities(sim, y, count) == STABINT_OK);
    CHECK(memcmp(x, y, count * sizeof(double)) == 0);
  }
  free(x);
  free(y);
  return d;
}

/* The chain and the 6 x 5 cloth, scenes `first` to `first + count - 1` of that list, stepped
 * `steps` times as one batch and each by its own simulator. Every scene's reports and state are
 * its simulator's: bit for bit where `exact` (a batch of one on the CPU reference,
 * tests/test_batch_of_one.cpp; and explicit SE with several scenes, whose per-vertex sums add each
 * scene's terms in its own order, test_scene_batch.cpp); else, as test_scene_batch.cpp asserts,
 * the state to 1e-9 of the scene's size and the energies and H* to 1e-12 of its E_scale: the
 * factor of the block-diagonal matrix may order a block otherwise than the scene's own factor, so
 * only round-off agreement (about eps times the conditioning per solve) is guaranteed, and 1e-9 is
 * far above it and far below any coupling between the scenes. */
static void compare_batch_with_simulators(const stabint_simulator_options* options, int first, int count, int steps,
                                          int exact) {
  stabint_scene* scenes[2];
  stabint_simulator* alone[2];
  stabint_step_report reports[2], own;
  stabint_batch* batch;
  double* start[2];
  int s, step, total = 0;
  scenes[0] = builtin(first == 0 ? "chain" : "cloth", first == 0 ? NULL : kSmallCloth);
  scenes[1] = builtin("cloth", kSmallCloth);
  batch = batch_of(scenes, count, options);
  if (batch == NULL) return;
  CHECK(stabint_batch_size(batch) == count);
  for (s = 0; s < count; ++s) {
    const int n = stabint_scene_num_particles(scenes[s]);
    CHECK(stabint_simulator_create(scenes[s], options, &alone[s]) == STABINT_OK);
    CHECK(stabint_batch_first_particle(batch, s) == total);
    CHECK(stabint_batch_energy_scale(batch, s) == stabint_simulator_energy_scale(alone[s]));
    start[s] = new_rows(n);
    CHECK(stabint_simulator_copy_positions(alone[s], start[s], 3 * (size_t)n) == STABINT_OK);
    total += n;
  }
  for (s = 0; s < 2; ++s) stabint_scene_destroy(scenes[s]); /* the batch holds its own copies */
  for (step = 0; step < steps; ++step) {
    CHECK(stabint_batch_step(batch, reports, (size_t)count) == STABINT_OK);
    for (s = 0; s < count; ++s) {
      const double tol = exact ? 0.0 : 1e-12 * stabint_simulator_energy_scale(alone[s]);
      CHECK(stabint_simulator_step(alone[s], &own) == STABINT_OK);
      CHECK(reports[s].step == own.step && reports[s].time == own.time && reports[s].branch == own.branch);
      CHECK(fabs(reports[s].target - own.target) <= tol);
      CHECK(fabs(reports[s].energy.total - own.energy.total) <= tol);
      CHECK(stabint_batch_active(batch, s) == 1);
    }
  }
  for (s = 0; s < count; ++s) {
    const int n = stabint_simulator_num_particles(alone[s]);
    double* x = new_rows(n);
    const double size = extent(start[s], n);
    const double d = batch_scene_vs_simulator(batch, s, alone[s], exact ? 0.0 : 1e-9 * size);
    CHECK(stabint_batch_copy_positions(batch, s, x, 3 * (size_t)n) == STABINT_OK);
    CHECK(max_abs_diff(x, start[s], 3 * (size_t)n) > 1e-6); /* it moved: not two resting states */
    CHECK(stabint_batch_step_count(batch, s) == steps);
    CHECK(stabint_batch_scene_time(batch, s) == stabint_simulator_time(alone[s]));
    printf("batch of %d (%s), scene %d: max |x - x_own| = %.3g m (size %.3g m)\n", count,
           stabint_integrator_name(options->integrator), s, d, size);
    free(x);
    free(start[s]);
    stabint_simulator_destroy(alone[s]);
  }
  CHECK(stabint_batch_time(batch) == stabint_batch_scene_time(batch, 0));
  stabint_batch_destroy(batch);
}

static void test_batch_steps_as_its_scenes_simulators(void) {
  stabint_simulator_options options;
  stabint_simulator_options_default(&options);
  compare_batch_with_simulators(&options, 1, 1, 20, 1); /* a batch of one: the blend, bit for bit */
  compare_batch_with_simulators(&options, 0, 2, 20, 0); /* chain and cloth: round-off */
  options.integrator = STABINT_SYMPLECTIC_EULER;        /* explicit: bit for bit */
  options.time_step = 1e-4;
  compare_batch_with_simulators(&options, 0, 2, 20, 1);
}

/* The chain and the 6 x 5 cloth with the default options. */
static stabint_batch* chain_and_cloth(void) {
  stabint_scene* scenes[2];
  stabint_simulator_options options;
  stabint_batch* batch;
  scenes[0] = builtin("chain", NULL);
  scenes[1] = builtin("cloth", kSmallCloth);
  stabint_simulator_options_default(&options);
  batch = batch_of(scenes, 2, &options);
  stabint_scene_destroy(scenes[0]);
  stabint_scene_destroy(scenes[1]);
  return batch;
}

/* The whole batch's positions are every scene's, one after another. */
static void test_batch_all_positions(void) {
  stabint_batch* batch = chain_and_cloth();
  double *all, *x;
  float* xf;
  int n0, n1, i, agree = 1;
  if (batch == NULL) return;
  CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
  n0 = stabint_batch_num_particles(batch, 0);
  n1 = stabint_batch_num_particles(batch, 1);
  CHECK(stabint_batch_first_particle(batch, 1) == n0);
  all = new_rows(n0 + n1);
  x = new_rows(n1);
  xf = (float*)malloc(3 * (size_t)(n0 + n1) * sizeof(float));
  CHECK(stabint_batch_copy_all_positions(batch, all, 3 * (size_t)(n0 + n1)) == STABINT_OK);
  CHECK(stabint_batch_copy_all_positions(batch, all, 3 * (size_t)(n0 + n1) - 1) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_batch_copy_all_positions_float(batch, xf, 3 * (size_t)(n0 + n1)) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(batch, 1, x, 3 * (size_t)n1) == STABINT_OK);
  CHECK(memcmp(all + 3 * n0, x, 3 * (size_t)n1 * sizeof(double)) == 0);
  /* float rounding of coordinates of order 1 m: relative 6e-8, so 1e-6 m is ample. */
  for (i = 0; i < 3 * (n0 + n1); ++i) agree = agree && fabs((double)xf[i] - all[i]) < 1e-6;
  CHECK(agree);
  CHECK(stabint_batch_copy_positions_float(batch, 1, xf, 3 * (size_t)n1) == STABINT_OK);
  for (i = 0; i < 3 * n1; ++i) agree = agree && fabs((double)xf[i] - x[i]) < 1e-6;
  CHECK(agree);
  free(all);
  free(x);
  free(xf);
  stabint_batch_destroy(batch);
}

/* Steps a frame of the drive() inputs (pin 0 dragged, a force on particle 0), functions of time
 * only, given to scene 1 of `batch` and to `sim` (unless NULL); scene 0 gets none. */
static void drive_scene_one(stabint_batch* batch, stabint_simulator* sim, const double corner[3], int n) {
  double* f = new_rows(n);
  double q[3];
  const double t1 = stabint_batch_time(batch) + 1.0 / 30.0;
  q[0] = corner[0] + 0.1 * sin(3.0 * t1);
  q[1] = corner[1];
  q[2] = corner[2] + 0.05 * t1;
  f[2] = 0.5 * cos(5.0 * t1);
  CHECK(stabint_batch_set_pin_target(batch, 1, 0, q) == STABINT_OK);
  CHECK(stabint_batch_set_external_forces(batch, 1, f, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
  if (sim != NULL) {
    CHECK(stabint_simulator_set_pin_target(sim, 0, q) == STABINT_OK);
    CHECK(stabint_simulator_set_external_forces(sim, f, 3 * (size_t)n) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  }
  free(f);
}

/* Two equal cloths; scene 1 is dragged, pushed, grabbed, released and stiffened, scene 0 is left
 * alone. Each follows its own simulator given the same input (to 1e-9 of its size: the batch
 * tests' round-off standard, here also after the factor's rank updates), and the two scenes end
 * centimetres apart: the input reached its scene only. */
static void test_batch_input_acts_on_its_scene(void) {
  stabint_scene* scenes[2];
  stabint_simulator_options options;
  stabint_simulator *still = small_cloth(STABINT_ENERGY_BLEND), *moved = small_cloth(STABINT_ENERGY_BLEND);
  const int n = stabint_simulator_num_particles(still);
  const int springs[3] = {0, 1, 2};
  double corner[3], q0[3], back[3], size;
  double *x0 = new_rows(n), *x1 = new_rows(n);
  stabint_batch* batch;
  int f, handle = -1, own_handle = -1;
  scenes[0] = builtin("cloth", kSmallCloth);
  scenes[1] = scenes[0];
  stabint_simulator_options_default(&options);
  options.integrator = STABINT_ENERGY_BLEND;
  batch = batch_of(scenes, 2, &options);
  stabint_scene_destroy(scenes[0]);
  if (batch == NULL) return;
  CHECK(stabint_batch_copy_positions(batch, 0, x0, 3 * (size_t)n) == STABINT_OK);
  size = extent(x0, n);
  CHECK(stabint_batch_pin_target(batch, 1, 0, corner) == STABINT_OK);
  CHECK(stabint_batch_pin_target(batch, 0, 0, q0) == STABINT_OK);
  for (f = 0; f < 30; ++f) {
    if (f == 5) {
      CHECK(stabint_batch_grab(batch, 1, n - 6, 1e4, &handle) == STABINT_OK);
      CHECK(stabint_simulator_grab(moved, n - 6, 1e4, &own_handle) == STABINT_OK);
      CHECK(handle == 2 && own_handle == 2);
    }
    if (f == 10) {
      CHECK(stabint_batch_set_element_stiffness(batch, 1, "springs", springs, 3, 5e3) == STABINT_OK);
      CHECK(stabint_batch_set_element_enabled(batch, 1, "spring", springs + 2, 1, 0) == STABINT_OK);
      CHECK(stabint_simulator_set_element_stiffness(moved, "springs", springs, 3, 5e3) == STABINT_OK);
      CHECK(stabint_simulator_set_element_enabled(moved, "spring", springs + 2, 1, 0) == STABINT_OK);
    }
    if (f == 15) {
      CHECK(stabint_batch_release(batch, 1, handle) == STABINT_OK);
      CHECK(stabint_simulator_release(moved, own_handle) == STABINT_OK);
    }
    drive_scene_one(batch, moved, corner, n);
    CHECK(stabint_simulator_step(still, NULL) == STABINT_OK);
  }
  CHECK(stabint_batch_pin_target(batch, 1, 0, back) == STABINT_OK);
  CHECK(stabint_simulator_pin_target(moved, 0, corner) == STABINT_OK);
  CHECK(memcmp(back, corner, sizeof back) == 0);
  CHECK(stabint_batch_pin_target(batch, 0, 0, back) == STABINT_OK);
  CHECK(memcmp(back, q0, sizeof back) == 0);
  batch_scene_vs_simulator(batch, 0, still, 1e-9 * size);
  batch_scene_vs_simulator(batch, 1, moved, 1e-9 * size);
  CHECK(fabs(stabint_batch_target(batch, 0) - stabint_simulator_target(still)) <=
        1e-12 * stabint_simulator_energy_scale(still));
  CHECK(fabs(stabint_batch_target(batch, 1) - stabint_simulator_target(moved)) <=
        1e-12 * stabint_simulator_energy_scale(moved));
  CHECK(stabint_batch_copy_positions(batch, 0, x0, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(batch, 1, x1, 3 * (size_t)n) == STABINT_OK);
  printf("batch input on scene 1 only: scenes 0 and 1 end %.3g m apart\n", max_abs_diff(x0, x1, 3 * (size_t)n));
  CHECK(max_abs_diff(x0, x1, 3 * (size_t)n) > 1e-2);
  free(x0);
  free(x1);
  stabint_simulator_destroy(still);
  stabint_simulator_destroy(moved);
  stabint_batch_destroy(batch);
}

/* A collider moved every frame acts in its scene and reads back as set; the other scene, a cloth
 * without colliders, has none to move. */
static void test_batch_collider_moved_every_frame(const char* scene_dir) {
  char path[1024];
  stabint_scene* scenes[2] = {NULL, NULL};
  stabint_simulator_options options;
  stabint_simulator* own = NULL;
  stabint_batch* batch;
  double p[3], q[3], size, *x;
  int f, n;
  snprintf(path, sizeof path, "%s/cloth_poke.json", scene_dir);
  CHECK(stabint_scene_load(path, &scenes[0]) == STABINT_OK);
  if (scenes[0] == NULL) return;
  scenes[1] = builtin("cloth", kSmallCloth);
  stabint_simulator_options_default(&options);
  batch = batch_of(scenes, 2, &options);
  CHECK(stabint_simulator_create(scenes[0], &options, &own) == STABINT_OK);
  stabint_scene_destroy(scenes[0]);
  stabint_scene_destroy(scenes[1]);
  if (batch == NULL || own == NULL) return;
  n = stabint_batch_num_particles(batch, 0);
  x = new_rows(n);
  CHECK(stabint_batch_copy_positions(batch, 0, x, 3 * (size_t)n) == STABINT_OK);
  size = extent(x, n);
  for (f = 1; f <= 30; ++f) {
    q[0] = 0.5, q[1] = 0.5, q[2] = -0.4 + 0.015 * f; /* as test_collider_moved_every_frame */
    CHECK(stabint_batch_set_collider_position(batch, 0, 0, q) == STABINT_OK);
    CHECK(stabint_simulator_set_collider_position(own, 0, q) == STABINT_OK);
    CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
    CHECK(stabint_simulator_step(own, NULL) == STABINT_OK);
    CHECK(stabint_batch_collider_position(batch, 0, 0, p) == STABINT_OK);
    CHECK(memcmp(p, q, sizeof p) == 0);
  }
  batch_scene_vs_simulator(batch, 0, own, 1e-9 * size);
  CHECK(stabint_batch_set_collider_position(batch, 1, 0, q) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "setColliderPosition: scene 1: collider 0 out of range") != NULL);
  CHECK(stabint_batch_set_collider_velocity(batch, 0, 0, NULL) == STABINT_INVALID_ARGUMENT);
  CHECK(strstr(stabint_last_error_message(), "velocity is NULL") != NULL);
  q[0] = 0.0, q[1] = 0.0, q[2] = 0.6;
  CHECK(stabint_batch_set_collider_velocity(batch, 0, 0, q) == STABINT_OK);
  CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
  CHECK(stabint_batch_collider_position(batch, 0, 0, p) == STABINT_OK);
  CHECK(fabs(p[2] - (0.05 + 0.6 * options.time_step)) <= 1e-15);
  free(x);
  stabint_simulator_destroy(own);
  stabint_batch_destroy(batch);
}

/* `status` is `expected` and the last error's message has `text`. */
static void check_refused(stabint_status status, stabint_status expected, const char* text) {
  CHECK(status == expected);
  if (strstr(stabint_last_error_message(), text) == NULL) {
    ++failed;
    fprintf(stderr, "expected a message with \"%s\", got \"%s\"\n", text, stabint_last_error_message());
  }
}

/* Bad arguments: C misuse (NULL, short buffers, wrong array sizes, a bad scene count) is
 * INVALID_ARGUMENT naming the argument; a scene or index out of range or a value the library
 * refuses is INVALID_INPUT naming the call and the scene. None changes the batch, which then steps
 * bit for bit as an untouched twin. */
/* set_states of scenes 1 and 0 is set_state of scene 1, then of scene 0: the same states and
 * targets bit for bit, and the same steps after them. */
static void test_batch_set_states_is_set_state_one_by_one(void) {
  stabint_batch* together = chain_and_cloth();
  stabint_batch* apart = chain_and_cloth();
  const int n0 = stabint_batch_num_particles(together, 0), n1 = stabint_batch_num_particles(together, 1);
  const size_t c0 = 3 * (size_t)n0, c1 = 3 * (size_t)n1;
  const int scenes[2] = {1, 0};
  double* x = malloc((c0 + c1) * sizeof(double));
  double* v = malloc((c0 + c1) * sizeof(double));
  double *a = new_rows(n1), *b = new_rows(n1);
  int s, step;
  CHECK(x != NULL && v != NULL);
  CHECK(stabint_batch_step(together, NULL, 0) == STABINT_OK && stabint_batch_step(apart, NULL, 0) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(together, 1, x, c1) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(together, 0, x + c1, c0) == STABINT_OK);
  for (s = 0; s < (int)(c0 + c1); ++s) {
    x[s] += 0.01 * sin(0.7 * s);
    v[s] = 0.3 * cos(1.3 * s);
  }
  CHECK(stabint_batch_set_states(together, scenes, 2, x, v, c0 + c1) == STABINT_OK);
  CHECK(stabint_batch_set_state(apart, 1, x, v, c1) == STABINT_OK);
  CHECK(stabint_batch_set_state(apart, 0, x + c1, v + c1, c0) == STABINT_OK);
  for (step = 0; step < 3; ++step) {
    for (s = 0; s < 2; ++s) CHECK(stabint_batch_target(together, s) == stabint_batch_target(apart, s));
    CHECK(stabint_batch_copy_positions(together, 1, a, c1) == STABINT_OK);
    CHECK(stabint_batch_copy_positions(apart, 1, b, c1) == STABINT_OK);
    CHECK(memcmp(a, b, c1 * sizeof(double)) == 0);
    CHECK(stabint_batch_step(together, NULL, 0) == STABINT_OK && stabint_batch_step(apart, NULL, 0) == STABINT_OK);
  }
  free(x);
  free(v);
  free(a);
  free(b);
  stabint_batch_destroy(together);
  stabint_batch_destroy(apart);
}

static void test_batch_bad_input_is_rejected_and_changes_nothing(void) {
  stabint_batch* batch = chain_and_cloth();
  stabint_batch* twin = chain_and_cloth();
  stabint_batch* none = (stabint_batch*)&batch; /* a stale value: a failed create sets it to NULL */
  stabint_scene* cloth = builtin("cloth", kSmallCloth);
  const stabint_scene* list[2];
  stabint_simulator_options options;
  stabint_step_report reports[2];
  stabint_checkpoint* ckpt = NULL;
  stabint_energy energy;
  const int n = stabint_batch_num_particles(batch, 1), bad_springs[2] = {0, 100000};
  const size_t count = 3 * (size_t)n;
  double *x = new_rows(n), *y = new_rows(n), q[3] = {0.0, 0.0, 0.0};
  char text[8];
  int pin = -1, f, s;

  list[0] = cloth;
  list[1] = NULL;
  stabint_simulator_options_default(&options);
  check_refused(stabint_batch_create(list, 2, &options, &none), STABINT_INVALID_ARGUMENT, "scenes[1] is NULL");
  CHECK(none == NULL);
  check_refused(stabint_batch_create(NULL, 2, &options, &none), STABINT_INVALID_ARGUMENT, "scenes is NULL");
  check_refused(stabint_batch_create(list, 0, &options, &none), STABINT_INVALID_ARGUMENT, "count: 0 scenes");
  check_refused(stabint_batch_create(list, 1, NULL, &none), STABINT_INVALID_ARGUMENT, "options is NULL");
  check_refused(stabint_batch_create(list, 1, &options, NULL), STABINT_INVALID_ARGUMENT, "out is NULL");
  list[1] = cloth;
  options.time_step = -1.0;
  check_refused(stabint_batch_create(list, 2, &options, &none), STABINT_INVALID_INPUT, "time_step");
  stabint_simulator_options_default(&options);
  options.global_solve = STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT; /* per scene, each on its block */
  CHECK(stabint_batch_create(list, 2, &options, &none) == STABINT_OK);
  CHECK(none != NULL);
  stabint_batch_destroy(none);
  stabint_scene_destroy(cloth);

  CHECK(stabint_batch_step(batch, reports, 2) == STABINT_OK);
  CHECK(stabint_batch_step(twin, NULL, 0) == STABINT_OK);
  check_refused(stabint_batch_step(batch, reports, 1), STABINT_INVALID_ARGUMENT,
                "reports: buffer holds 1 values, 2 needed");
  check_refused(stabint_batch_step(batch, NULL, 2), STABINT_INVALID_ARGUMENT, "reports is NULL");
  check_refused(stabint_batch_step(NULL, NULL, 0), STABINT_INVALID_ARGUMENT, "batch is NULL");
  CHECK(stabint_batch_step_count(batch, 0) == 1 && stabint_batch_step_count(batch, 1) == 1); /* not stepped */

  /* Getters of plain values: -1 or NaN, with the last error naming the problem. */
  CHECK(stabint_batch_size(NULL) == -1);
  CHECK(stabint_batch_time(NULL) != stabint_batch_time(NULL)); /* NaN */
  CHECK(stabint_batch_num_particles(batch, 2) == -1);
  CHECK(strstr(stabint_last_error_message(), "numParticles: scene 2 out of range (the batch has 2 scenes)") != NULL);
  CHECK(stabint_batch_active(batch, -1) == -1);
  CHECK(strstr(stabint_last_error_message(), "active: scene -1 out of range") != NULL);
  CHECK(stabint_batch_first_particle(batch, 2) == -1);
  CHECK(stabint_batch_step_count(batch, 2) == -1);
  CHECK(stabint_batch_target(batch, 2) != stabint_batch_target(batch, 2));
  CHECK(stabint_batch_energy_scale(batch, -1) != stabint_batch_energy_scale(batch, -1));
  CHECK(stabint_batch_scene_time(batch, 3) != stabint_batch_scene_time(batch, 3));
  CHECK(stabint_batch_backend_description(NULL, text, sizeof text) == 0);
  CHECK(stabint_batch_backend_description(batch, NULL, 0) > 0);

  /* Copies: a scene out of range, a short buffer, NULL. */
  check_refused(stabint_batch_copy_positions(batch, 2, x, count), STABINT_INVALID_INPUT,
                "positions: scene 2 out of range");
  check_refused(stabint_batch_copy_velocities(batch, 1, x, count - 1), STABINT_INVALID_ARGUMENT, "needed");
  check_refused(stabint_batch_copy_positions_float(batch, 1, NULL, count), STABINT_INVALID_ARGUMENT, "out is NULL");
  check_refused(stabint_batch_energy(batch, 1, NULL), STABINT_INVALID_ARGUMENT, "out is NULL");
  check_refused(stabint_batch_energy(batch, 5, &energy), STABINT_INVALID_INPUT, "energy: scene 5 out of range");
  check_refused(stabint_batch_last_report(batch, 2, reports), STABINT_INVALID_INPUT, "scene 2 out of range");
  check_refused(stabint_batch_refusal(batch, -1, text, sizeof text, NULL), STABINT_INVALID_INPUT,
                "scene -1 out of range");
  check_refused(stabint_batch_get_options(batch, NULL), STABINT_INVALID_ARGUMENT, "out is NULL");

  /* Per-frame input: sizes (scene 1's, not scene 0's or the batch's), NULL, ranges, values. */
  check_refused(stabint_batch_set_external_forces(batch, 1, x, 3 * (size_t)stabint_batch_num_particles(batch, 0)),
                STABINT_INVALID_ARGUMENT, "forces: ");
  CHECK(strstr(stabint_last_error_message(), "expected (3 per particle)") != NULL);
  check_refused(stabint_batch_set_external_forces(batch, -1, x, count), STABINT_INVALID_INPUT,
                "setExternalForces: scene -1 out of range");
  check_refused(stabint_batch_set_state(batch, 1, x, NULL, count), STABINT_INVALID_ARGUMENT, "velocities is NULL");
  check_refused(stabint_batch_set_state(batch, 1, x, y, count + 3), STABINT_INVALID_ARGUMENT, "positions: ");
  check_refused(stabint_batch_set_state(batch, 2, x, y, count), STABINT_INVALID_INPUT,
                "setState: scene 2 out of range");
  CHECK(stabint_batch_copy_positions(batch, 1, x, count) == STABINT_OK);
  {
    /* set_states: the listed scenes' arrays one after another; a scene listed twice, a count that
     * is not the listed scenes', NULL scenes or a bad row in the second listed array are refused. */
    const int twice[2] = {1, 1}, scene_one[1] = {1};
    double* xx = malloc(2 * count * sizeof(double));
    double* yy = malloc(2 * count * sizeof(double));
    CHECK(xx != NULL && yy != NULL);
    memcpy(xx, x, count * sizeof(double));
    memcpy(xx + count, x, count * sizeof(double));
    memcpy(yy, y, count * sizeof(double));
    memcpy(yy + count, y, count * sizeof(double));
    check_refused(stabint_batch_set_states(batch, twice, 2, xx, yy, 2 * count), STABINT_INVALID_INPUT,
                  "setStates: scene 1: listed twice");
    check_refused(stabint_batch_set_states(batch, scene_one, 1, xx, yy, 2 * count), STABINT_INVALID_ARGUMENT,
                  "count is");
    check_refused(stabint_batch_set_states(batch, NULL, 1, xx, yy, count), STABINT_INVALID_ARGUMENT, "scenes is NULL");
    xx[count + 5] = NAN; /* in the second listed scene's array */
    check_refused(stabint_batch_set_states(batch, twice, 2, xx, yy, 2 * count), STABINT_INVALID_INPUT,
                  "setStates: scene 1: positions: row 1");
    free(xx);
    free(yy);
  }
  x[3 * 3 + 1] = NAN;
  check_refused(stabint_batch_set_state(batch, 1, x, y, count), STABINT_INVALID_INPUT, "row 3");
  CHECK(strstr(stabint_last_error_message(), "scene 1") != NULL);
  check_refused(stabint_batch_set_pin_target(batch, 1, 2, q), STABINT_INVALID_INPUT,
                "setPinTarget: scene 1: pin 2 out of range");
  check_refused(stabint_batch_set_pin_target(batch, 1, 0, NULL), STABINT_INVALID_ARGUMENT, "target is NULL");
  q[1] = NAN;
  check_refused(stabint_batch_set_pin_target(batch, 1, 0, q), STABINT_INVALID_INPUT, "scene 1: pin 0: target");
  check_refused(stabint_batch_pin_target(batch, 2, 0, q), STABINT_INVALID_INPUT, "pinTarget: scene 2 out of range");
  check_refused(stabint_batch_pin_target(batch, 1, 0, NULL), STABINT_INVALID_ARGUMENT, "out is NULL");
  check_refused(stabint_batch_collider_position(batch, 0, 0, q), STABINT_INVALID_INPUT,
                "colliderPosition: scene 0: collider 0 out of range");
  check_refused(stabint_batch_grab(batch, 1, n, 1e4, &pin), STABINT_INVALID_INPUT, "grab: scene 1: vertex");
  check_refused(stabint_batch_grab(batch, 1, 0, -1.0, &pin), STABINT_INVALID_INPUT, "grab: scene 1: stiffness");
  check_refused(stabint_batch_grab(batch, 1, 0, 1e4, NULL), STABINT_INVALID_ARGUMENT, "out_pin is NULL");
  CHECK(pin == -1);
  check_refused(stabint_batch_release(batch, 0, 4), STABINT_INVALID_INPUT, "release: scene 0: pin 4 out of range");
  check_refused(stabint_batch_set_element_stiffness(batch, 1, "springs", bad_springs, 2, 1.0), STABINT_INVALID_INPUT,
                "setElementStiffness: scene 1: spring 100000 out of range");
  check_refused(stabint_batch_set_element_stiffness(batch, 1, "colliders", bad_springs, 1, 1.0), STABINT_INVALID_INPUT,
                "unknown element kind");
  check_refused(stabint_batch_set_element_stiffness(batch, 1, NULL, bad_springs, 1, 1.0), STABINT_INVALID_ARGUMENT,
                "kind is NULL");
  check_refused(stabint_batch_set_element_enabled(batch, 1, "springs", NULL, 1, 0), STABINT_INVALID_ARGUMENT,
                "indices is NULL");
  check_refused(stabint_batch_set_element_enabled(batch, 0, "tets", bad_springs, 1, 0), STABINT_INVALID_INPUT,
                "setElementEnabled: scene 0: tet 0 out of range");
  check_refused(stabint_batch_scene_checkpoint(batch, 2, &ckpt), STABINT_INVALID_INPUT, "scene 2 out of range");
  CHECK(ckpt == NULL);
  check_refused(stabint_batch_scene_restore(batch, 0, NULL), STABINT_INVALID_ARGUMENT, "checkpoint is NULL");

  /* Nothing changed: the batch steps on as its twin, bit for bit. */
  for (f = 0; f < 5; ++f) {
    CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
    CHECK(stabint_batch_step(twin, NULL, 0) == STABINT_OK);
  }
  for (s = 0; s < 2; ++s) {
    const size_t m = 3 * (size_t)stabint_batch_num_particles(batch, s);
    CHECK(stabint_batch_copy_positions(batch, s, x, m) == STABINT_OK);
    CHECK(stabint_batch_copy_positions(twin, s, y, m) == STABINT_OK);
    CHECK(memcmp(x, y, m * sizeof(double)) == 0);
    CHECK(stabint_batch_target(batch, s) == stabint_batch_target(twin, s));
    CHECK(stabint_batch_step_count(batch, s) == 6);
  }
  stabint_batch_destroy(NULL);
  stabint_batch_destroy(batch);
  stabint_batch_destroy(twin);
  free(x);
  free(y);
}

/* SE explodes on the stiff chain's pin (tests/test_batch_input.cpp, BatchInputInactive): its step
 * is refused with the message its own simulator's step fails with, at the same step (SE in a
 * batch is its simulator bit for bit), while the batch's step succeeds and the soft chain steps
 * on; set_state restarts the refused scene. */
static void test_batch_refusal_leaves_the_other_scenes(void) {
  stabint_scene* scenes[2];
  stabint_simulator_options options;
  stabint_simulator *soft = NULL, *stiff = NULL;
  stabint_status own_status = STABINT_OK;
  stabint_step_report reports[2];
  stabint_batch* batch;
  char own_message[512], message[512], cut[8];
  size_t length = 0, cut_length = 0;
  double *kept, *x, *start;
  int f, n, refused_at = -1;
  scenes[0] = builtin("chain", "{\"stiffness\": 10, \"pin_stiffness\": 100}");
  scenes[1] = builtin("chain", "{\"particles\": 6}");
  stabint_simulator_options_default(&options);
  options.integrator = STABINT_SYMPLECTIC_EULER;
  options.time_step = 1e-3;
  options.energy_limit = 1.0;
  batch = batch_of(scenes, 2, &options);
  CHECK(stabint_simulator_create(scenes[0], &options, &soft) == STABINT_OK);
  CHECK(stabint_simulator_create(scenes[1], &options, &stiff) == STABINT_OK);
  stabint_scene_destroy(scenes[0]);
  stabint_scene_destroy(scenes[1]);
  if (batch == NULL || soft == NULL || stiff == NULL) return;
  n = stabint_batch_num_particles(batch, 1);
  start = new_rows(n);
  CHECK(stabint_batch_copy_positions(batch, 1, start, 3 * (size_t)n) == STABINT_OK);
  for (f = 0; f < 200 && own_status == STABINT_OK; ++f) own_status = stabint_simulator_step(stiff, NULL);
  CHECK(stabint_status_is(own_status, STABINT_NON_FINITE_STATE));
  snprintf(own_message, sizeof own_message, "%s", stabint_last_error_message());
  CHECK(stabint_batch_refusal(batch, 1, message, sizeof message, &length) == STABINT_OK);
  CHECK(length == 0 && message[0] == '\0'); /* before the first step */
  for (f = 0; f < 200 && refused_at < 0; ++f) {
    CHECK(stabint_batch_step(batch, reports, 2) == STABINT_OK);
    CHECK(stabint_simulator_step(soft, NULL) == STABINT_OK);
    if (stabint_batch_active(batch, 1) == 0) refused_at = f;
  }
  printf("stiff chain in a batch refused at step %d: %s\n", refused_at, own_message);
  CHECK(refused_at == stabint_simulator_step_count(stiff));
  CHECK(stabint_batch_step_count(batch, 1) == refused_at);
  CHECK(reports[1].step == refused_at); /* the refused scene's report: its kept state's step count */
  CHECK(stabint_batch_refusal(batch, 1, message, sizeof message, &length) == STABINT_OK);
  CHECK(length > 0 && length == strlen(message));
  CHECK(strstr(own_message, message) != NULL); /* "<class>: " + the C++ message */
  CHECK(stabint_batch_refusal(batch, 1, cut, sizeof cut, &cut_length) == STABINT_OK);
  CHECK(cut_length == length && strlen(cut) == sizeof cut - 1 && strncmp(cut, message, sizeof cut - 1) == 0);
  CHECK(stabint_batch_refusal(batch, 1, NULL, 0, &cut_length) == STABINT_OK && cut_length == length);
  CHECK(stabint_batch_refusal(batch, 0, message, sizeof message, &length) == STABINT_OK);
  CHECK(length == 0 && stabint_batch_active(batch, 0) == 1);

  /* The refused scene keeps its state while the other steps on as its own simulator. */
  kept = new_rows(n);
  x = new_rows(n);
  CHECK(stabint_batch_copy_positions(batch, 1, kept, 3 * (size_t)n) == STABINT_OK);
  for (f = 0; f < 10; ++f) {
    CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
    CHECK(stabint_simulator_step(soft, NULL) == STABINT_OK);
  }
  CHECK(stabint_batch_active(batch, 1) == 0);
  CHECK(stabint_batch_refusal(batch, 1, message, sizeof message, &length) == STABINT_OK && length > 0);
  CHECK(stabint_batch_copy_positions(batch, 1, x, 3 * (size_t)n) == STABINT_OK);
  CHECK(memcmp(x, kept, 3 * (size_t)n * sizeof(double)) == 0);
  CHECK(stabint_batch_step_count(batch, 1) == refused_at);
  batch_scene_vs_simulator(batch, 0, soft, 0.0);

  /* set_state to its start, at rest, restarts it (its first steps are accepted, as at the start). */
  memset(kept, 0, 3 * (size_t)n * sizeof(double));
  CHECK(stabint_batch_set_state(batch, 1, start, kept, 3 * (size_t)n) == STABINT_OK);
  CHECK(stabint_batch_active(batch, 1) == 1);
  CHECK(stabint_batch_step(batch, reports, 2) == STABINT_OK);
  CHECK(stabint_batch_refusal(batch, 1, message, sizeof message, &length) == STABINT_OK && length == 0);
  CHECK(reports[1].step == refused_at);
  free(kept);
  free(x);
  free(start);
  stabint_simulator_destroy(soft);
  stabint_simulator_destroy(stiff);
  stabint_batch_destroy(batch);
}

/* A scene's checkpoint is a simulator's: taken from a batch it restores into a simulator of the
 * scene, and a simulator's into the batch; restored into a batch whose scene went another way, it
 * brings the scene back. Continuations agree to 1e-9 of the cloth's size (the batch's factor
 * against the simulator's own: round-off, as above); a batch of the same scenes restored from it
 * continues bit for bit (the same factor). */
static void test_batch_checkpoints(void) {
  stabint_batch* batch = chain_and_cloth();
  stabint_batch* other = chain_and_cloth();
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  stabint_simulator* chain = NULL;
  stabint_scene* chain_scene = builtin("chain", NULL);
  stabint_simulator_options options;
  stabint_checkpoint *ckpt = NULL, *from_sim = NULL, *chain_ckpt = NULL;
  const int n = stabint_simulator_num_particles(sim);
  const size_t count = 3 * (size_t)n;
  double *x = new_rows(n), *y = new_rows(n), *f = new_rows(n), size;
  int i;
  stabint_simulator_options_default(&options);
  CHECK(stabint_simulator_create(chain_scene, &options, &chain) == STABINT_OK);
  stabint_scene_destroy(chain_scene);
  if (batch == NULL || other == NULL || chain == NULL) return;
  CHECK(stabint_batch_copy_positions(batch, 1, x, count) == STABINT_OK);
  size = extent(x, n);
  f[3 * (n - 6)] = 2.0; /* `other`'s cloth is pushed at a free corner: it goes another way */
  CHECK(stabint_batch_set_external_forces(other, 1, f, count) == STABINT_OK);
  for (i = 0; i < 10; ++i) {
    CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
    CHECK(stabint_batch_step(other, NULL, 0) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
    CHECK(stabint_simulator_step(chain, NULL) == STABINT_OK);
  }
  CHECK(stabint_batch_scene_checkpoint(batch, 1, &ckpt) == STABINT_OK);
  CHECK(stabint_checkpoint_step_count(ckpt) == 10);
  CHECK(stabint_checkpoint_time(ckpt) == stabint_batch_scene_time(batch, 1));
  CHECK(stabint_simulator_checkpoint(chain, &chain_ckpt) == STABINT_OK);

  /* Another scene's checkpoint is refused, naming the scene, and changes nothing. */
  check_refused(stabint_batch_scene_restore(other, 1, chain_ckpt), STABINT_INVALID_INPUT, "scene 1");
  CHECK(stabint_batch_copy_positions(batch, 1, x, count) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(other, 1, y, count) == STABINT_OK);
  CHECK(max_abs_diff(x, y, count) > 1e-3); /* pushed */
  CHECK(stabint_batch_scene_restore(other, 1, ckpt) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(other, 1, y, count) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(batch, 1, x, count) == STABINT_OK);
  CHECK(memcmp(x, y, count * sizeof(double)) == 0);
  CHECK(stabint_batch_target(other, 1) == stabint_batch_target(batch, 1));

  /* Into a simulator of the cloth; and the simulator's own into the chain scene of a batch. */
  CHECK(stabint_simulator_restore(sim, ckpt) == STABINT_OK);
  CHECK(stabint_simulator_step_count(sim) == 10);
  CHECK(stabint_batch_scene_restore(other, 0, chain_ckpt) == STABINT_OK);
  for (i = 0; i < 10; ++i) {
    CHECK(stabint_batch_step(batch, NULL, 0) == STABINT_OK);
    CHECK(stabint_batch_step(other, NULL, 0) == STABINT_OK);
    CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  }
  batch_scene_vs_simulator(batch, 1, sim, 1e-9 * size);
  CHECK(stabint_batch_copy_positions(other, 1, y, count) == STABINT_OK);
  CHECK(stabint_batch_copy_positions(batch, 1, x, count) == STABINT_OK);
  CHECK(memcmp(x, y, count * sizeof(double)) == 0);
  /* An old checkpoint: the batch's time moved on. */
  CHECK(stabint_batch_scene_restore(batch, 1, ckpt) == STABINT_INVALID_INPUT);
  CHECK(strstr(stabint_last_error_message(), "scene 1") != NULL);
  CHECK(stabint_batch_step_count(batch, 1) == 20);
  CHECK(stabint_batch_scene_checkpoint(batch, 0, &from_sim) == STABINT_OK);
  CHECK(stabint_checkpoint_step_count(from_sim) == 20);
  stabint_checkpoint_destroy(ckpt);
  stabint_checkpoint_destroy(from_sim);
  stabint_checkpoint_destroy(chain_ckpt);
  stabint_simulator_destroy(sim);
  stabint_simulator_destroy(chain);
  stabint_batch_destroy(batch);
  stabint_batch_destroy(other);
  free(x);
  free(y);
  free(f);
}

/* Every scene's positions of `batch`, one after another, into a new array. */
static double* all_positions(const stabint_batch* batch) {
  const int s = stabint_batch_size(batch) - 1;
  const size_t count = 3 * (size_t)(stabint_batch_first_particle(batch, s) + stabint_batch_num_particles(batch, s));
  double* x = (double*)malloc(count * sizeof(double));
  CHECK(stabint_batch_copy_all_positions(batch, x, count) == STABINT_OK);
  return x;
}

/* Drives scene 1 of `batch` 20 frames (drive_scene_one); it ends with all positions `original`,
 * bit for bit. */
static void drive_and_compare(stabint_batch* batch, const double corner[3], const double* original) {
  const int n = stabint_batch_num_particles(batch, 1);
  const size_t all = 3 * (size_t)(stabint_batch_first_particle(batch, 1) + n);
  double* again;
  int i;
  for (i = 0; i < 20; ++i) drive_scene_one(batch, NULL, corner, n);
  again = all_positions(batch);
  CHECK(memcmp(again, original, all * sizeof(double)) == 0);
  free(again);
}

/* A whole batch's checkpoint (chain and cloth, the cloth dragged as in drive()) restored into the
 * same batch, into a new batch of the same scenes, from its bytes and from a file continues bit
 * for bit (no pin or element was changed, so the factor is the same: BatchCheckpoint); one of its
 * scenes restores into a simulator; another batch's is refused and changes nothing. */
static void test_batch_checkpoint_of_the_whole_batch(void) {
  stabint_batch* batch = chain_and_cloth();
  stabint_batch* other = chain_and_cloth();
  stabint_batch* one = NULL;
  stabint_simulator* sim = small_cloth(STABINT_ENERGY_BLEND);
  stabint_scene* cloth = builtin("cloth", kSmallCloth);
  const stabint_scene* list[1];
  stabint_simulator_options options;
  stabint_batch_checkpoint *ckpt = NULL, *copy = NULL, *loaded = NULL, *single = NULL;
  stabint_checkpoint* scene_ckpt = NULL;
  const int n = stabint_batch_num_particles(batch, 1);
  const size_t all = 3 * (size_t)(stabint_batch_first_particle(batch, 1) + n);
  double corner[3], time, *original, *again;
  const void* data;
  size_t size = 0;
  char path[1024];
  int i, fd;
  list[0] = cloth;
  stabint_simulator_options_default(&options);
  CHECK(stabint_batch_create(list, 1, &options, &one) == STABINT_OK);
  stabint_scene_destroy(cloth);
  if (batch == NULL || other == NULL || one == NULL) return;
  CHECK(stabint_batch_pin_target(batch, 1, 0, corner) == STABINT_OK);
  for (i = 0; i < 12; ++i) drive_scene_one(batch, NULL, corner, n);
  CHECK(stabint_batch_checkpoint_create(batch, &ckpt) == STABINT_OK);
  CHECK(stabint_batch_checkpoint_size(ckpt) == 2);
  time = stabint_batch_time(batch);
  CHECK(stabint_batch_checkpoint_time(ckpt) == time);
  for (i = 0; i < 20; ++i) drive_scene_one(batch, NULL, corner, n);
  original = all_positions(batch);

  CHECK(stabint_batch_restore(batch, ckpt) == STABINT_OK);
  CHECK(stabint_batch_time(batch) == time && stabint_batch_step_count(batch, 1) == 12);
  drive_and_compare(batch, corner, original);

  /* From its bytes into a new batch; through a file into it again. */
  data = stabint_batch_checkpoint_data(ckpt, &size);
  CHECK(data != NULL && size > 0);
  CHECK(stabint_batch_checkpoint_from_bytes(data, size, &copy) == STABINT_OK);
  CHECK(stabint_batch_restore(other, copy) == STABINT_OK);
  drive_and_compare(other, corner, original);
  fd = temp_file(path, sizeof path);
  if (fd >= 0) close(fd);
  CHECK(stabint_batch_checkpoint_save(ckpt, path) == STABINT_OK);
  CHECK(stabint_batch_checkpoint_load(path, &loaded) == STABINT_OK);
  remove(path);
  CHECK(stabint_batch_restore(other, loaded) == STABINT_OK);
  drive_and_compare(other, corner, original);
  CHECK(stabint_batch_checkpoint_load(path, &single) == STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), path) != NULL);
  CHECK(stabint_batch_checkpoint_from_bytes(data, size - 1, &single) == STABINT_FILE_FORMAT);
  CHECK(single == NULL);

  /* Its cloth restores into a simulator, which continues as the batch's cloth to 1e-9 of the
   * cloth's size (the batch's factor against the simulator's own: round-off, as above). */
  CHECK(stabint_batch_checkpoint_scene(ckpt, 1, &scene_ckpt) == STABINT_OK);
  CHECK(stabint_checkpoint_step_count(scene_ckpt) == 12);
  CHECK(stabint_simulator_restore(sim, scene_ckpt) == STABINT_OK);
  CHECK(stabint_batch_restore(batch, ckpt) == STABINT_OK);
  for (i = 0; i < 20; ++i) drive_scene_one(batch, sim, corner, n);
  batch_scene_vs_simulator(batch, 1, sim, 1e-9 * extent(original + (all - 3 * (size_t)n), n));
  stabint_checkpoint_destroy(scene_ckpt);
  check_refused(stabint_batch_checkpoint_scene(ckpt, 2, &scene_ckpt), STABINT_INVALID_INPUT, "2");
  CHECK(scene_ckpt == NULL);

  /* A batch of one's checkpoint into a batch of two: refused, nothing changed. */
  CHECK(stabint_batch_checkpoint_create(one, &single) == STABINT_OK);
  free(original);
  original = all_positions(other);
  CHECK(stabint_batch_restore(other, single) == STABINT_INVALID_INPUT);
  stabint_batch_checkpoint_destroy(single);
  single = NULL;
  again = all_positions(other);
  CHECK(memcmp(again, original, all * sizeof(double)) == 0);
  CHECK(stabint_batch_step_count(other, 1) == 32);
  free(again);
  check_refused(stabint_batch_restore(other, NULL), STABINT_INVALID_ARGUMENT, "checkpoint is NULL");
  check_refused(stabint_batch_checkpoint_create(NULL, &single), STABINT_INVALID_ARGUMENT, "batch is NULL");
  CHECK(single == NULL);
  CHECK(stabint_batch_checkpoint_time(NULL) != stabint_batch_checkpoint_time(NULL)); /* NaN */
  CHECK(stabint_batch_checkpoint_size(NULL) == -1);
  CHECK(stabint_batch_checkpoint_data(NULL, &size) == NULL && size == 0);
  stabint_batch_checkpoint_destroy(NULL);
  stabint_batch_checkpoint_destroy(ckpt);
  stabint_batch_checkpoint_destroy(copy);
  stabint_batch_checkpoint_destroy(loaded);
  stabint_checkpoint_destroy(scene_ckpt);
  stabint_simulator_destroy(sim);
  stabint_batch_destroy(batch);
  stabint_batch_destroy(other);
  stabint_batch_destroy(one);
  free(original);
}

/* The iteration budget of every scene's later steps: options follow, a refused budget changes
 * nothing, and a plain BE step does exactly that many iterations per scene. */
static void test_batch_set_iterations(void) {
  stabint_batch* batch = chain_and_cloth();
  stabint_simulator_options options;
  stabint_step_report reports[2];
  check_refused(stabint_batch_set_iterations(batch, 0), STABINT_INVALID_INPUT, "iterations = 0");
  check_refused(stabint_batch_set_iterations(NULL, 3), STABINT_INVALID_ARGUMENT, "batch is NULL");
  CHECK(stabint_batch_get_options(batch, &options) == STABINT_OK && options.iterations == 10);
  stabint_batch_destroy(batch);

  stabint_simulator_options_default(&options);
  options.integrator = STABINT_BACKWARD_EULER;
  options.acceleration = STABINT_ACCELERATION_NONE;
  {
    stabint_scene* scenes[2];
    scenes[0] = builtin("chain", NULL);
    scenes[1] = builtin("cloth", kSmallCloth);
    batch = batch_of(scenes, 2, &options);
    stabint_scene_destroy(scenes[0]);
    stabint_scene_destroy(scenes[1]);
  }
  CHECK(stabint_batch_set_iterations(batch, 4) == STABINT_OK);
  CHECK(stabint_batch_get_options(batch, &options) == STABINT_OK && options.iterations == 4);
  CHECK(stabint_batch_step(batch, reports, 2) == STABINT_OK);
  CHECK(reports[0].iterations == 4 && reports[1].iterations == 4);
  stabint_batch_destroy(batch);
}

/* Reporters from C: a function called after every second step with the step's report, one that
 * fails its report (the step stays accepted, STABINT_ERROR names it), a CSV file with its header,
 * the initial row and one row per step, and removal by id. */
struct report_log {
  int calls;
  int last_step;
  int fail_at;
};
static int log_report(const stabint_simulator* sim, const stabint_step_report* report, void* user_data) {
  struct report_log* log = (struct report_log*)user_data;
  ++log->calls;
  log->last_step = report->step;
  CHECK(stabint_simulator_step_count(sim) == report->step + 1); /* the state after the step */
  return report->step == log->fail_at ? 7 : 0;
}

static void test_reporters(void) {
  stabint_simulator* sim = small_cloth(STABINT_BACKWARD_EULER);
  struct report_log log = {0, -1, -1};
  int id = 0, csv = 0, f, lines = 0, c;
  char path[256];
  FILE* file;
  snprintf(path, sizeof path, "/tmp/stabint_c_reporter_%d.csv", (int)getpid());
  CHECK(stabint_simulator_add_reporter(sim, log_report, &log, 0, &id) == STABINT_INVALID_INPUT);
  CHECK(stabint_simulator_add_reporter(sim, NULL, &log, 1, &id) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_add_reporter(sim, log_report, &log, 2, &id) == STABINT_OK);
  CHECK(stabint_simulator_add_csv_reporter(sim, "/nonexistent/dir/steps.csv", 1, 1, &csv) == STABINT_FILE_FORMAT);
  CHECK(stabint_simulator_add_csv_reporter(sim, path, 1, 1, &csv) == STABINT_OK);
  CHECK(id != csv);
  for (f = 0; f < 6; ++f) CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  CHECK(log.calls == 3 && log.last_step == 5); /* after steps 2, 4 and 6 */
  log.fail_at = 7;
  CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK); /* step 7: not due */
  CHECK(stabint_simulator_step(sim, NULL) == STABINT_ERROR);
  CHECK(strstr(stabint_last_error_message(), "C reporter") != NULL);
  CHECK(stabint_simulator_step_count(sim) == 8); /* the step stands */
  CHECK(stabint_simulator_remove_reporter(sim, id) == STABINT_OK);
  CHECK(stabint_simulator_remove_reporter(sim, id) == STABINT_INVALID_ARGUMENT);
  CHECK(stabint_simulator_step(sim, NULL) == STABINT_OK);
  CHECK(log.calls == 4);
  CHECK(stabint_simulator_remove_reporter(sim, csv) == STABINT_OK);
  stabint_simulator_destroy(sim); /* closes the CSV file */
  file = fopen(path, "r");
  CHECK(file != NULL);
  if (file != NULL) {
    while ((c = fgetc(file)) != EOF) lines += c == '\n';
    fclose(file);
  }
  /* The header, frame 0, steps 1-7 and 9: at step 8 the failing reporter, added first, kept the
   * ones after it from reporting (as in C++). */
  CHECK(lines == 1 + 1 + 8);
  remove(path);
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
  test_batch_steps_as_its_scenes_simulators();
  test_batch_all_positions();
  test_batch_set_iterations();
  test_batch_input_acts_on_its_scene();
  test_batch_collider_moved_every_frame(argv[1]);
  test_batch_set_states_is_set_state_one_by_one();
  test_batch_bad_input_is_rejected_and_changes_nothing();
  test_batch_refusal_leaves_the_other_scenes();
  test_batch_checkpoints();
  test_batch_checkpoint_of_the_whole_batch();
  test_reporters();
  printf("%d passed, %d failed\n", passed, failed);
  return failed == 0 ? 0 : 1;
}
