#pragma once
/// @file
/// The one list of SimulatorOptions' fields (X-macros), from which the C API's conversions, the
/// Python keywords and properties and stabint-run's flags are generated.
///
/// Adding a field to SimulatorOptions now touches: the struct (stabint/simulator.hpp: its type,
/// default and comment), one line of STABINT_SIMULATOR_OPTIONS_FIELDS below, its check in
/// validateOptions (the library's option checks), and the C struct stabint_simulator_options
/// (stabint/stabint_c.h, plain C, which cannot use these macros). The C conversions, Python's
/// `SimulatorOptions(**kwargs)` and its properties, and stabint-run's `--field-name` flag and
/// help line follow from the list. The build fails until the struct, this list and the C struct
/// agree: the library counts the struct's members against the list and checks every type, and
/// the C API's implementation checks every C field's type and every C enum value
/// (docs/development.md, "Adding a simulator option").
///
/// Each entry is `FIELD(type, name, doc)` (an int, a double or an enum of stabint/simulator.hpp)
/// or, for a nested options struct, `NESTED(type, name, FIELDS, doc)`, where FIELDS is the
/// list of the nested struct's fields. Entries are in the struct's order.
#include <stabint/types.hpp>

#include <string>

/// The fields of stabint::SimulatorOptions, in the struct's order: `FIELD(type, name, doc)` for
/// an int, double or enum; `NESTED(type, name, FIELDS, doc)` for a nested struct whose fields
/// are listed by the macro FIELDS (called as `FIELDS(FIELD, name)`, see
/// STABINT_OPENCL_OPTIONS_FIELDS). The docs are the one-line summaries of stabint/simulator.hpp.
#define STABINT_SIMULATOR_OPTIONS_FIELDS(FIELD, NESTED)                                                        \
  FIELD(stabint::Integrator, integrator, "the integrator: FE, SE, BE, BDF2, IM or blend")                      \
  FIELD(double, time_step, "time step h in seconds, > 0")                                                      \
  FIELD(int, iterations, "local/global iterations per implicit solve (the budget), >= 1")                      \
  FIELD(double, tolerance, "solve to this relative change of the objective instead (0: fixed budget)")         \
  FIELD(int, max_iterations, "most iterations of a solve run to `tolerance`, >= 1")                            \
  FIELD(stabint::Acceleration, acceleration, "the solver of every local/global solve")                         \
  FIELD(double, chebyshev_rho, "spectral-radius estimate of the Chebyshev recurrence, in (0, 1)")              \
  FIELD(int, anderson_window, "past iterates Anderson acceleration combines, in [1, 50]")                      \
  FIELD(int, lbfgs_history, "curvature pairs L-BFGS keeps, in [1, 50]")                                        \
  FIELD(double, gradient_tolerance, "L-BFGS stops at this fraction of the warm start's gradient (0: off)")     \
  FIELD(stabint::GlobalSolve, global_solve, "the global step's solver: factor or cg")                          \
  FIELD(int, cg_iterations, "CG iterations per global step (global_solve cg), >= 1")                           \
  FIELD(double, cg_tolerance, "CG stops earlier at this relative residual (0: always cg_iterations)")          \
  FIELD(int, be_iterations, "iterations of the blend's backward-Euler partner solve, >= 1")                    \
  FIELD(double, energy_tolerance, "the blend's tolerance tau = energy_tolerance * (K + E_int + E_scale), > 0") \
  FIELD(double, max_velocity_scale, "largest factor one step may scale the velocities up by, >= 1")            \
  FIELD(int, max_root_evaluations, "energy evaluations of the blend's root find, >= 1")                        \
  FIELD(double, energy_limit, "refuse a step whose H exceeds H* by this times E_scale (0: no limit)")          \
  FIELD(double, contact_tolerance, "deepest a particle may stay inside a collider after a step, m, >= 0")      \
  FIELD(stabint::BackendKind, backend, "where the element work runs: cpu, opencl or auto")                     \
  NESTED(stabint::OpenCLOptions, opencl, STABINT_OPENCL_OPTIONS_FIELDS, "OpenCL device and precision")

/// The fields of stabint::OpenCLOptions, in the struct's order, as `FIELD(parent, type, name,
/// doc)`: `parent` is the argument given to this macro (the name of the SimulatorOptions member
/// that holds them, `opencl`), so that a use can spell `parent.name` or a prefixed C name.
#define STABINT_OPENCL_OPTIONS_FIELDS(FIELD, parent)                                                  \
  FIELD(parent, std::string, platform, "OpenCL platform: index or name substring (empty: the first)") \
  FIELD(parent, std::string, device, "OpenCL device: index or name substring (empty: the first)")     \
  FIELD(parent, stabint::Precision, precision, "precision of the OpenCL kernels: double or float")
