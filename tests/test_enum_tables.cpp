// Every public enum's list (stabint/types.hpp) against what is generated from it and what is
// written apart from it: each C enumerator of stabint/stabint_c.h equals its C++ value, and every
// value's name parses back to it. The lists and the count constants drive the loops, so a new
// value is tested without touching this file.
#include <stabint/stabint.hpp>
#include <stabint/stabint_c.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <string>

namespace stabint {
namespace {

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

// Every value has its own name, which the parser reads back in any case; the first value past
// the end has none.
template <class Enum>
void expectNamesRoundTrip(const char* (*nameOf)(Enum), Enum (*parse)(const std::string&), int count) {
  std::set<std::string> names;
  for (int i = 0; i < count; ++i) {
    const Enum value = static_cast<Enum>(i);
    const std::string name = nameOf(value);
    SCOPED_TRACE(name);
    EXPECT_NE(name, "?");
    EXPECT_TRUE(names.insert(upper(name)).second) << "two values share a name";
    EXPECT_EQ(parse(name), value);
    EXPECT_EQ(parse(upper(name)), value);
  }
  EXPECT_STREQ(nameOf(static_cast<Enum>(count)), "?");
  EXPECT_THROW(parse("no such name"), InvalidInputError);
}

TEST(EnumTables, EveryNameParsesBackToItsValue) {
  expectNamesRoundTrip(integratorName, parseIntegrator, kIntegratorCount);
  expectNamesRoundTrip(backendName, parseBackend, kBackendKindCount);
  expectNamesRoundTrip(precisionName, parsePrecision, kPrecisionCount);
  expectNamesRoundTrip(accelerationName, parseAcceleration, kAccelerationCount);
  expectNamesRoundTrip(globalSolveName, parseGlobalSolve, kGlobalSolveCount);
  expectNamesRoundTrip(elementKindName, parseElementKind, kElementKindCount);
  expectNamesRoundTrip(blendBranchName, parseBlendBranch, kBlendBranchCount);
  expectNamesRoundTrip(colliderShapeName, parseColliderShape, kColliderShapeCount);
  expectNamesRoundTrip(clothModelName, parseClothModel, kClothModelCount);
  EXPECT_EQ(allIntegrators().size(), static_cast<size_t>(kIntegratorCount));
  EXPECT_EQ(allElementKinds().size(), static_cast<size_t>(kElementKindCount));
}

TEST(EnumTables, ParsersKeepTheirMessages) {
  const auto message = [](auto parse) -> std::string {
    try {
      parse("x");
    } catch (const InvalidInputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message(parseIntegrator), "unknown integrator 'x' (expected FE, SE, BE, BDF2, IM or blend)");
  EXPECT_EQ(message(parseBackend), "unknown backend 'x' (expected cpu, opencl or auto)");
  EXPECT_EQ(message(parseAcceleration),
            "unknown acceleration 'x' (expected none, chebyshev, anderson, lbfgs or newton)");
  EXPECT_EQ(message(parseGlobalSolve), "unknown global solve 'x' (expected factor or cg)");
  EXPECT_EQ(message(parseElementKind),
            "unknown element kind 'x' (expected spring, tet, triangle_strain, bending_hinge or pin, or their plurals)");
  EXPECT_EQ(parseElementKind("Triangle_Strains"), ElementKind::TriangleStrain);
}

// The C values through the list's C names, and through the C API's own range check: the C name
// functions answer for every value below the C++ count and for none at it.
TEST(EnumTables, EveryCEnumeratorEqualsItsCppValue) {
#define EXPECT_C_VALUE(enumerator, name, doc, c_enumerator) \
  EXPECT_EQ(static_cast<int>(c_enumerator), static_cast<int>(Enum::enumerator)) << #c_enumerator;
#define EXPECT_C_VALUES(cpp_enum, LIST) \
  {                                     \
    using Enum = cpp_enum;              \
    LIST(EXPECT_C_VALUE)                \
  }
  EXPECT_C_VALUES(Integrator, STABINT_INTEGRATORS)
  EXPECT_C_VALUES(BackendKind, STABINT_BACKENDS)
  EXPECT_C_VALUES(Precision, STABINT_PRECISIONS)
  EXPECT_C_VALUES(Acceleration, STABINT_ACCELERATIONS)
  EXPECT_C_VALUES(GlobalSolve, STABINT_GLOBAL_SOLVES)
  EXPECT_C_VALUES(BlendBranch, STABINT_BLEND_BRANCHES)
#undef EXPECT_C_VALUES
#undef EXPECT_C_VALUE
  for (int i = 0; i < kIntegratorCount; ++i)
    EXPECT_STREQ(stabint_integrator_name(static_cast<stabint_integrator>(i)), integratorName(Integrator(i)));
  EXPECT_EQ(stabint_integrator_name(static_cast<stabint_integrator>(kIntegratorCount)), nullptr);
  EXPECT_EQ(stabint_integrator_name(static_cast<stabint_integrator>(-1)), nullptr);
  for (int i = 0; i < kBlendBranchCount; ++i)
    EXPECT_STREQ(stabint_blend_branch_name(static_cast<stabint_blend_branch>(i)), blendBranchName(BlendBranch(i)));
  EXPECT_EQ(stabint_blend_branch_name(static_cast<stabint_blend_branch>(kBlendBranchCount)), nullptr);
}

}  // namespace
}  // namespace stabint
