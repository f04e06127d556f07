/* The C API (include/stabint/stabint_c.h) from a C program: compiled as C99, no C++ in sight.
 * Each check prints on failure; the program ends with "N passed, N failed" and exits non-zero
 * when any check failed. Run by ctest (label cpu). */
#include <stabint/stabint_c.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int passed = 0;
static int failed = 0;

#define CHECK(cond)                                                                \
  do {                                                                             \
    if (cond) {                                                                    \
      ++passed;                                                                    \
    } else {                                                                       \
      ++failed;                                                                    \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__,      \
              __LINE__, #cond, stabint_last_error_message());                      \
    }                                                                              \
  } while (0)

static int starts_with(const char* text, const char* prefix) {
  return strncmp(text, prefix, strlen(prefix)) == 0;
}

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
    if (fabs(report.energy.total - report.target) > max_dev)
      max_dev = fabs(report.energy.total - report.target);
  }
  stabint_simulator_destroy(sim);
  return max_dev;
}

/* The blend tracks H* on the stiff chain where IM alone explodes (README motion table: max
 * |H - H*| 0.3 % of the available energy). Bound: 5 % of the swing energy over 300 frames, a
 * margin of 10x over the measured figure; IM's deviation exceeds it by orders of magnitude, so
 * the bound also shows that the report's fields are the blend's, not zeros. */
static void test_blend_tracks_target_on_chain(void) {
  const double blend = chain_max_deviation(STABINT_ENERGY_BLEND, 300);
  const double im = chain_max_deviation(STABINT_IMPLICIT_MIDPOINT, 300);
  printf("chain, 300 frames: max |H - H*| blend %.3g J, IM %.3g J (swing energy %.3g J)\n", blend,
         im, kSwingEnergy);
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

static void test_bad_options_are_reported(void) {
  stabint_scene* scene = NULL;
  stabint_simulator* sim = NULL;
  stabint_simulator_options options;
  CHECK(stabint_scene_create_builtin("oscillator", NULL, &scene) == STABINT_OK);

  stabint_simulator_options_default(&options);
  options.time_step = -0.1;
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
  CHECK(stabint_scene_create_builtin("cloth", "{\"no_such_param\": 1}", &scene) ==
        STABINT_FILE_FORMAT);
  CHECK(strstr(stabint_last_error_message(), "no_such_param") != NULL);
  snprintf(path, sizeof path, "%s/chain.json", scene_dir);
  CHECK(stabint_scene_load(path, &scene) == STABINT_OK);
  CHECK(stabint_scene_num_particles(scene) == 6); /* scenes/chain.json: six masses */
  stabint_scene_destroy(scene);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s SCENE_DIR\n", argv[0]);
    return 2;
  }
  test_defaults_and_names();
  test_bad_options_are_reported();
  test_blow_up_is_reported();
  test_buffers_and_triangles();
  test_files(argv[1]);
  test_blend_tracks_target_on_chain();
  printf("%d passed, %d failed\n", passed, failed);
  return failed == 0 ? 0 : 1;
}
