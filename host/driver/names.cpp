// The parsers of the public enums' names and small value-type helpers of simulator.hpp. The names
// themselves come from the enums' lists (stabint/types.hpp).
#include <stabint/simulator.hpp>

#include <algorithm>
#include <cctype>

namespace stabint {
namespace {
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The value of an enum with `count` values named by `nameOf` whose name is `name` in any case
// (or, with `plurals`, that name plus "s"); else InvalidInputError "unknown <what> '<name>'
// (expected a, b or c)", the names in the enum's order.
template <class Enum>
Enum parseName(const std::string& name, const char* (*nameOf)(Enum), int count, const std::string& what,
               bool plurals = false) {
  for (int i = 0; i < count; ++i) {
    const Enum value = static_cast<Enum>(i);
    const std::string candidate = lower(nameOf(value));
    if (lower(name) == candidate || (plurals && lower(name) == candidate + "s")) return value;
  }
  throw InvalidInputError("unknown " + what + " '" + name + "' (expected " + enumNames(nameOf, count) +
                          (plurals ? ", or their plurals)" : ")"));
}

template <class Enum>
std::vector<Enum> allValues(int count) {
  std::vector<Enum> values;
  for (int i = 0; i < count; ++i) values.push_back(static_cast<Enum>(i));
  return values;
}
}  // namespace

Integrator parseIntegrator(const std::string& name) {
  return parseName(name, integratorName, kIntegratorCount, "integrator");
}
std::vector<Integrator> allIntegrators() { return allValues<Integrator>(kIntegratorCount); }
BackendKind parseBackend(const std::string& name) { return parseName(name, backendName, kBackendKindCount, "backend"); }
Precision parsePrecision(const std::string& name) {
  return parseName(name, precisionName, kPrecisionCount, "precision");
}
Acceleration parseAcceleration(const std::string& name) {
  return parseName(name, accelerationName, kAccelerationCount, "acceleration");
}
GlobalSolve parseGlobalSolve(const std::string& name) {
  return parseName(name, globalSolveName, kGlobalSolveCount, "global solve");
}
ElementKind parseElementKind(const std::string& name) {
  return parseName(name, elementKindName, kElementKindCount, "element kind", true);
}
std::vector<ElementKind> allElementKinds() { return allValues<ElementKind>(kElementKindCount); }
BlendBranch parseBlendBranch(const std::string& name) {
  return parseName(name, blendBranchName, kBlendBranchCount, "blend branch");
}
ColliderShape parseColliderShape(const std::string& name) {
  return parseName(name, colliderShapeName, kColliderShapeCount, "collider shape");
}
ClothModel parseClothModel(const std::string& name) {
  return parseName(name, clothModelName, kClothModelCount, "cloth model");
}

PhaseTimes& PhaseTimes::operator+=(const PhaseTimes& o) {
  local += o.local;
  gather += o.gather;
  transfer += o.transfer;
  global += o.global;
  energy += o.energy;
  bookkeeping += o.bookkeeping;
  return *this;
}

}  // namespace stabint
