// Python classes generated from the field tables of the public structs (stabint/field_list.hpp):
// a keyword constructor whose defaults are the C++ struct's, one property per field with its doc,
// and a __repr__ naming every field. A struct with a table needs no binding code of its own; what
// a struct has beyond its fields (methods, another constructor) goes into a specialization of
// bindExtras in the file that binds it, before the call that binds the struct.
#pragma once

#include "common.hpp"

#include <stabint/events_io_fields.hpp>
#include <stabint/field_list.hpp>

#include <cstddef>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace stabint::py {

// How a struct's generated class differs from the default: every field a keyword argument with
// the C++ default, read-write properties. Fields are named by a list "a, b, c", which must be the
// struct's first fields in order (checked when its constructor is made).
template <class T>
struct PyStruct {
  static constexpr bool read_only = false;       // read-only properties, no constructor (reports)
  static constexpr const char* positional = "";  // leading fields that may also be passed by position
  static constexpr const char* required = "";    // leading fields without a default
  // A value type (the options): a keyword-only constructor whose unknown keyword is a one-line
  // TypeError naming the closest field, pickling (__getstate__/__setstate__) and ==.
  static constexpr bool value_type = false;
};
// The element constructors of before the tables take their fields by position and require them,
// as they did (Spring(a, b, rest_length, stiffness), TriangleStrain(vertices, stiffness,
// strain_min=1.0, strain_max=1.0), ...); a Pin's target is a keyword (its position is the
// third positional argument of the constructor Pin(vertex, stiffness, position)). A new struct
// takes keywords only, so that a field inserted into it cannot shift the arguments of a call;
// for these, a field inserted among the named ones fails the build.
#define STABINT_PY_STRUCT(type, positional_, required_, read_only_, value_type_) \
  template <>                                                                    \
  struct PyStruct<type> {                                                        \
    static constexpr bool read_only = read_only_;                                \
    static constexpr const char* positional = positional_;                       \
    static constexpr const char* required = required_;                           \
    static constexpr bool value_type = value_type_;                              \
  };
STABINT_PY_STRUCT(Spring, "a, b, rest_length, stiffness", "a, b, rest_length, stiffness", false, false)
STABINT_PY_STRUCT(Tet, "vertices, stiffness", "vertices, stiffness", false, false)
STABINT_PY_STRUCT(TriangleStrain, "vertices, stiffness, strain_min, strain_max", "vertices, stiffness", false, false)
STABINT_PY_STRUCT(BendingHinge, "vertices, stiffness", "vertices, stiffness", false, false)
STABINT_PY_STRUCT(Pin, "vertex, stiffness", "vertex, stiffness, target", false, false)
STABINT_PY_STRUCT(PathKey, "frame, position", "frame, position", false, false)
STABINT_PY_STRUCT(ScriptedEvent, "frame, action", "frame, action", false, false)
STABINT_PY_STRUCT(OpenCLDeviceInfo, "", "", true, false)
STABINT_PY_STRUCT(EnergyReport, "", "", true, false)
STABINT_PY_STRUCT(PhaseTimes, "", "", true, false)
STABINT_PY_STRUCT(StepReport, "", "", true, false)
STABINT_PY_STRUCT(OpenCLOptions, "", "", false, true)
STABINT_PY_STRUCT(SimulatorOptions, "", "", false, true)
#undef STABINT_PY_STRUCT

// The number of names in a list "a, b, c".
constexpr std::size_t countNames(const char* list) {
  std::size_t n = *list ? 1 : 0;
  for (; *list; ++list) n += *list == ',';
  return n;
}

// What a struct's class has beyond its fields; specialized where the struct is bound.
template <class T>
void bindExtras(nb::class_<T>&) {}

template <class T, std::size_t I>
constexpr auto fieldOf() {
  return std::get<I>(FieldTable<T>::fields);
}
template <class T, std::size_t I>
using FieldType = std::decay_t<decltype(std::declval<const T&>().*(fieldOf<T, I>().member))>;
template <class T>
constexpr std::size_t kFieldCount = std::tuple_size_v<std::decay_t<decltype(FieldTable<T>::fields)>>;

// Whether `list` ("a, b") names T's first fields, in order.
template <class T, std::size_t... I>
constexpr bool leadingNamesAre(const char* list, std::index_sequence<I...>) {
  const char* names[] = {fieldOf<T, I>().name..., ""};
  std::size_t at = 0;
  for (std::size_t i = 0; i < countNames(list); ++i) {
    if (i >= sizeof...(I)) return false;
    for (const char* c = names[i]; *c; ++c, ++at)
      if (list[at] != *c) return false;
    if (list[at] == ',' && list[at + 1] == ' ')
      at += 2;
    else if (list[at] != 0)
      return false;
  }
  return list[at] == 0;
}
template <class T>
constexpr bool leadingNamesAre(const char* list) {
  return leadingNamesAre<T>(list, std::make_index_sequence<kFieldCount<T>>());
}

template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {
  using element = T;
};
template <class T>
struct IsVariant : std::false_type {};
template <class... T>
struct IsVariant<std::variant<T...>> : std::true_type {};

template <class T>
void defineStruct(nb::module_& m);

// Binds T's class from its table unless it is bound already: a struct is bound where it is first
// needed, a nested one (Pin::target) before the struct that holds it, whose defaults are cast to
// it.
template <class T>
void bindStruct(nb::module_& m) {
  static bool bound = false;
  if (bound) return;
  bound = true;
  defineStruct<T>(m);
}

template <class V>
void bindFieldType(nb::module_& m);
template <class... T>
void bindAlternatives(nb::module_& m, std::variant<T...>*) {
  (bindFieldType<T>(m), ...);
}

// A field of a struct whose type has a table, or a list or variant of them, needs those classes
// before its property and its default are made; a list that is opaque (common.hpp: the Scene's,
// views) also its list class (SpringList); other lists (GrabEvent::path) are Python lists, copies.
template <class V>
void bindFieldType(nb::module_& m) {
  if constexpr (HasFieldTable<V>::value) {
    bindStruct<V>(m);
  } else if constexpr (IsVariant<V>::value) {
    bindAlternatives(m, static_cast<V*>(nullptr));
  } else if constexpr (IsVector<V>::value) {
    using E = typename IsVector<V>::element;
    bindFieldType<E>(m);
    if constexpr (HasFieldTable<E>::value && nb::detail::is_base_caster_v<nb::detail::make_caster<V>>) {
      static bool bound = false;
      if (!bound) {
        bound = true;
        static const std::string name = std::string(FieldTable<E>::name) + "List";
        auto list = nb::bind_vector<V>(m, name.c_str());
        list.attr("__doc__") = "A Scene's list of " + std::string(FieldTable<E>::name) +
                               ": a view of the scene's own (indexing, len, append, extend, insert, pop, clear "
                               "change the scene), as a Python list behaves.";
      }
    }
  }
}

// One property: arrays are copies in and out (common.hpp), everything else the member itself
// (an element list is a view).
template <class T, class V>
void bindProperty(nb::class_<T>& c, const char* name, V T::*member, const std::string& doc) {
  const std::string copy_doc = doc + " (copy)";
  if constexpr (std::is_same_v<V, Eigen::MatrixX3d>) {
    c.def_prop_rw(
        name, [member](const T& s) { return rowsCopy(s.*member); },
        [member](T& s, const Eigen::MatrixX3d& value) { s.*member = value; }, nb::for_getter(nb::rv_policy::move),
        copy_doc.c_str());
  } else if constexpr (std::is_same_v<V, Eigen::VectorXd>) {
    c.def_prop_rw(
        name, [member](const T& s) { return Eigen::VectorXd(s.*member); },
        [member](T& s, const Eigen::VectorXd& value) { s.*member = value; }, nb::for_getter(nb::rv_policy::move),
        copy_doc.c_str());
  } else if constexpr (std::is_same_v<V, Triangles>) {
    c.def_prop_rw(
        name, [member](const T& s) { return trianglesCopy(s.*member); },
        [member](T& s, TrianglesIn a) { s.*member = trianglesFrom(a); }, nb::for_getter(nb::rv_policy::move),
        copy_doc.c_str());
  } else if constexpr (PyStruct<T>::read_only) {
    c.def_ro(name, member, doc.c_str());
  } else {
    c.def_rw(name, member, doc.c_str());
  }
}

// A property per field of T's table, in its order, with the field's doc.
template <class T, std::size_t... I>
void bindProperties(nb::module_& m, nb::class_<T>& c, std::index_sequence<I...>) {
  (bindFieldType<FieldType<T, I>>(m), ...);
  (bindProperty(c, pythonName(fieldOf<T, I>().name), fieldOf<T, I>().member, fieldOf<T, I>().doc), ...);
}
template <class T>
void bindProperties(nb::module_& m, nb::class_<T>& c) {
  bindProperties(m, c, std::make_index_sequence<kFieldCount<T>>());
}

// The argument of field I, keyword-only from `positional` on.
template <class T, std::size_t I, class Argument>
auto inPlace(Argument argument) {
  if constexpr (I == countNames(PyStruct<T>::positional))
    return std::make_tuple(nb::kw_only(), std::move(argument));
  else
    return std::make_tuple(std::move(argument));
}
// The argument of field I: required, or with the C++ default.
template <class T, std::size_t I>
auto argumentOf(const T& defaults) {
  const nb::arg name(pythonName(fieldOf<T, I>().name));
  if constexpr (I < countNames(PyStruct<T>::required))
    return inPlace<T, I>(name);
  else
    return inPlace<T, I>(name = defaults.*(fieldOf<T, I>().member));
}

// T(field=value, ...): a default-constructed T with the given fields set.
template <class T, std::size_t... I>
void bindConstructor(nb::class_<T>& c, std::index_sequence<I...>) {
  static_assert(leadingNamesAre<T>(PyStruct<T>::positional) && leadingNamesAre<T>(PyStruct<T>::required),
                "PyStruct names fields that are not the struct's first ones: a field was inserted among them, "
                "which would shift the arguments of the Python constructor");
  const T defaults{};
  std::apply(
      [&](auto&&... arguments) {
        c.def(
            "__init__",
            [](T* self, const FieldType<T, I>&... values) {
              new (self) T{};
              ((self->*(fieldOf<T, I>().member) = values), ...);
            },
            arguments..., "Arguments set the fields of the same names; the others keep the C++ defaults.");
      },
      std::tuple_cat(argumentOf<T, I>(defaults)...));
}

// A value as a repr shows it: an enum value as the expression that names it
// ("Integrator.EnergyBlend", not "<Integrator.EnergyBlend: 5>"), anything else as its repr.
std::string valueRepr(nb::handle value);

// "Spring(a=0, b=1, rest_length=1.0, stiffness=100.0)": every property's repr. A struct whose
// repr shows less (Collider: its shape's fields) specializes structRepr where it is bound, as
// bindExtras.
template <class T, std::size_t... I>
std::string structRepr(nb::handle self, std::index_sequence<I...>) {
  const char* names[] = {pythonName(fieldOf<T, I>().name)...};
  std::string text = std::string(FieldTable<T>::name) + "(";
  for (std::size_t i = 0; i < sizeof...(I); ++i) {
    text += std::string(i ? ", " : "") + names[i] + "=" + valueRepr(self.attr(names[i]));
  }
  return text + ")";
}
template <class T>
std::string structRepr(nb::handle self) {
  return structRepr<T>(self, std::make_index_sequence<kFieldCount<T>>());
}

template <class T>
void bindRepr(nb::class_<T>& c) {
  c.def("__repr__", [](nb::handle self) { return structRepr<T>(self); });
}

// --- value types (PyStruct::value_type: the options) --------------------------------------------

// A field's type as a signature writes it: what the keyword takes.
template <class V>
std::string annotation() {
  if constexpr (std::is_same_v<V, int>) {
    return "int";
  } else if constexpr (std::is_same_v<V, double>) {
    return "float";
  } else if constexpr (std::is_same_v<V, bool>) {
    return "bool";
  } else if constexpr (std::is_same_v<V, std::string>) {
    return "str";
  } else if constexpr (std::is_enum_v<V>) {
    return nb::cast<std::string>(nb::type<V>().attr("__name__")) + " | str";
  } else {
    static_assert(HasFieldTable<V>::value, "a value type's field is a number, a string, an enum or a value type");
    return FieldTable<V>::name;
  }
}

// "def __init__(self, *, integrator: Integrator | str = Integrator.EnergyBlend, ...) -> None": the
// keyword constructor's signature, for help() and the stub, from the table and the C++ defaults.
template <class T, std::size_t... I>
std::string keywordSignature(std::index_sequence<I...>) {
  const T defaults{};
  std::string text = "def __init__(self, *";
  ((text += std::string(", ") + pythonName(fieldOf<T, I>().name) + ": " + annotation<FieldType<T, I>>() + " = " +
            valueRepr(nb::cast(defaults.*(fieldOf<T, I>().member)))),
   ...);
  return text + ") -> None";
}

// The one-line TypeError of a keyword T has no field for: the closest field's name when one is
// close (difflib, as Python's own "did you mean"), else every field's.
[[noreturn]] void unknownKeyword(const char* type, const std::string& keyword, const std::vector<std::string>& fields);

// Sets field I of `out` from a Python value; a value of another type is a one-line TypeError
// naming the field. An enum's unknown name is the parser's InvalidInputError (common.hpp).
template <class T, std::size_t I>
void setField(T& out, nb::handle value) {
  using V = FieldType<T, I>;
  try {
    out.*(fieldOf<T, I>().member) = nb::cast<V>(value);
  } catch (const nb::cast_error&) {
    throw nb::type_error((std::string(FieldTable<T>::name) + "." + pythonName(fieldOf<T, I>().name) + " takes " +
                          annotation<V>() + ", not " + nb::cast<std::string>(nb::type_name(value.type())))
                             .c_str());
  }
}

// Sets the fields of `out` that `values` names (a dict of keywords, or the state of a pickle).
template <class T, std::size_t... I>
void setFields(T& out, nb::dict values, std::index_sequence<I...>) {
  for (const auto& [key, value] : values) {
    const std::string name = nb::cast<std::string>(nb::str(key));
    const bool known = ((name == pythonName(fieldOf<T, I>().name) ? (setField<T, I>(out, value), true) : false) || ...);
    if (!known) unknownKeyword(FieldTable<T>::name, name, {pythonName(fieldOf<T, I>().name)...});
  }
}

// A field as pickled: an enum by its library name ("blend"), which stays valid when the enum's
// values are renumbered; a nested value type as itself (it pickles too); the rest as it is.
template <class V>
nb::object pickled(const V& value) {
  if constexpr (std::is_enum_v<V>)
    return nb::str(enumName(value));
  else
    return nb::cast(value);
}

// Field by field, a nested value type by its own fields.
template <class T, std::size_t... I>
bool fieldsEqual(const T& a, const T& b, std::index_sequence<I...>) {
  const auto equal = [](const auto& x, const auto& y) {
    using V = std::decay_t<decltype(x)>;
    if constexpr (HasFieldTable<V>::value)
      return fieldsEqual(x, y, std::make_index_sequence<kFieldCount<V>>());
    else
      return x == y;
  };
  return (equal(a.*(fieldOf<T, I>().member), b.*(fieldOf<T, I>().member)) && ...);
}

template <class T, std::size_t... I>
void bindValueType(nb::class_<T>& c, std::index_sequence<I...> fields) {
  static const std::string signature = keywordSignature<T>(fields);
  c.def(
      "__init__",
      [fields](T* self, nb::args args, nb::kwargs kwargs) {
        if (args.size() != 0)
          throw nb::type_error((std::string(FieldTable<T>::name) + "() takes keyword arguments only").c_str());
        T value{};
        setFields(value, kwargs, fields);
        new (self) T(std::move(value));
      },
      nb::sig(signature.c_str()),
      "Keyword arguments set the fields of the same names; the others keep the C++ defaults. An enum field also "
      "takes a name as a str (the names the CLI and scene files use, e.g. 'BE', 'blend', 'lbfgs', 'cpu'). An "
      "unknown keyword is a TypeError naming the closest field.");
  c.def("__getstate__", [](const T& o) {
    nb::dict state;
    ((state[pythonName(fieldOf<T, I>().name)] = pickled(o.*(fieldOf<T, I>().member))), ...);
    return state;
  });
  c.def("__setstate__", [fields](T& o, nb::dict state) {
    T value{};
    setFields(value, state, fields);
    new (&o) T(std::move(value));
  });
  c.def(
      "__eq__", [fields](const T& a, const T& b) { return fieldsEqual(a, b, fields); }, nb::is_operator());
  // Mutable, so unhashable, as a dataclass with eq.
  c.attr("__hash__") = nb::none();
}

template <class T>
void defineStruct(nb::module_& m) {
  nb::class_<T> c(m, FieldTable<T>::name, FieldTable<T>::doc);
  bindProperties(m, c);
  constexpr auto fields = std::make_index_sequence<kFieldCount<T>>();
  if constexpr (PyStruct<T>::value_type) {
    bindValueType(c, fields);
  } else if constexpr (!PyStruct<T>::read_only) {
    c.def(nb::init<>());
    bindConstructor(c, fields);
  }
  bindRepr(c);
  bindExtras(c);
}

}  // namespace stabint::py
