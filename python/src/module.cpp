// The Python extension stabint._stabint (nanobind): the module, its exception classes and its
// enums. The pure-Python package python/stabint re-exports it and adds scene_from_arrays and the
// builder shortcuts. The classes are bound by topic in the other files of this folder
// (common.hpp lists them); those with a field table are generated from it (fields.hpp).
#include "common.hpp"

#include <cstring>
#include <initializer_list>
#include <string>
#include <utility>

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

}  // namespace

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
  nb::register_exception_translator(translate);
}

// Python's enum `cpp_enum` with the values of its list (stabint/types.hpp): the enumerators'
// names and, where the list has one, each value's doc (its third field).
#define STABINT_PY_ENUM(cpp_enum, LIST, doc)           \
  {                                                    \
    using Enum = cpp_enum;                             \
    auto py_enum = nb::enum_<Enum>(m, #cpp_enum, doc); \
    LIST(STABINT_PY_VALUE)                             \
  }
#define STABINT_PY_VALUE(enumerator, ...) \
  py_enum.value(pythonName(#enumerator), Enum::enumerator, STABINT_PY_SECOND(__VA_ARGS__, nullptr, ));
#define STABINT_PY_SECOND(first, second, ...) second

void bindEnums(nb::module_& m) {
  STABINT_PY_ENUM(Integrator, STABINT_INTEGRATORS, "The six integrators (docs/method.md sections 2 and 3).")
  STABINT_PY_ENUM(BackendKind, STABINT_BACKENDS, "Where the local step and the energies run.")
  STABINT_PY_ENUM(Precision, STABINT_PRECISIONS, "Floating-point precision of the OpenCL backend.")
  STABINT_PY_ENUM(Acceleration, STABINT_ACCELERATIONS,
                  "Acceleration of the local/global iterations (None_: 'None' is a Python keyword).")
  STABINT_PY_ENUM(GlobalSolve, STABINT_GLOBAL_SOLVES, "How the global step solves K_c x = rhs.")
  STABINT_PY_ENUM(BlendBranch, STABINT_BLEND_BRANCHES,
                  "What the blend did with the IM candidate (None_: 'None' is a Python keyword).")
  STABINT_PY_ENUM(ColliderShape, STABINT_COLLIDER_SHAPE_VALUES, "Shape of a Collider.")
  STABINT_PY_ENUM(ClothModel, STABINT_CLOTH_MODELS, "How a cloth resists deformation.")
  STABINT_PY_ENUM(ElementKind, STABINT_ELEMENT_KINDS,
                  "An element list of a Scene, for set_element_stiffness and set_element_enabled.")
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
}
