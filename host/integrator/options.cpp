#include "integrator/options.hpp"

#include <stabint/options_fields.hpp>

#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "member_count.hpp"

namespace stabint {
namespace {

// The field list (stabint/options_fields.hpp) must name every member of the structs, with its
// type, or the C API, Python and stabint-run would silently miss a field. A member
// missing from the list changes the count of members an aggregate initializer takes; a wrong
// type or name fails the is_same checks.
using member_count::memberCount;

#define STABINT_CHECK_FIELD(type, name, doc)                            \
  static_assert(std::is_same_v<decltype(SimulatorOptions::name), type>, \
                "SimulatorOptions::" #name " has another type than its entry in the field list");
#define STABINT_CHECK_NESTED(type, name, fields, doc) \
  STABINT_CHECK_FIELD(type, name, doc)                \
  fields(STABINT_CHECK_SUB, name)
#define STABINT_CHECK_SUB(parent, type, name, doc)                                        \
  static_assert(std::is_same_v<decltype(decltype(SimulatorOptions::parent)::name), type>, \
                #parent "." #name " has another type than its entry in the field list");
STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_CHECK_FIELD, STABINT_CHECK_NESTED)
#undef STABINT_CHECK_FIELD
#undef STABINT_CHECK_NESTED
#undef STABINT_CHECK_SUB

// Whether an enum holds one of its values, 0 to count - 1 (the counts of simulator.hpp).
template <class Enum>
bool inRange(Enum value, int count) {
  return static_cast<int>(value) >= 0 && static_cast<int>(value) < count;
}

}  // namespace

void validateOptions(const SimulatorOptions& o) {
  auto fail = [](const std::string& what) { throw InvalidInputError("simulator options: " + what); };
  if (!std::isfinite(o.time_step) || o.time_step <= 0.0)
    fail("time_step = " + std::to_string(o.time_step) + " must be finite and > 0");
  // The solves use c = 4/h^2 (IM): h^2 must neither underflow (1e-300) nor overflow.
  const double h2 = o.time_step * o.time_step;
  if (!std::isnormal(h2) || !std::isfinite(4.0 / h2)) {
    std::ostringstream h;
    h << o.time_step;
    fail("time_step = " + h.str() + " is out of range: 1/h^2 must be a finite, non-zero number");
  }
  // An enum from a config file or a binding can hold any integer; an unknown integrator used to
  // run no integrator at all and commit a zero state.
  if (!inRange(o.integrator, kIntegratorCount))
    fail("integrator = " + std::to_string(static_cast<int>(o.integrator)) + " is not an Integrator value");
  if (!inRange(o.backend, kBackendKindCount))
    fail("backend = " + std::to_string(static_cast<int>(o.backend)) + " is not a BackendKind value");
  if (!inRange(o.opencl.precision, kPrecisionCount))
    fail("opencl.precision = " + std::to_string(static_cast<int>(o.opencl.precision)) + " is not a Precision value");
  if (!std::isfinite(o.energy_limit) || o.energy_limit < 0.0)
    fail("energy_limit must be finite and >= 0 (0: no limit)");
  if (o.iterations < 1) fail("iterations = " + std::to_string(o.iterations) + " must be >= 1");
  if (!std::isfinite(o.tolerance) || o.tolerance < 0.0) fail("tolerance must be finite and >= 0");
  if (o.max_iterations < 1) fail("max_iterations must be >= 1");
  if (o.be_iterations < 1) fail("be_iterations = " + std::to_string(o.be_iterations) + " must be >= 1");
  if (!std::isfinite(o.energy_tolerance) || o.energy_tolerance <= 0.0) fail("energy_tolerance must be finite and > 0");
  if (!(o.max_velocity_scale >= 1.0) || !std::isfinite(o.max_velocity_scale))
    fail("max_velocity_scale = " + std::to_string(o.max_velocity_scale) + " must be finite and >= 1");
  if (!inRange(o.acceleration, kAccelerationCount))
    fail("acceleration = " + std::to_string(static_cast<int>(o.acceleration)) + " is not an Acceleration value");
  if (o.anderson_window < 1 || o.anderson_window > 50)
    fail("anderson_window = " + std::to_string(o.anderson_window) + " must be in [1, 50]");
  if (o.lbfgs_history < 1 || o.lbfgs_history > 50)
    fail("lbfgs_history = " + std::to_string(o.lbfgs_history) + " must be in [1, 50]");
  if (!std::isfinite(o.gradient_tolerance) || !(o.gradient_tolerance >= 0.0 && o.gradient_tolerance < 1.0))
    fail("gradient_tolerance must be finite and in [0, 1) (0: off)");
  if (o.gradient_tolerance > 0.0 && o.acceleration != Acceleration::LBFGS)
    fail("gradient_tolerance > 0 needs acceleration = lbfgs (the solve that computes the gradient)");
  if (!(o.chebyshev_rho > 0.0 && o.chebyshev_rho < 1.0))
    fail("chebyshev_rho = " + std::to_string(o.chebyshev_rho) + " must be in (0, 1)");
  if (!inRange(o.global_solve, kGlobalSolveCount))
    fail("global_solve = " + std::to_string(static_cast<int>(o.global_solve)) + " is not a GlobalSolve value");
  if (o.cg_iterations < 1) fail("cg_iterations = " + std::to_string(o.cg_iterations) + " must be >= 1");
  if (!std::isfinite(o.cg_tolerance) || !(o.cg_tolerance >= 0.0 && o.cg_tolerance < 1.0))
    fail("cg_tolerance must be finite and in [0, 1) (0: a fixed count of cg_iterations)");
  if (o.max_root_evaluations < 1) fail("max_root_evaluations must be >= 1");
  if (!std::isfinite(o.contact_tolerance) || !(o.contact_tolerance >= 0.0))
    fail("contact_tolerance must be finite and >= 0");
}

}  // namespace stabint
