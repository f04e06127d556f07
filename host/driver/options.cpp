#include "driver/options.hpp"

#include <stabint/options_table.h>

#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>

namespace stabint {
namespace {

// The rules of the options' rows (stabint/options_table.h): the values a field accepts, as an
// interval (a double must also be finite) or "one of the enum's values".
struct Rule {
  double lo = -HUGE_VAL, hi = HUGE_VAL;
  bool lo_open = false, hi_open = false;
  bool is_enum = false;
};
constexpr Rule any() { return {}; }
constexpr Rule positive() { return {0.0, HUGE_VAL, true, false}; }
constexpr Rule nonNegative() { return {0.0, HUGE_VAL}; }
constexpr Rule atLeast(double lo) { return {lo, HUGE_VAL}; }
constexpr Rule inRange(double lo, double hi) { return {lo, hi}; }
constexpr Rule openUnit() { return {0.0, 1.0, true, true}; }
constexpr Rule unitInterval() { return {0.0, 1.0, false, true}; }
constexpr Rule isEnum() { return {0.0, 0.0, false, false, true}; }

std::string text(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

// "must be ...": the rule in words, as the row's doc writes it.
std::string accepted(const Rule& r, bool is_double) {
  const std::string finite = is_double ? "finite and " : "";
  if (r.hi == HUGE_VAL) return "must be " + finite + (r.lo_open ? "> " : ">= ") + text(r.lo);
  return "must be " + finite + "in " + (r.lo_open ? "(" : "[") + text(r.lo) + ", " + text(r.hi) +
         (r.hi_open ? ")" : "]");
}

bool inside(double value, const Rule& r) {
  return (r.lo_open ? value > r.lo : value >= r.lo) && (r.hi_open ? value < r.hi : value <= r.hi);
}

[[noreturn]] void fail(const std::string& what) { throw InvalidInputError("simulator options: " + what); }

void check(int value, const char* name, const Rule& r) {
  if (!inside(value, r)) fail(std::string(name) + " = " + std::to_string(value) + " " + accepted(r, false));
}
void check(double value, const char* name, const Rule& r) {
  if (!std::isfinite(value) || !inside(value, r))
    fail(std::string(name) + " = " + text(value) + " " + accepted(r, true));
}
void check(const std::string&, const char*, const Rule&) {}  // any text (a selector)

// An enum from a config file or a binding can hold any integer; an unknown integrator used to run
// no integrator at all and commit a zero state. Its valid values are 0 to count - 1, named by its
// name function; an enum type new to the options needs its line here.
struct EnumValues {
  int count;
  std::string names;
};
EnumValues values(Integrator) { return {kIntegratorCount, enumNames(integratorName, kIntegratorCount)}; }
EnumValues values(Acceleration) { return {kAccelerationCount, enumNames(accelerationName, kAccelerationCount)}; }
EnumValues values(GlobalSolve) { return {kGlobalSolveCount, enumNames(globalSolveName, kGlobalSolveCount)}; }
EnumValues values(BackendKind) { return {kBackendKindCount, enumNames(backendName, kBackendKindCount)}; }
EnumValues values(Precision) { return {kPrecisionCount, enumNames(precisionName, kPrecisionCount)}; }
template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
void check(Enum value, const char* name, const Rule&) {
  const EnumValues v = values(value);
  const int i = static_cast<int>(value);
  if (i < 0 || i >= v.count) fail(std::string(name) + " = " + std::to_string(i) + " is not one of " + v.names);
}

}  // namespace

void validateOptions(const SimulatorOptions& o) {
  // Every row's rule, in the table's order.
#define STABINT_CHECK_OPTION(type, name, default_value, rule, doc) check(o.name, #name, rule);
#define STABINT_CHECK_NESTED(type, name, fields, doc) fields(STABINT_CHECK_SUB, name)
#define STABINT_CHECK_SUB(parent, type, name, default_value, rule, doc) check(o.parent.name, #parent "." #name, rule);
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_CHECK_OPTION, STABINT_CHECK_NESTED)
#undef STABINT_CHECK_OPTION
#undef STABINT_CHECK_NESTED
#undef STABINT_CHECK_SUB

  // The rules between fields and beyond an interval.
  // The solves use c = 4/h^2 (IM): h^2 must neither underflow (1e-300) nor overflow.
  const double h2 = o.time_step * o.time_step;
  if (!std::isnormal(h2) || !std::isfinite(4.0 / h2))
    fail("time_step = " + text(o.time_step) + " is out of range: 1/h^2 must be a finite, non-zero number");
  if (o.gradient_tolerance > 0.0 && o.acceleration != Acceleration::LBFGS)
    fail("gradient_tolerance > 0 needs acceleration = lbfgs (the solve that computes the gradient)");
}

}  // namespace stabint
