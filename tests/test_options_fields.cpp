// Every field of the options' field list (stabint/options_table.h) round-trips through the C
// API: a non-default value put into stabint_simulator_options reaches the simulator and comes back
// from stabint_simulator_get_options unchanged. The list drives the test, so a field added to it
// is tested without touching this file.
#include <stabint/options_table.h>
#include <stabint/stabint.hpp>
#include <stabint/stabint_c.h>

#include <gtest/gtest.h>

#include <functional>
#include <iterator>
#include <string>
#include <type_traits>
#include <vector>

namespace stabint {
namespace {

// A valid value other than `value`, one field at a time (the others keep their defaults).
int changed(int value) { return value == 1 ? 0 : value + 1; }  // a 0/1 switch (lbfgs_rigid_modes) flips
double changed(double value) { return 0.5 * value + 0.25; }
std::string changed(const std::string&) { return "0"; }
// The previous enum value, wrapping: BackendKind goes from CpuReference to Auto, which runs
// everywhere, where the next one, OpenCL, needs a device.
template <class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
Enum changed(Enum value, int count) {
  return static_cast<Enum>((static_cast<int>(value) + count - 1) % count);
}
Integrator changed(Integrator v) { return changed(v, kIntegratorCount); }
Acceleration changed(Acceleration v) { return changed(v, kAccelerationCount); }
GlobalSolve changed(GlobalSolve v) { return changed(v, kGlobalSolveCount); }
BackendKind changed(BackendKind v) { return changed(v, kBackendKindCount); }
Precision changed(Precision v) { return changed(v, kPrecisionCount); }

// The C struct as this test writes it, independently of the library's conversion.
void put(int value, int& c) { c = value; }
void put(double value, double& c) { c = value; }
void put(const std::string& value, const char*& c) { c = value.empty() ? nullptr : value.c_str(); }
template <class Enum, class C, class = std::enable_if_t<std::is_enum_v<Enum>>>
void put(Enum value, C& c) {
  c = static_cast<C>(value);
}
stabint_simulator_options toCStruct(const SimulatorOptions& o) {
  stabint_simulator_options c;
  stabint_simulator_options_default(&c);
#define PUT_FIELD(type, name, default_value, rule, doc) put(o.name, c.name);
#define PUT_NESTED(type, name, fields, doc) fields(PUT_SUB, name)
#define PUT_SUB(parent, type, name, default_value, rule, doc) put(o.parent.name, c.parent##_##name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(PUT_FIELD, PUT_NESTED)
#undef PUT_FIELD
#undef PUT_NESTED
#undef PUT_SUB
  return c;
}

bool same(int c, int cpp) { return c == cpp; }
bool same(double c, double cpp) { return c == cpp; }  // bit for bit: nothing is computed
bool same(const char* c, const std::string& cpp) { return std::string(c ? c : "") == cpp; }
template <class C, class Enum, class = std::enable_if_t<std::is_enum_v<Enum>>>
bool same(C c, Enum cpp) {
  return static_cast<int>(c) == static_cast<int>(cpp);
}
// Names every field of `c` that differs from `o`.
std::vector<std::string> differences(const stabint_simulator_options& c, const SimulatorOptions& o) {
  std::vector<std::string> names;
#define SAME_FIELD(type, name, default_value, rule, doc) \
  if (!same(c.name, o.name)) names.push_back(#name);
#define SAME_NESTED(type, name, fields, doc) fields(SAME_SUB, name)
#define SAME_SUB(parent, type, name, default_value, rule, doc) \
  if (!same(c.parent##_##name, o.parent.name)) names.push_back(#parent "_" #name);
  STABINT_SIMULATOR_OPTIONS_FIELDS(SAME_FIELD, SAME_NESTED)
#undef SAME_FIELD
#undef SAME_NESTED
#undef SAME_SUB
  return names;
}

TEST(OptionsFields, DefaultsOfTheCStructAreTheCppDefaults) {
  stabint_simulator_options c;
  stabint_simulator_options_default(&c);
  EXPECT_EQ(differences(c, SimulatorOptions{}), std::vector<std::string>{});
}

TEST(OptionsFields, EveryFieldRoundTripsThroughTheCApi) {
  struct Change {
    const char* field;
    void (*apply)(SimulatorOptions&);
  };
  const Change changes[] = {
#define CHANGE_FIELD(type, name, default_value, rule, doc) \
  {#name, [](SimulatorOptions& o) { o.name = changed(o.name); }},
#define CHANGE_NESTED(type, name, fields, doc) fields(CHANGE_SUB, name)
#define CHANGE_SUB(parent, type, name, default_value, rule, doc) \
  {#parent "." #name, [](SimulatorOptions& o) { o.parent.name = changed(o.parent.name); }},
      STABINT_SIMULATOR_OPTIONS_FIELDS(CHANGE_FIELD, CHANGE_NESTED)
#undef CHANGE_FIELD
#undef CHANGE_NESTED
#undef CHANGE_SUB
  };
  EXPECT_EQ(std::size(changes), 28u);  // 25 fields and opencl's 3

  stabint_scene* scene = nullptr;
  ASSERT_EQ(stabint_scene_create_builtin("oscillator", nullptr, &scene), STABINT_OK);
  for (const Change& change : changes) {
    const std::string name = change.field;
    SimulatorOptions set;
    change.apply(set);
    const stabint_simulator_options c = toCStruct(set);
    ASSERT_NE(differences(c, SimulatorOptions{}), std::vector<std::string>{}) << name << " did not change";
    stabint_simulator* sim = nullptr;
    ASSERT_EQ(stabint_simulator_create(scene, &c, &sim), STABINT_OK) << name << ": " << stabint_last_error_message();
    stabint_simulator_options back;
    ASSERT_EQ(stabint_simulator_get_options(sim, &back), STABINT_OK);
    EXPECT_EQ(differences(back, set), std::vector<std::string>{}) << name;
    stabint_simulator_destroy(sim);
  }
  stabint_scene_destroy(scene);
}

TEST(OptionsFields, OutOfRangeCEnumsNameTheField) {
  stabint_scene* scene = nullptr;
  ASSERT_EQ(stabint_scene_create_builtin("oscillator", nullptr, &scene), STABINT_OK);
  const auto rejected = [&](const std::function<void(stabint_simulator_options&)>& change, const std::string& field) {
    stabint_simulator_options c;
    stabint_simulator_options_default(&c);
    change(c);
    stabint_simulator* sim = nullptr;
    EXPECT_EQ(stabint_simulator_create(scene, &c, &sim), STABINT_INVALID_INPUT) << field;
    EXPECT_EQ(sim, nullptr);
    EXPECT_NE(std::string(stabint_last_error_message()).find("options." + field + ": invalid value"), std::string::npos)
        << stabint_last_error_message();
  };
  rejected([](stabint_simulator_options& c) { c.integrator = static_cast<stabint_integrator>(kIntegratorCount); },
           "integrator");
  rejected([](stabint_simulator_options& c) { c.acceleration = static_cast<stabint_acceleration>(-1); },
           "acceleration");
  rejected([](stabint_simulator_options& c) { c.global_solve = static_cast<stabint_global_solve>(kGlobalSolveCount); },
           "global_solve");
  rejected([](stabint_simulator_options& c) { c.backend = static_cast<stabint_backend>(kBackendKindCount); },
           "backend");
  rejected([](stabint_simulator_options& c) { c.opencl_precision = static_cast<stabint_precision>(kPrecisionCount); },
           "opencl_precision");
  stabint_scene_destroy(scene);
}

}  // namespace
}  // namespace stabint
