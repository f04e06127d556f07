#pragma once
/// @file
/// How the fields of the public structs are declared once. Each struct that the C API or the
/// Python binding converts field by field (the elements and the other parts of a Scene, the step
/// and energy reports, ...) has one X-macro list of its data members next to it,
/// `FIELD(name, "doc")` in the struct's order, and a FieldTable made from that list. From the
/// table come Python's keyword constructors, properties and `__repr__`, and, from the list, the
/// C API's conversions of the reports and their `static_assert`s; the library's build checks that
/// each list names every member of its struct. A member's type is taken from the struct itself
/// (decltype), so that it is written once; SimulatorOptions and OpenCLOptions are themselves
/// generated from their table (stabint/options_table.h), which also makes the C struct.
/// docs/development.md, "Adding a field to a public struct".

#include <cstddef>
#include <tuple>
#include <type_traits>

namespace stabint {

/// One entry of a FieldTable: a data member of `Struct` of type `Type`, its name as written in
/// the struct (also its Python name, but for Python keywords such as `global`, which get a
/// trailing '_') and its one-line doc.
template <class Struct, class Type>
struct StructField {
  const char* name;      ///< the member's name
  Type Struct::*member;  ///< the member
  const char* doc;       ///< one-line doc, for the bindings
};

/// The field table of public struct T, made by STABINT_FIELD_TABLE_ from the struct's field list.
/// Where T has one, it holds `name` (the struct's name), `doc` (a one-line summary of the struct)
/// and `fields`, a std::tuple of StructField entries in the struct's order. The primary template is
/// empty: a struct without a list has no table (HasFieldTable is false).
template <class T>
struct FieldTable {};

/// Whether T has a FieldTable (its `fields` exists).
///@{
template <class T, class = void>
struct HasFieldTable {
  static constexpr bool value = false;  ///< no table
};
/// @cond
template <class T>
struct HasFieldTable<T, std::void_t<decltype(FieldTable<T>::fields)>> {
  static constexpr bool value = true;
};
/// @endcond
///@}

}  // namespace stabint

/// @cond
// One Field of the struct whose table is being made (`Struct` inside FieldTable's specialization).
#define STABINT_FIELD_(member_name, member_doc) \
  ::stabint::StructField<Struct, decltype(Struct::member_name)>{#member_name, &Struct::member_name, member_doc},
// The FieldTable of `Type` (in namespace stabint) from its field list `LIST`, with `summary` the
// struct's one-line doc. The list's trailing comma is allowed in a braced initializer.
#define STABINT_FIELD_TABLE_(Type, LIST, summary)                    \
  template <>                                                        \
  struct FieldTable<Type> {                                          \
    using Struct = Type;                                             \
    static constexpr const char* name = #Type;                       \
    static constexpr const char* doc = summary;                      \
    static constexpr auto fields = std::tuple{LIST(STABINT_FIELD_)}; \
  };
// `0 LIST(STABINT_FIELD_ONE_)`: the number of fields of a list.
#define STABINT_FIELD_ONE_(...) +1
/// @endcond
