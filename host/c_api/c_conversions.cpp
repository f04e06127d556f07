// The C API's conversions between its plain-C structs and enums (include/stabint/stabint_c.h)
// and the C++ ones, generated from the lists: the options from their table
// (stabint/options_table.h, which also makes both option structs), the reports from their lists
// (stabint/types.hpp), the enums from their value lists. The C header spells the report structs
// and the enums itself; the checks below fail the build when a C field is missing or has another
// type (for the options: when the table's C type map disagrees with its C++ one), or when a C
// enum's values drift from the C++ enum's.
#include "c_api/c_api.hpp"

#include <stabint/options_table.h>

#include <string>
#include <type_traits>

namespace stabint::c_api {
namespace {

// Every C enumerator equals its C++ value (from the enum's list): a value added to the list
// without its C enumerator, or a C value that drifts, fails the build here.
#define STABINT_C_SAME_VALUES(cpp_enum, LIST) \
  namespace check_##cpp_enum {                \
    using Enum = cpp_enum;                    \
    LIST(STABINT_C_SAME_VALUE)                \
  }
#define STABINT_C_SAME_VALUE(enumerator, name, doc, c_enumerator)                     \
  static_assert(static_cast<int>(c_enumerator) == static_cast<int>(Enum::enumerator), \
                #c_enumerator " differs from the C++ value " #enumerator);
STABINT_C_SAME_VALUES(Integrator, STABINT_INTEGRATORS)
STABINT_C_SAME_VALUES(BackendKind, STABINT_BACKENDS)
STABINT_C_SAME_VALUES(Precision, STABINT_PRECISIONS)
STABINT_C_SAME_VALUES(Acceleration, STABINT_ACCELERATIONS)
STABINT_C_SAME_VALUES(GlobalSolve, STABINT_GLOBAL_SOLVES)
STABINT_C_SAME_VALUES(BlendBranch, STABINT_BLEND_BRANCHES)
#undef STABINT_C_SAME_VALUES
#undef STABINT_C_SAME_VALUE

// The C type of a field of C++ type T: the same for int and double, the C enum for an enum, a
// NUL-terminated string (NULL: empty) for a std::string, the C struct of a nested report.
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
template <>
struct CField<EnergyReport> {
  using type = stabint_energy;
};
template <>
struct CField<PhaseTimes> {
  using type = stabint_phase_times;
};
template <class T>
using CType = typename CField<T>::type;

// Every row of the options' table has its C field, with the C type of its C++ type. A nested struct's fields
// are spelled <member>_<field> in C (opencl_platform).
#define STABINT_C_CHECK_FIELD(type, name, default_value, rule, doc)                     \
  static_assert(std::is_same_v<decltype(stabint_simulator_options::name), CType<type>>, \
                "stabint_simulator_options::" #name " has the wrong type");
#define STABINT_C_CHECK_NESTED(type, name, fields, doc) fields(STABINT_C_CHECK_SUB, name)
#define STABINT_C_CHECK_SUB(parent, type, name, default_value, rule, doc)                          \
  static_assert(std::is_same_v<decltype(stabint_simulator_options::parent##_##name), CType<type>>, \
                "stabint_simulator_options::" #parent "_" #name " has the wrong type");
STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_C_CHECK_FIELD, STABINT_C_CHECK_NESTED)
#undef STABINT_C_CHECK_FIELD
#undef STABINT_C_CHECK_NESTED
#undef STABINT_C_CHECK_SUB

// C -> C++, one field. C enums arrive as plain ints: the range is checked before the cast (the
// message names the C field).
void fromC(int value, int& out, const char*) { out = value; }
void fromC(double value, double& out, const char*) { out = value; }
void fromC(const char* value, std::string& out, const char*) { out = value ? value : ""; }
template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
void fromC(typename CEnum<Enum>::type value, Enum& out, const char* field) {
  if (!isValue<Enum>(value)) {
    throw InvalidInputError(std::string("options.") + field + ": invalid value " +
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
void toC(const EnergyReport& value, stabint_energy& out) { out = c_api::toC(value); }
void toC(const PhaseTimes& value, stabint_phase_times& out);

// One field of a report's list (stabint/types.hpp), from `cpp` into `c`: the C struct has a field
// of that name and of the C type of the C++ member, or the build fails here.
#define STABINT_TO_C_REPORT_FIELD(name, doc)                                                         \
  static_assert(std::is_same_v<decltype(c.name), CType<std::decay_t<decltype(cpp.name)>>>,           \
                "the C struct's field " #name " is missing or has another type than the C++ one's"); \
  toC(cpp.name, c.name);

// The other direction: a C report struct has no field its list lacks. A struct made of the
// list's fields with their C types, in the list's order (plus the C struct's computed `total`),
// has the C struct's size; a C field the list lacks (which would stay zero) changes the size
// unless it fits into padding.
#define STABINT_C_MIRROR_FIELD(name, doc) CType<decltype(Struct::name)> name;
#define STABINT_C_SAME_SIZE(c_struct, cpp_struct, LIST, extra) \
  struct Mirror_##c_struct {                                   \
    using Struct = cpp_struct;                                 \
    LIST(STABINT_C_MIRROR_FIELD)                               \
    extra                                                      \
  };                                                           \
  static_assert(sizeof(Mirror_##c_struct) == sizeof(c_struct), \
                #c_struct " has a field that " #LIST " lacks, or its fields in another order");
STABINT_C_SAME_SIZE(stabint_energy, EnergyReport, STABINT_ENERGY_REPORT_FIELDS, double total;)
STABINT_C_SAME_SIZE(stabint_phase_times, PhaseTimes, STABINT_PHASE_TIMES_FIELDS, double total;)
STABINT_C_SAME_SIZE(stabint_step_report, StepReport, STABINT_STEP_REPORT_FIELDS, )
#undef STABINT_C_MIRROR_FIELD
#undef STABINT_C_SAME_SIZE

void toC(const PhaseTimes& cpp, stabint_phase_times& c) {
  STABINT_PHASE_TIMES_FIELDS(STABINT_TO_C_REPORT_FIELD)
  c.total = cpp.total();  // computed, not a field
}

}  // namespace

SimulatorOptions fromC(const stabint_simulator_options& c) {
  SimulatorOptions o;
#define STABINT_FROM_C_FIELD(type, name, default_value, rule, doc) fromC(c.name, o.name, #name);
#define STABINT_FROM_C_NESTED(type, name, fields, doc) fields(STABINT_FROM_C_SUB, name)
#define STABINT_FROM_C_SUB(parent, type, name, default_value, rule, doc) \
  fromC(c.parent##_##name, o.parent.name, #parent "_" #name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_FROM_C_FIELD, STABINT_FROM_C_NESTED)
#undef STABINT_FROM_C_FIELD
#undef STABINT_FROM_C_NESTED
#undef STABINT_FROM_C_SUB
  return o;
}

stabint_simulator_options toC(const SimulatorOptions& o) {
  stabint_simulator_options c{};
#define STABINT_TO_C_FIELD(type, name, default_value, rule, doc) toC(o.name, c.name);
#define STABINT_TO_C_NESTED(type, name, fields, doc) fields(STABINT_TO_C_SUB, name)
#define STABINT_TO_C_SUB(parent, type, name, default_value, rule, doc) toC(o.parent.name, c.parent##_##name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_TO_C_FIELD, STABINT_TO_C_NESTED)
#undef STABINT_TO_C_FIELD
#undef STABINT_TO_C_NESTED
#undef STABINT_TO_C_SUB
  return c;
}

stabint_energy toC(const EnergyReport& cpp) {
  stabint_energy c{};
  STABINT_ENERGY_REPORT_FIELDS(STABINT_TO_C_REPORT_FIELD)
  c.total = cpp.total();  // computed, not a field
  return c;
}

stabint_step_report toC(const StepReport& cpp) {
  stabint_step_report c{};
  STABINT_STEP_REPORT_FIELDS(STABINT_TO_C_REPORT_FIELD)
  return c;
}

}  // namespace stabint::c_api
