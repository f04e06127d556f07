// The field tables of the public structs (stabint/field_list.hpp) against the structs, by paths
// that do not use the code the tables generate: the entries are the struct's members in the
// struct's order (the count is checked by the build, host/c_api/field_tables.cpp), and the C
// API's reports, converted from the tables, carry the same values as the C++ reports of the same
// run taken from stabint::Simulator directly.
#include <stabint/events_io_fields.hpp>
#include <stabint/stabint.hpp>
#include <stabint/stabint_c.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <string>
#include <tuple>
#include <vector>

namespace stabint {
namespace {

// Where each entry's member lies in one object, in the table's order, and the entries' names.
template <class T>
std::vector<std::uintptr_t> addresses(const T& object) {
  std::vector<std::uintptr_t> out;
  std::apply(
      [&](const auto&... field) { (out.push_back(reinterpret_cast<std::uintptr_t>(&(object.*field.member))), ...); },
      FieldTable<T>::fields);
  return out;
}
template <class T>
std::vector<std::string> names() {
  std::vector<std::string> out;
  std::apply([&](const auto&... field) { (out.emplace_back(field.name), ...); }, FieldTable<T>::fields);
  return out;
}

// The members follow each other in memory in the order of declaration, so increasing addresses
// mean the table lists distinct members in the struct's order (what Python's positional
// arguments rely on); its name is the struct's.
template <class T>
void expectTableInStructOrder(const char* type) {
  SCOPED_TRACE(type);
  EXPECT_EQ(std::string(FieldTable<T>::name), type);
  const T object{};
  const std::vector<std::uintptr_t> at = addresses(object);
  ASSERT_FALSE(at.empty());
  for (size_t i = 1; i < at.size(); ++i) EXPECT_LT(at[i - 1], at[i]) << names<T>()[i];
  const std::vector<std::string> n = names<T>();
  EXPECT_EQ(std::set<std::string>(n.begin(), n.end()).size(), n.size());
  std::vector<std::string> docs;
  std::apply([&](const auto&... field) { (docs.emplace_back(field.doc), ...); }, FieldTable<T>::fields);
  for (size_t i = 0; i < docs.size(); ++i) EXPECT_NE(docs[i], "") << n[i];
}

TEST(FieldTables, ListTheMembersInTheStructsOrder) {
#define EXPECT_KIND(kind, name) expectTableInStructOrder<kind>(#kind);
  STABINT_ELEMENT_KINDS(EXPECT_KIND)
#undef EXPECT_KIND
  expectTableInStructOrder<PinTarget>("PinTarget");
  expectTableInStructOrder<ForceField>("ForceField");
  expectTableInStructOrder<Collider>("Collider");
  expectTableInStructOrder<Body>("Body");
  expectTableInStructOrder<Scene>("Scene");
  expectTableInStructOrder<OpenCLDeviceInfo>("OpenCLDeviceInfo");
  expectTableInStructOrder<EnergyReport>("EnergyReport");
  expectTableInStructOrder<PhaseTimes>("PhaseTimes");
  expectTableInStructOrder<StepReport>("StepReport");
  expectTableInStructOrder<PathKey>("PathKey");
  expectTableInStructOrder<GrabEvent>("GrabEvent");
  expectTableInStructOrder<ReleaseEvent>("ReleaseEvent");
  expectTableInStructOrder<ImpulseEvent>("ImpulseEvent");
  expectTableInStructOrder<ElementEvent>("ElementEvent");
  expectTableInStructOrder<ColliderEvent>("ColliderEvent");
  expectTableInStructOrder<ScriptedEvent>("ScriptedEvent");
  expectTableInStructOrder<ClothMaterial>("ClothMaterial");
  expectTableInStructOrder<SolidMaterial>("SolidMaterial");
  // The options' tables come from the same rows as their members (stabint/options_table.h).
  expectTableInStructOrder<OpenCLOptions>("OpenCLOptions");
  expectTableInStructOrder<SimulatorOptions>("SimulatorOptions");
}

// The fields Python and the C API see, written out here by hand: a field added to a struct and
// its table shows here as a difference to review (and to add to the tests of the bindings).
TEST(FieldTables, NameTheFieldsOfTheStructs) {
  using V = std::vector<std::string>;
  EXPECT_EQ(names<Spring>(), (V{"a", "b", "rest_length", "stiffness"}));
  EXPECT_EQ(names<Tet>(), (V{"vertices", "stiffness"}));
  EXPECT_EQ(names<TriangleStrain>(), (V{"vertices", "stiffness", "strain_min", "strain_max"}));
  EXPECT_EQ(names<BendingHinge>(), (V{"vertices", "stiffness"}));
  EXPECT_EQ(names<Pin>(), (V{"vertex", "stiffness", "target"}));
  EXPECT_EQ(names<PinTarget>(), (V{"position", "velocity", "amplitude", "frequency"}));
  EXPECT_EQ(names<ForceField>(), (V{"particles", "force", "rate", "amplitude", "frequency"}));
  EXPECT_EQ(names<Collider>(), (V{"shape", "center", "normal", "half_extents", "end", "radius", "mesh_vertices",
                                  "mesh_triangles", "velocity", "friction", "stiffness", "elastic_ratio", "restitution",
                                  "first_particle", "num_particles"}));
  EXPECT_EQ(names<Body>(), (V{"name", "particles", "damping"}));
  EXPECT_EQ(names<EnergyReport>(), (V{"kinetic", "elastic", "external"}));
  EXPECT_EQ(names<PhaseTimes>(), (V{"local", "gather", "transfer", "global", "energy", "bookkeeping"}));
  EXPECT_EQ(names<StepReport>(),
            (V{"step", "time", "energy", "target", "forcing", "damping", "branch", "alpha", "velocity_scale",
               "event_energy", "friction", "contact_projection", "iterations", "energy_evaluations", "times"}));
}

// Every field of the C report equals the C++ report's of the same run (bit for bit: the runs are
// deterministic), but the wall-clock times, which only have to add up. Written out by hand, not
// from the list the conversion is generated from (NameTheFieldsOfTheStructs catches a new field).
void expectSameReport(const stabint_step_report& c, const StepReport& cpp) {
  EXPECT_EQ(c.step, cpp.step);
  EXPECT_EQ(c.time, cpp.time);
  EXPECT_EQ(c.target, cpp.target);
  EXPECT_EQ(c.forcing, cpp.forcing);
  EXPECT_EQ(c.damping, cpp.damping);
  EXPECT_EQ(static_cast<int>(c.branch), static_cast<int>(cpp.branch));
  EXPECT_EQ(c.alpha, cpp.alpha);
  EXPECT_EQ(c.velocity_scale, cpp.velocity_scale);
  EXPECT_EQ(c.event_energy, cpp.event_energy);
  EXPECT_EQ(c.friction, cpp.friction);
  EXPECT_EQ(c.contact_projection, cpp.contact_projection);
  EXPECT_EQ(c.iterations, cpp.iterations);
  EXPECT_EQ(c.energy_evaluations, cpp.energy_evaluations);
  EXPECT_EQ(c.energy.kinetic, cpp.energy.kinetic);
  EXPECT_EQ(c.energy.elastic, cpp.energy.elastic);
  EXPECT_EQ(c.energy.external, cpp.energy.external);
  EXPECT_EQ(c.energy.total, cpp.energy.total());
  EXPECT_GE(c.times.local, 0.0);
  EXPECT_EQ(c.times.total,
            c.times.local + c.times.gather + c.times.transfer + c.times.global + c.times.energy + c.times.bookkeeping);
}

TEST(FieldTables, CReportsCarryTheCppReportsValues) {
  // The blend on a chain under a moving pin: every energy term, a blend branch and forcing are
  // non-zero somewhere in the run.
  const Scene scene = builtinScene("chain", "{}");
  SimulatorOptions options;
  Simulator cpp(scene, options);
  stabint_scene* c_scene = nullptr;
  ASSERT_EQ(stabint_scene_create_builtin("chain", nullptr, &c_scene), STABINT_OK);
  stabint_simulator_options c_options;
  stabint_simulator_options_default(&c_options);
  stabint_simulator* c_sim = nullptr;
  ASSERT_EQ(stabint_simulator_create(c_scene, &c_options, &c_sim), STABINT_OK) << stabint_last_error_message();
  std::set<int> branches;
  for (int step = 0; step < 40; ++step) {
    SCOPED_TRACE(step);
    const StepReport& r = cpp.step();
    stabint_step_report c{};
    ASSERT_EQ(stabint_simulator_step(c_sim, &c), STABINT_OK) << stabint_last_error_message();
    expectSameReport(c, r);
    stabint_step_report last{};
    ASSERT_EQ(stabint_simulator_last_report(c_sim, &last), STABINT_OK);
    expectSameReport(last, r);
    branches.insert(static_cast<int>(r.branch));
  }
  EXPECT_GT(branches.size(), 1u);  // the run exercises more than one value of the enum field
  stabint_energy energy{};
  ASSERT_EQ(stabint_simulator_energy(c_sim, &energy), STABINT_OK);
  const EnergyReport e = cpp.energy();
  EXPECT_EQ(energy.kinetic, e.kinetic);
  EXPECT_EQ(energy.elastic, e.elastic);
  EXPECT_EQ(energy.external, e.external);
  EXPECT_EQ(energy.total, e.total());
  stabint_simulator_destroy(c_sim);
  stabint_scene_destroy(c_scene);
}

}  // namespace
}  // namespace stabint
