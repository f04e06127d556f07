// Shared by the C API's source files (include/stabint/stabint_c.h over the C++ API): the handles'
// definitions, guarded() and its argument checks, and the conversions between the C structs and
// enums and the C++ ones (c_conversions.cpp). Every entry point that can fail runs its body
// through guarded(), which turns every exception into a status code and the thread's last-error
// message, so that no exception unwinds into C frames.
#pragma once

#include <stabint/stabint.hpp>
#include <stabint/stabint_c.h>

#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

struct stabint_scene {
  stabint::Scene scene;
};
struct stabint_simulator {
  stabint::Simulator sim;
  // The reporters the C API attached, by the ids it handed out.
  std::vector<std::pair<int, std::shared_ptr<stabint::Reporter>>> reporters{};
  int next_reporter = 1;
};
struct stabint_checkpoint {
  stabint::Checkpoint checkpoint;
};
// A whole batch's checkpoint and its serialized bytes (BatchCheckpoint::bytes() makes them anew;
// stabint_batch_checkpoint_data hands out a pointer into them).
struct stabint_batch_checkpoint {
  explicit stabint_batch_checkpoint(stabint::BatchCheckpoint c) : checkpoint(std::move(c)), bytes(checkpoint.bytes()) {}
  stabint::BatchCheckpoint checkpoint;
  std::string bytes;
};
// The batch and the report of its last step (its refusals and per-scene reports, which the C API
// reads back after stabint_batch_step): the batch's own, which stays valid until its next step, so
// a step of a thousand scenes copies no report. Null before the first step and after a step that
// threw (its report may be half written).
struct stabint_batch {
  stabint::BatchSimulator batch;
  const stabint::BatchStepReport* last = nullptr;
};

namespace stabint::c_api {

// Raised by the C layer itself for API misuse (NULL handles, short buffers).
struct ArgumentError {
  std::string text;
};

// Records `status` with the message "<class_name>: <text>" (and the step of a refused step) as
// the thread's last error; returns `status`.
stabint_status fail(stabint_status status, const char* class_name, const std::string& text, int step = -1);

// Most specific class first: each catch below must precede the catches of its bases.
template <class Body>
stabint_status guarded(Body&& body) noexcept {
  try {
    body();
    return STABINT_OK;
  } catch (const ArgumentError& e) {
    return fail(STABINT_INVALID_ARGUMENT, "InvalidArgument", e.text);
  } catch (const EnergyLimitError& e) {
    return fail(STABINT_ENERGY_LIMIT, "EnergyLimitError", e.what(), e.step());
  } catch (const NonFiniteStateError& e) {
    return fail(STABINT_NON_FINITE_STATE, "NonFiniteStateError", e.what(), e.step());
  } catch (const InvalidInputError& e) {
    return fail(STABINT_INVALID_INPUT, "InvalidInputError", e.what());
  } catch (const FileFormatError& e) {
    return fail(STABINT_FILE_FORMAT, "FileFormatError", e.what());
  } catch (const NoOpenCLDeviceError& e) {
    return fail(STABINT_NO_OPENCL_DEVICE, "NoOpenCLDeviceError", e.what());
  } catch (const KernelBuildError& e) {
    return fail(STABINT_KERNEL_BUILD, "KernelBuildError", e.what());
  } catch (const UnsupportedPrecisionError& e) {
    return fail(STABINT_UNSUPPORTED_PRECISION, "UnsupportedPrecisionError", e.what());
  } catch (const OpenCLError& e) {
    return fail(STABINT_OPENCL, "OpenCLError", e.what());
  } catch (const OutOfMemoryError& e) {
    return fail(STABINT_OUT_OF_MEMORY, "OutOfMemoryError", e.what());
  } catch (const ReporterError& e) {
    return fail(STABINT_ERROR, "ReporterError", e.what(), e.step());
  } catch (const Error& e) {
    return fail(STABINT_ERROR, "Error", e.what());
  } catch (const std::bad_alloc&) {
    return fail(STABINT_OUT_OF_MEMORY, "OutOfMemory", "allocation failed");
  } catch (const std::exception& e) {
    return fail(STABINT_INTERNAL, "InternalError", e.what());
  } catch (...) {
    return fail(STABINT_INTERNAL, "InternalError", "unknown exception");
  }
}

template <class T>
void require(const T* pointer, const char* what) {
  if (pointer == nullptr) throw ArgumentError{std::string(what) + " is NULL"};
}

inline void requireCapacity(size_t capacity, size_t needed, const char* what) {
  if (capacity < needed) {
    throw ArgumentError{std::string(what) + ": buffer holds " + std::to_string(capacity) + " values, " +
                        std::to_string(needed) + " needed"};
  }
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Rows of an n by 3 matrix, interleaved x y z, converted to T, into `out` (room for `capacity`
// values); `what` names the array in the message of a short buffer.
template <class T>
void copyRows(const Eigen::MatrixX3d& m, T* out, size_t capacity, const char* what) {
  require(out, "out");
  const size_t n = static_cast<size_t>(m.rows());
  requireCapacity(capacity, 3 * n, what);
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) out[3 * i + k] = static_cast<T>(m(static_cast<Eigen::Index>(i), k));
  }
}

// An interleaved x y z array of `count` values as an n by 3 matrix, n = `particles`; a NULL
// array or a count other than 3 n is API misuse.
Eigen::MatrixX3d rowsFrom(Eigen::Index particles, const double* values, size_t count, const char* what);

// A C array of element indices (NULL allowed when count is 0) as the C++ API takes them.
std::vector<int> indexList(const int* indices, size_t count);

// A C vector of three values (`what` names it when NULL), and a C++ one copied out.
Eigen::Vector3d vector3(const double* values, const char* what);
void copyVector3(const Eigen::Vector3d& v, double* out);

// `text` truncated to `capacity` bytes with a terminating NUL into `out` (nothing when `out` is
// NULL or `capacity` is 0); returns the full length without NUL.
size_t copyText(const std::string& text, char* out, size_t capacity);

// The text `describe()` returns, copied as copyText does; 0 when it throws (an informational text
// never lets an exception into C).
template <class Describe>
size_t copyDescription(Describe&& describe, char* out, size_t capacity) noexcept {
  std::string text;
  try {
    text = describe();
  } catch (...) {
    return 0;
  }
  return copyText(text, out, capacity);
}

// The checkpoint handles' common calls (stabint_checkpoint, stabint_batch_checkpoint): save,
// load, bytes and from bytes, over the C++ class's save(), load(), bytes() and fromBytes().
inline const std::string& bytesOf(const stabint_checkpoint& c) { return c.checkpoint.bytes(); }
inline const std::string& bytesOf(const stabint_batch_checkpoint& c) { return c.bytes; }

template <class Handle>
stabint_status saveCheckpoint(const Handle* handle, const char* path) {
  return guarded([&] {
    require(handle, "checkpoint");
    require(path, "path");
    handle->checkpoint.save(path);
  });
}

template <class Handle>
stabint_status loadCheckpoint(const char* path, Handle** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(path, "path");
    require(out, "out");
    *out = new Handle{decltype(Handle::checkpoint)::load(path)};
  });
}

template <class Handle>
const void* checkpointData(const Handle* handle, size_t* size) {
  if (size != nullptr) *size = handle ? bytesOf(*handle).size() : 0;
  return handle ? bytesOf(*handle).data() : nullptr;
}

template <class Handle>
stabint_status checkpointFromBytes(const void* data, size_t size, Handle** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    if (size > 0) require(data, "data");
    require(out, "out");
    std::string bytes;
    if (size > 0) bytes.assign(static_cast<const char*>(data), size);
    *out = new Handle{decltype(Handle::checkpoint)::fromBytes(std::move(bytes))};
  });
}

// The C enum of each public C++ enum with its count (its values run from 0); c_conversions.cpp
// checks, from the enum's list, that every C enumerator equals its C++ value, so that a
// conversion either way is a cast.
template <class Enum>
struct CEnum;
#define STABINT_C_ENUM(cpp_enum, c_enum, LIST)              \
  template <>                                               \
  struct CEnum<cpp_enum> {                                  \
    using Enum = cpp_enum;                                  \
    using type = c_enum;                                    \
    static constexpr int count = 0 LIST(STABINT_ENUM_ONE_); \
  };
STABINT_C_ENUM(Integrator, stabint_integrator, STABINT_INTEGRATORS)
STABINT_C_ENUM(BackendKind, stabint_backend, STABINT_BACKENDS)
STABINT_C_ENUM(Precision, stabint_precision, STABINT_PRECISIONS)
STABINT_C_ENUM(Acceleration, stabint_acceleration, STABINT_ACCELERATIONS)
STABINT_C_ENUM(GlobalSolve, stabint_global_solve, STABINT_GLOBAL_SOLVES)
STABINT_C_ENUM(BlendBranch, stabint_blend_branch, STABINT_BLEND_BRANCHES)
#undef STABINT_C_ENUM

// Whether a C enum value (any int) is a value of the C++ enum.
template <class Enum>
bool isValue(typename CEnum<Enum>::type value) {
  return value >= 0 && value < CEnum<Enum>::count;
}
// The C++ name of a C enum value; NULL for any other int.
template <class Enum>
const char* nameOf(typename CEnum<Enum>::type value, const char* (*name)(Enum)) {
  return isValue<Enum>(value) ? name(static_cast<Enum>(value)) : nullptr;
}

// The conversions of the structs, generated from their field lists (c_conversions.cpp). A
// string of the C options points into the C++ options it came from.
SimulatorOptions fromC(const stabint_simulator_options& c);
stabint_simulator_options toC(const SimulatorOptions& o);
stabint_energy toC(const EnergyReport& e);
stabint_step_report toC(const StepReport& r);

}  // namespace stabint::c_api
