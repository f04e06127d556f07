#pragma once
// The number of members of an aggregate, for the static checks that a field list names every
// member of its struct (host/driver/options.cpp, host/c_api/field_tables.cpp): a member
// missing from a list changes the count of initializers T{...} takes.
#include <cstddef>
#include <utility>

namespace stabint::member_count {

struct AnyField {
  template <class T>
  operator T() const;  // never called: only the initializer's validity is asked
};

// Counting members means asking whether T{AnyField, ...} with fewer initializers than members is
// valid, which clang's -Wmissing-field-initializers reports inside the unevaluated decltype.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
template <class T, class... Args>
constexpr auto bracesWith(int) -> decltype(void(T{std::declval<Args>()...}), true) {
  return true;
}
template <class T, class... Args>
constexpr bool bracesWith(...) {
  return false;
}
#pragma GCC diagnostic pop

/// The number of members of aggregate T: the most initializers T{...} accepts.
template <class T, class... Args>
constexpr std::size_t memberCount() {
  if constexpr (bracesWith<T, Args..., AnyField>(0))
    return memberCount<T, Args..., AnyField>();
  else
    return sizeof...(Args);
}

}  // namespace stabint::member_count
