/** @file
 * The options of a simulator, declared once: one row per field of stabint::SimulatorOptions and
 * stabint::OpenCLOptions, with its type, default, allowed values and meaning. Everything else is
 * generated from these rows: the C++ structs (stabint/types.hpp), the plain-C struct
 * stabint_simulator_options (stabint/stabint_c.h, which is why this header is plain C: macros
 * only), the checks of validateOptions (the rule), the C conversions, Python's
 * `SimulatorOptions(**keywords)` with its properties and docs, and stabint-run's `--field-name`
 * flags with their help lines. Adding an option is one row here plus its use
 * (docs/development.md, "Adding a simulator option").
 *
 * A row is `FIELD(T(type), name, default, rule, doc)`:
 * - `type`: int, double, string, or an enum of stabint/types.hpp (Integrator, ...). `T` maps
 *   it to the language's type (STABINT_OPTION_CXX_TYPE_: int, std::string,
 *   stabint::Integrator; STABINT_OPTION_C_TYPE_: int, const char*, stabint_integrator).
 * - `default`: a C++ expression (the C struct's defaults come from the C++ struct:
 *   stabint_simulator_options_default).
 * - `rule`: what validateOptions accepts, checked with a message naming the field and value:
 *   positive() (finite, > 0), nonNegative() (finite, >= 0), atLeast(lo), inRange(lo, hi) (closed),
 *   openUnit() ((0, 1)), unitInterval() ([0, 1)), isEnum() (one of the enum's values), any().
 *   Rules between fields (time_step's h^2, gradient_tolerance's solver) are written in
 *   validateOptions itself.
 * - `doc`: one line, for --help and Python's docs. What a field does in full is in the comment
 *   above its row.
 *
 * A nested struct is a row `NESTED(T(type), name, T(FIELDS), doc)`, whose own rows are
 * `FIELD(parent, T(type), name, default, rule, doc)` (`parent` is the member's name, so that a
 * use can spell `parent.name` or the C field `parent_name`); `T(FIELDS)` names its list for the
 * language (STABINT_OPENCL_OPTIONS_FIELDS in C++), called as `fields(FIELD, name)`. Rows are in
 * the structs' order. */
#ifndef STABINT_OPTIONS_TABLE_H
#define STABINT_OPTIONS_TABLE_H

/** The rows of SimulatorOptions: how a Simulator (or BatchSimulator) steps. */
#define STABINT_SIMULATOR_OPTIONS_TABLE(FIELD, NESTED, T)                                                              \
  /* The integrator: the energy-tracking blend by default (docs/method.md, "The blend"). */                            \
  FIELD(T(Integrator), integrator, Integrator::EnergyBlend, isEnum(), "the integrator: FE, SE, BE, BDF2, IM or blend") \
  FIELD(T(double), time_step, 1.0 / 30.0, positive(), "time step h in seconds, > 0")                                   \
  /* Local/global iterations per implicit solve (the real-time budget). When `tolerance` > 0 the                       \
     solve instead runs until the relative change of the objective is below it (reference runs), at                    \
     most `max_iterations`. */                                                                                         \
  FIELD(T(int), iterations, 10, atLeast(1), "local/global iterations per implicit solve (the budget), >= 1")           \
  FIELD(T(double), tolerance, 0.0, nonNegative(),                                                                      \
        "solve to this relative change of the objective instead (0: fixed budget)")                                    \
  FIELD(T(int), max_iterations, 1000, atLeast(1), "most iterations of a solve run to `tolerance`, >= 1")               \
  /* The solver of every local/global solve: L-BFGS by default, the most accurate at its cost on                       \
     every scene measured (docs/method.md, "Which solver is the default"); None is plain iterations.                   \
     Then the spectral-radius estimate of the plain iteration that the Chebyshev recurrence uses,                      \
     the number of past iterates Anderson acceleration combines and the curvature pairs L-BFGS keeps.                  \
   */                                                                                                                  \
  FIELD(T(Acceleration), acceleration, Acceleration::LBFGS, isEnum(), "the solver of every local/global solve")        \
  FIELD(T(double), chebyshev_rho, 0.98, openUnit(), "spectral-radius estimate of the Chebyshev recurrence, in (0, 1)") \
  FIELD(T(int), anderson_window, 5, inRange(1, 50), "past iterates Anderson acceleration combines, in [1, 50]")        \
  FIELD(T(int), lbfgs_history, 5, inRange(1, 50), "curvature pairs L-BFGS keeps, in [1, 50]")                          \
  /* L-BFGS: 1 puts the scene's rigid motions into the initial Hessian as a coarse space (a pinned                     \
     cloth's swing in a few iterations instead of hundreds), 0 keeps K_c^-1 alone. Taken by backward                   \
     Euler's solves, and by implicit midpoint's and the blend partner's in the steps where the                         \
     scene's forcing does not change; never by BDF2's (docs/method.md, "Rigid motions in the                           \
     initial Hessian"). */                                                                                             \
  FIELD(T(int), lbfgs_rigid_modes, 1, inRange(0, 1), "L-BFGS: rigid motions in the initial Hessian (1) or not (0)")    \
  /* L-BFGS's stopping rule by accuracy (Acceleration::LBFGS only; 0: off): a solve stops once the                     \
     gradient of its objective, in the norm of L-BFGS's inverse Hessian (sqrt(g.H g), the Newton                       \
     decrement), has fallen to gradient_tolerance times its value at the warm start; `iterations`                      \
     stays the cap (docs/method.md, "L-BFGS"). */                                                                      \
  FIELD(T(double), gradient_tolerance, 0.0, unitInterval(),                                                            \
        "L-BFGS stops at this fraction of the warm start's gradient (0: off)")                                         \
  /* The global step's solver. With ConjugateGradient every global step runs `cg_iterations` CG                        \
     iterations (a fixed count: the OpenCL device reads nothing back), or, when `cg_tolerance` > 0,                    \
     stops earlier once ||rhs - K_c x|| <= cg_tolerance ||rhs|| in every column (the device then                       \
     reads back the residual after every CG iteration). */                                                             \
  FIELD(T(GlobalSolve), global_solve, GlobalSolve::Factor, isEnum(), "the global step's solver: factor or cg")         \
  FIELD(T(int), cg_iterations, 20, atLeast(1), "CG iterations per global step (global_solve cg), >= 1")                \
  FIELD(T(double), cg_tolerance, 0.0, unitInterval(),                                                                  \
        "CG stops earlier at this relative residual (0: always cg_iterations)")                                        \
  /* The energy-tracking blend (docs/method.md, "The blend"): the budget of its BE partner solve,                      \
     warm-started at x_n (solved on, up to `iterations` in all, where even the whole partner keeps                     \
     more energy than the target: docs/method.md, "A partner that cannot reach the target"); its                       \
     tolerance; the largest factor by which one step may scale the velocities up to restore missing                    \
     energy (energy comes back over a few steps, never as a kinetic jump of a nearly resting body);                    \
     the energy evaluations of its root find. */                                                                       \
  FIELD(T(int), be_iterations, 3, atLeast(1), "iterations of the blend's backward-Euler partner solve, >= 1")          \
  FIELD(T(double), energy_tolerance, 1e-3, positive(),                                                                 \
        "the blend's tolerance tau = energy_tolerance * (K + E_int + E_scale), > 0")                                   \
  FIELD(T(double), max_velocity_scale, 2.0, atLeast(1.0),                                                              \
        "largest factor one step may scale the velocities up by, >= 1")                                                \
  FIELD(T(int), max_root_evaluations, 12, atLeast(1), "energy evaluations of the blend's root find, >= 1")             \
  /* Energy ceiling, off when 0: a step whose energy H exceeds the tracked target H* by more than                      \
     energy_limit * E_scale (energyScale()) is refused with EnergyLimitError, keeping the last                         \
     accepted state, so that an explicit or midpoint run that gains energy stops long before it                        \
     overflows. Energy lost (damping, BE) is never refused. */                                                         \
  FIELD(T(double), energy_limit, 0.0, nonNegative(),                                                                   \
        "refuse a step whose H exceeds H* by this times E_scale (0: no limit)")                                        \
  /* Contact (docs/method.md, "Contact"): after every step, no particle stays deeper than this inside                  \
     a collider (m); the final projection that moves it out is booked in H*. It also sets the contact                  \
     set's margin, contact_tolerance + time_step^2 |gravity|: a particle that is (or, at its                           \
     velocity, will be) that close to a collider carries its contact term. */                                          \
  FIELD(T(double), contact_tolerance, 1e-2, nonNegative(),                                                             \
        "deepest a particle may stay inside a collider after a step, m, >= 0")                                         \
  /* Contact pairs leaving within the solve (docs/method.md, "Contact", "Leaving within the solve"),                   \
     L-BFGS only, off when 0: after the solve's third iteration a pair whose particle the iterate                      \
     and the forces on it carry away from its collider leaves the contact set and the global matrix,                   \
     and returns if a later iterate takes it back inside. A body lifted off a collider then follows                    \
     its hand; a settling cloth trembles on its colliders with more kinetic energy, so it is off. */                   \
  FIELD(T(int), contact_release, 0, inRange(0, 1), "contact pairs leave within the solve (1) or not (0)")              \
  /* Self-contact and contact between the cloths of a scene (docs/method.md, "Self-contact"), off                      \
     when 0: the surface triangles (Scene::triangles and the tets' boundary faces) keep this distance                  \
     apart and no triangle passes through another within a step. */                                                    \
  FIELD(T(double), self_contact_thickness, 0.0, nonNegative(),                                                         \
        "distance the scene's surfaces keep from each other, m (0: no self-contact)")                                  \
  FIELD(T(double), self_contact_friction, 0.0, nonNegative(),                                                          \
        "Coulomb coefficient mu between the scene's surfaces in self-contact, >= 0")                                   \
  FIELD(T(int), self_contact_supports, 1, inRange(0, 2),                                                               \
        "self-contact's supports in the solve: 0 none, 1 on heavy bodies, 2 also on cloths")                           \
  FIELD(T(BackendKind), backend, BackendKind::CpuReference, isEnum(),                                                  \
        "where the element work runs: cpu, opencl or auto")                                                            \
  NESTED(T(OpenCLOptions), opencl, T(OPENCL_OPTIONS_FIELDS), "OpenCL device and precision (backend opencl or auto)")

/** The rows of OpenCLOptions: which OpenCL device to use. Empty selectors fall back to the
 * environment variables STABINT_OPENCL_PLATFORM and STABINT_OPENCL_DEVICE, then to the first
 * platform and device; a selector is an index ("0") or a case-insensitive substring of the name. */
#define STABINT_OPENCL_OPTIONS_TABLE(FIELD, parent, T)                                                         \
  FIELD(parent, T(string), platform, "", any(), "OpenCL platform: index or name substring (empty: the first)") \
  FIELD(parent, T(string), device, "", any(), "OpenCL device: index or name substring (empty: the first)")     \
  FIELD(parent, T(Precision), precision, Precision::Double, isEnum(),                                          \
        "precision of the OpenCL kernels: double or float")

/** @cond */
/* The table's types in C++ (T = STABINT_OPTION_CXX_TYPE_) and in C (T = STABINT_OPTION_C_TYPE_);
 * a nested struct's list is a "type" too, so that `T(FIELDS)` gives each language its view. */
#define STABINT_OPTION_CXX_TYPE_(type) STABINT_OPTION_CXX_TYPE_##type
#define STABINT_OPTION_CXX_TYPE_int int
#define STABINT_OPTION_CXX_TYPE_double double
#define STABINT_OPTION_CXX_TYPE_string std::string
#define STABINT_OPTION_CXX_TYPE_Integrator stabint::Integrator
#define STABINT_OPTION_CXX_TYPE_Acceleration stabint::Acceleration
#define STABINT_OPTION_CXX_TYPE_GlobalSolve stabint::GlobalSolve
#define STABINT_OPTION_CXX_TYPE_BackendKind stabint::BackendKind
#define STABINT_OPTION_CXX_TYPE_Precision stabint::Precision
#define STABINT_OPTION_CXX_TYPE_OpenCLOptions stabint::OpenCLOptions
#define STABINT_OPTION_CXX_TYPE_OPENCL_OPTIONS_FIELDS STABINT_OPENCL_OPTIONS_FIELDS

#define STABINT_OPTION_C_TYPE_(type) STABINT_OPTION_C_TYPE_##type
#define STABINT_OPTION_C_TYPE_int int
#define STABINT_OPTION_C_TYPE_double double
#define STABINT_OPTION_C_TYPE_string const char*
#define STABINT_OPTION_C_TYPE_Integrator stabint_integrator
#define STABINT_OPTION_C_TYPE_Acceleration stabint_acceleration
#define STABINT_OPTION_C_TYPE_GlobalSolve stabint_global_solve
#define STABINT_OPTION_C_TYPE_BackendKind stabint_backend
#define STABINT_OPTION_C_TYPE_Precision stabint_precision
#define STABINT_OPTION_C_TYPE_OPENCL_OPTIONS_FIELDS STABINT_OPENCL_OPTIONS_C_FIELDS_
#define STABINT_OPENCL_OPTIONS_C_FIELDS_(FIELD, parent) \
  STABINT_OPENCL_OPTIONS_TABLE(FIELD, parent, STABINT_OPTION_C_TYPE_)
/** @endcond */

/** The rows of SimulatorOptions with their C++ types: `FIELD(type, name, default, rule, doc)`,
 * `NESTED(type, name, FIELDS, doc)` (see the file's comment). */
#define STABINT_SIMULATOR_OPTIONS_FIELDS(FIELD, NESTED) \
  STABINT_SIMULATOR_OPTIONS_TABLE(FIELD, NESTED, STABINT_OPTION_CXX_TYPE_)
/** The rows of OpenCLOptions with their C++ types: `FIELD(parent, type, name, default, rule, doc)`. */
#define STABINT_OPENCL_OPTIONS_FIELDS(FIELD, parent) \
  STABINT_OPENCL_OPTIONS_TABLE(FIELD, parent, STABINT_OPTION_CXX_TYPE_)

#endif /* STABINT_OPTIONS_TABLE_H */
