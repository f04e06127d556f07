#pragma once
/// @file
/// How the public enums are declared once. Each enum has one X-macro list of its values,
/// `X(Enumerator, "name", ...)`: the enumerator and its name as the library prints and parses it
/// (integratorName, parseIntegrator, ...), then what that enum's other uses need (a one-line doc
/// for the bindings, the C API's enumerator). The enum, its count, its name function, its parser,
/// the C API's checks and conversions and Python's values are generated from the list, so that a
/// new value is one line of it (docs/development.md, "Adding an enum value"). The helpers below
/// take any list and, but for enumNames, are not part of the API (their names end in '_').

#include <cstddef>
#include <string>

/// @cond
// Within `enum class E { LIST(STABINT_ENUMERATOR_) }`: the enumerators, valued 0, 1, ... in the
// list's order.
#define STABINT_ENUMERATOR_(enumerator, ...) enumerator,
// `0 LIST(STABINT_ENUM_ONE_)`: the number of values (the enum's count constant).
#define STABINT_ENUM_ONE_(...) +1
// Within `{ LIST(STABINT_ENUM_NAME_) }`: the names, in the enum's order.
#define STABINT_ENUM_NAME_(enumerator, ...) STABINT_ENUM_FIRST_(__VA_ARGS__, ),
// The first of its arguments; the trailing comma above gives `...` an argument, which C++17 wants
// also for the two-field lists.
#define STABINT_ENUM_FIRST_(first, ...) first
/// @endcond

namespace stabint {
/// @cond
// The name function of an enum: `value`'s entry of `names` (the list's names), "?" for a value
// outside the enum.
template <class Enum, std::size_t N>
constexpr const char* enumName_(Enum value, const char* const (&names)[N]) {
  const auto i = static_cast<std::size_t>(value);
  return i < N ? names[i] : "?";
}
/// @endcond

/// The names of the `count` values of an enum, in its order, as `nameOf` (integratorName, ...)
/// prints them: "a, b or c" by default, "a|b|c" with separator and last "|". For the messages of
/// parsers and the help of tools, which so list every value of the enum's list.
template <class Enum>
std::string enumNames(const char* (*nameOf)(Enum), int count, const std::string& separator = ", ",
                      const std::string& last = " or ") {
  std::string names;
  for (int i = 0; i < count; ++i)
    names += (i == 0 ? "" : i == count - 1 ? last : separator) + std::string(nameOf(static_cast<Enum>(i)));
  return names;
}
}  // namespace stabint
