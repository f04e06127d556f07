// The build's check of the field lists (stabint/field_list.hpp): every list names every data
// member of its struct. A member missing from a list would be missing from Python's keyword
// constructor, properties and repr and from the C conversions of the reports, silently; here it
// changes the count of members an aggregate initializer takes and fails the build. (Names are
// checked by the lists' own expansion, `&Struct::name`; types come from the struct.)
#include <stabint/events_io_fields.hpp>
#include <stabint/stabint.hpp>

#include <cstddef>
#include <tuple>
#include <utility>

#include "common/member_count.hpp"

namespace stabint {
namespace {

using member_count::memberCount;

template <class T>
constexpr bool listsEveryMember() {
  return std::tuple_size_v<decltype(FieldTable<T>::fields)> == memberCount<T>();
}

// The element types come from their list (STABINT_ELEMENT_KINDS), so a new one is checked here
// without a line of its own.
// Clang instantiates std::optional<Eigen::Vector3d>'s converting constructor from AnyField as a
// hard error, not a substitution failure; the GCC build (CI's main build) runs the checks.
#if !defined(__clang__)
#define STABINT_CHECK_KIND(kind, name) \
  static_assert(listsEveryMember<kind>(), "the field list of " #kind " must name every member of the struct");
STABINT_ELEMENT_KINDS(STABINT_CHECK_KIND)
#undef STABINT_CHECK_KIND

#define STABINT_CHECK_STRUCT(type) \
  static_assert(listsEveryMember<type>(), "the field list of " #type " must name every member of the struct");
STABINT_CHECK_STRUCT(PinTarget)
STABINT_CHECK_STRUCT(ForceField)
STABINT_CHECK_STRUCT(Collider)
STABINT_CHECK_STRUCT(Body)
STABINT_CHECK_STRUCT(Scene)
STABINT_CHECK_STRUCT(OpenCLDeviceInfo)
STABINT_CHECK_STRUCT(EnergyReport)
STABINT_CHECK_STRUCT(PhaseTimes)
STABINT_CHECK_STRUCT(StepReport)
STABINT_CHECK_STRUCT(PathKey)
STABINT_CHECK_STRUCT(GrabEvent)
STABINT_CHECK_STRUCT(ReleaseEvent)
STABINT_CHECK_STRUCT(ImpulseEvent)
STABINT_CHECK_STRUCT(ElementEvent)
STABINT_CHECK_STRUCT(ColliderEvent)
STABINT_CHECK_STRUCT(ScriptedEvent)
STABINT_CHECK_STRUCT(ClothMaterial)
STABINT_CHECK_STRUCT(SolidMaterial)
#undef STABINT_CHECK_STRUCT
#endif  // !defined(__clang__)

}  // namespace
}  // namespace stabint
