// The Python extension stabint._stabint (nanobind): the module, its exception classes and its
// enums. The pure-Python package python/stabint re-exports it and adds scene_from_arrays and the
// builder shortcuts. The classes are bound by topic in the other files of this folder
// (common.hpp lists them); those with a field table are generated from it (fields.hpp).
#include "fields.hpp"

#include <cli.hpp>  // tools/run: stabint-run's runCli, for the `stabint-run` console command

#include <cstring>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace stabint::py {

using namespace nb::literals;

const char* pythonName(const char* name) {
  // The Python keywords a C++ member or enumerator may be named (C++ keywords excluded).
  static const char* const renamed[][2] = {
      {"None", "None_"},       {"True", "True_"},     {"False", "False_"},   {"and", "and_"},
      {"as", "as_"},           {"assert", "assert_"}, {"async", "async_"},   {"await", "await_"},
      {"def", "def_"},         {"del", "del_"},       {"elif", "elif_"},     {"except", "except_"},
      {"finally", "finally_"}, {"from", "from_"},     {"global", "global_"}, {"import", "import_"},
      {"in", "in_"},           {"is", "is_"},         {"lambda", "lambda_"}, {"nonlocal", "nonlocal_"},
      {"not", "not_"},         {"or", "or_"},         {"pass", "pass_"},     {"raise", "raise_"},
      {"with", "with_"},       {"yield", "yield_"},   {"print", "print"}};
  for (const auto& pair : renamed)
    if (std::strcmp(name, pair[0]) == 0) return pair[1];
  return name;
}

std::string valueRepr(nb::handle value) {
  // Owned by the module (never freed), as the exception classes below.
  static PyObject* const enum_class = nb::object(nb::module_::import_("enum").attr("Enum")).release().ptr();
  if (PyObject_IsInstance(value.ptr(), enum_class) == 1)
    return nb::cast<std::string>(value.type().attr("__name__")) + "." + nb::cast<std::string>(value.attr("name"));
  // A short array (a point, a direction, a tet's vertices) as a list, "[0.0, 1.0, 0.0]", which the
  // constructors take back; a long one as numpy writes it, abbreviated.
  static PyObject* const ndarray_class = nb::object(nb::module_::import_("numpy").attr("ndarray")).release().ptr();
  if (PyObject_IsInstance(value.ptr(), ndarray_class) == 1 && nb::cast<std::size_t>(value.attr("size")) <= 16)
    return nb::cast<std::string>(nb::repr(value.attr("tolist")()));
  return nb::cast<std::string>(nb::repr(value));
}

void unknownKeyword(const char* type, const std::string& keyword, const std::vector<std::string>& fields) {
  nb::list known;
  for (const std::string& field : fields) known.append(nb::str(field.c_str()));
  const nb::list close =
      nb::cast<nb::list>(nb::module_::import_("difflib").attr("get_close_matches")(keyword, known, 1, 0.6));
  std::string text = std::string(type) + "() got an unexpected keyword argument '" + keyword + "'; ";
  if (close.size() != 0) {
    text += "did you mean '" + nb::cast<std::string>(close[0]) + "'?";
  } else {
    text += "its fields are ";
    for (std::size_t i = 0; i < fields.size(); ++i) text += (i ? ", " : "") + fields[i];
  }
  throw nb::type_error(text.c_str());
}

namespace {

// The exception classes, created once at import; owned by the module (never freed).
struct ErrorTypes {
  PyObject* error = nullptr;
  PyObject* invalid_input = nullptr;
  PyObject* file_format = nullptr;
  PyObject* non_finite_state = nullptr;
  PyObject* energy_limit = nullptr;
  PyObject* opencl = nullptr;
  PyObject* no_opencl_device = nullptr;
  PyObject* kernel_build = nullptr;
  PyObject* unsupported_precision = nullptr;
  PyObject* out_of_memory = nullptr;
  PyObject* reporter = nullptr;
} errors;

PyObject* newErrorType(nb::module_& m, const char* name, PyObject* base, const char* doc) {
  // Defined in stabint._stabint so that stubgen writes the classes into the stub; the package
  // sets __module__ to "stabint" for readable tracebacks.
  const std::string qualified = std::string("stabint._stabint.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
  if (type == nullptr) throw nb::python_error();
  m.attr(name) = nb::handle(type);
  return type;
}

// Raises `type` with message `what` and the given attributes on the exception object.
void raise(PyObject* type, const char* what,
           std::initializer_list<std::pair<const char*, nb::object>> attributes = {}) {
  nb::object exc = nb::handle(type)(nb::str(what));
  for (const auto& [name, value] : attributes) nb::setattr(exc, name, value);
  PyErr_SetObject(type, exc.ptr());
}

// Most specific class first, as in the C API: each catch precedes the catches of its bases.
void translate(const std::exception_ptr& p, void*) {
  try {
    std::rethrow_exception(p);
  } catch (const ReporterError& e) {
    // A Python reporter's exception goes back to Python as itself (simulator.cpp's
    // PyCallbackReporter); a C++ reporter's failure is a ReporterError.
    try {
      std::rethrow_exception(e.cause());
    } catch (nb::python_error& cause) {
      cause.restore();
      return;
    } catch (...) {
    }
    raise(errors.reporter, e.what(), {{"step", nb::int_(e.step())}});
  } catch (const EnergyLimitError& e) {
    raise(errors.energy_limit, e.what(), {{"step", nb::int_(e.step())}});
  } catch (const NonFiniteStateError& e) {
    raise(errors.non_finite_state, e.what(), {{"step", nb::int_(e.step())}});
  } catch (const InvalidInputError& e) {
    raise(errors.invalid_input, e.what());
  } catch (const FileFormatError& e) {
    raise(errors.file_format, e.what(), {{"file", nb::str(e.file().c_str())}, {"line", nb::int_(e.line())}});
  } catch (const NoOpenCLDeviceError& e) {
    raise(errors.no_opencl_device, e.what());
  } catch (const KernelBuildError& e) {
    raise(errors.kernel_build, e.what(), {{"build_log", nb::str(e.buildLog().c_str())}});
  } catch (const UnsupportedPrecisionError& e) {
    raise(errors.unsupported_precision, e.what());
  } catch (const OpenCLError& e) {
    raise(errors.opencl, e.what());
  } catch (const OutOfMemoryError& e) {
    raise(errors.out_of_memory, e.what());
  } catch (const Error& e) {
    raise(errors.error, e.what());
  }
  // Anything else propagates to nanobind's own translators (bad_alloc -> MemoryError, ...).
}

// A name the library's parser takes, else a Python enumerator's name; else the parser's error.
template <class E>
E fromName(const std::string& name, E (*parse)(const std::string&)) {
  try {
    return parse(name);
  } catch (const InvalidInputError&) {
    nb::object member = nb::type<E>().attr("__members__").attr("get")(name);
    if (!member.is_none()) return nb::cast<E>(member);
    throw;
  }
}

}  // namespace

#define STABINT_PY_ENUM_PARSER(Enum, LIST, nameOf, parse, doc) \
  template <>                                                  \
  Enum enumFromName<Enum>(const std::string& name) {           \
    return fromName(name, parse);                              \
  }
STABINT_PY_ENUMS(STABINT_PY_ENUM_PARSER)
#undef STABINT_PY_ENUM_PARSER

void bindErrors(nb::module_& m) {
  errors.error =
      newErrorType(m, "Error", PyExc_RuntimeError, "Base of every error stabint raises (C++ stabint::Error).");
  errors.invalid_input = newErrorType(m, "InvalidInputError", errors.error,
                                      "A scene or an option failed validation; the message names the field.");
  errors.file_format = newErrorType(m, "FileFormatError", errors.error,
                                    "A file could not be opened or parsed. Attributes: file, line (0: none).");
  errors.non_finite_state = newErrorType(
      m, "NonFiniteStateError", errors.error,
      "A step was refused (non-finite state); the simulator keeps the last accepted state. Attribute: step.");
  errors.energy_limit = newErrorType(m, "EnergyLimitError", errors.non_finite_state,
                                     "A step would have exceeded SimulatorOptions.energy_limit. Attribute: step.");
  errors.opencl = newErrorType(m, "OpenCLError", errors.error, "Any OpenCL failure.");
  errors.no_opencl_device = newErrorType(m, "NoOpenCLDeviceError", errors.opencl,
                                         "No OpenCL device matches: fall back to BackendKind.CpuReference.");
  errors.kernel_build =
      newErrorType(m, "KernelBuildError", errors.opencl, "A kernel failed to compile. Attribute: build_log.");
  errors.unsupported_precision =
      newErrorType(m, "UnsupportedPrecisionError", errors.opencl, "Double precision on a device without cl_khr_fp64.");
  // Both a stabint.Error and Python's MemoryError, so either handler catches it.
  nb::object bases = nb::make_tuple(nb::handle(errors.error), nb::handle(PyExc_MemoryError));
  errors.out_of_memory = newErrorType(m, "OutOfMemoryError", bases.release().ptr(),
                                      "Memory ran out inside the call the message names; a simulator keeps its state.");
  errors.reporter = newErrorType(
      m, "ReporterError", errors.error,
      "A reporter failed after an accepted step (the step stands); the message names it. Attribute: step.");
  nb::register_exception_translator(translate);
}

// The enums of STABINT_PY_ENUMS (common.hpp), each with the values of its list: the enumerators'
// names and, where the list has one, each value's doc (its third field).
#define STABINT_PY_ENUM(cpp_enum, LIST, nameOf, parse, doc) \
  {                                                         \
    using Enum = cpp_enum;                                  \
    auto py_enum = nb::enum_<Enum>(m, #cpp_enum, doc);      \
    LIST(STABINT_PY_VALUE)                                  \
  }
#define STABINT_PY_VALUE(enumerator, ...) \
  py_enum.value(pythonName(#enumerator), Enum::enumerator, STABINT_PY_SECOND(__VA_ARGS__, nullptr, ));
#define STABINT_PY_SECOND(first, second, ...) second

void bindEnums(nb::module_& m) {
  STABINT_PY_ENUMS(STABINT_PY_ENUM)
#undef STABINT_PY_ENUM
#undef STABINT_PY_VALUE
#undef STABINT_PY_SECOND

  m.def("integrator_name", &integratorName, "The integrator's name: 'FE', 'blend', ...");
  m.def("parse_integrator", &parseIntegrator, "name"_a,
        "Integrator from a name as integrator_name prints it (any case).");
  m.def("backend_name", &backendName);
  m.def("parse_backend", &parseBackend, "name"_a);
  m.def("acceleration_name", &accelerationName);
  m.def("parse_acceleration", &parseAcceleration, "name"_a);
  m.def("blend_branch_name", &blendBranchName);
  m.def("all_integrators", &allIntegrators);
}

}  // namespace stabint::py

NB_MODULE(_stabint, m) {
  using namespace stabint::py;
  m.doc() = "stabint: stabilizing integrators for real-time deformable bodies (C++ extension).";
  bindErrors(m);
  bindEnums(m);
  bindScene(m);
  bindSimulator(m);
  bindBatch(m);
  bindEvents(m);
  // The C++ tool itself rather than a Python copy of it, so that both commands are one program.
  m.def(
      "_run_cli",
      [](std::vector<std::string> argv) {
        std::vector<char*> pointers;
        for (std::string& arg : argv) pointers.push_back(arg.data());
        pointers.push_back(nullptr);
        return stabint_run::runCli(static_cast<int>(argv.size()), pointers.data());
      },
      nb::arg("argv"), nb::call_guard<nb::gil_scoped_release>(),
      "Runs stabint-run with `argv` (argv[0] the program's name) and returns its exit status; it writes to "
      "the process's standard output and error. The `stabint-run` console command (stabint._cli).");
}
