#pragma once
/// @file
/// Error types of stabint. Everything the library throws derives from stabint::Error, so a
/// program can catch one type; the subtypes let it react to the cause (for example fall back to
/// the CPU reference backend on NoOpenCLDeviceError).
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

/// Everything of the C++ API: scenes, simulators, batches, loaders and errors.
namespace stabint {

/// Base of every exception stabint throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A scene or an option failed validation (index out of range, NaN, non-positive mass, time step
/// or rest volume, negative stiffness, ...). The message names the element or field.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

/// A file could not be opened or parsed. The message carries the file name and, when the file
/// was readable, the line number.
class FileFormatError : public Error {
 public:
  /// The message is "file:line: what" ("file: what" when `line` is 0).
  FileFormatError(const std::string& file, int line, const std::string& what)
      : Error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what), file_(file), line_(line) {}
  /// The file's path as it was given.
  const std::string& file() const { return file_; }
  /// 1-based line number, 0 when the error is not tied to a line (e.g. missing file).
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

/// A step produced a non-finite position or velocity. The step is refused: the simulator keeps
/// the last finite state, and the report of the refused step is available from the exception.
class NonFiniteStateError : public Error {
 public:
  /// `what` is the message, `step` the index of the refused step.
  NonFiniteStateError(const std::string& what, int step) : Error(what), step_(step) {}
  /// Index of the step that was refused (0 = the first step).
  int step() const { return step_; }

 private:
  int step_;
};

/// A step would have exceeded SimulatorOptions::energy_limit. Refused like a non-finite step (and
/// a NonFiniteStateError, so that code handling blow-ups handles this early stop too).
class EnergyLimitError : public NonFiniteStateError {
 public:
  /// As NonFiniteStateError's constructor: the message and the refused step.
  using NonFiniteStateError::NonFiniteStateError;
};

/// A reporter (stabint/reporters.hpp) threw after an accepted step: the step stands (state, time,
/// step count and report are the step's), the message names the reporter and the step, and the
/// reporter's own exception is cause(), for std::rethrow_exception.
class ReporterError : public Error {
 public:
  /// `what` is the message, `step` the index of the reported step, `cause` what the reporter threw.
  ReporterError(const std::string& what, int step, std::exception_ptr cause)
      : Error(what), step_(step), cause_(std::move(cause)) {}
  /// Index of the reported step (0 = the first step); the step was accepted.
  int step() const { return step_; }
  /// The exception the reporter threw.
  const std::exception_ptr& cause() const { return cause_; }

 private:
  int step_;
  std::exception_ptr cause_;
};

/// Memory ran out (std::bad_alloc inside the library): the message names the call. Refused like
/// bad input: a simulator keeps the state it had before the call.
class OutOfMemoryError : public Error {
 public:
  using Error::Error;
};

/// Any OpenCL failure; the message names the API call and the OpenCL error code.
class OpenCLError : public Error {
 public:
  using Error::Error;
};

/// No OpenCL platform or no device matching the selection exists. Catch it to fall back to the
/// CPU reference backend.
class NoOpenCLDeviceError : public OpenCLError {
 public:
  using OpenCLError::OpenCLError;
};

/// A kernel program failed to compile; the message contains the full build log.
class KernelBuildError : public OpenCLError {
 public:
  /// `what` is the message, `log` the compiler's build log (appended to the message).
  KernelBuildError(const std::string& what, std::string log)
      : OpenCLError(what + "\n--- build log ---\n" + log), log_(std::move(log)) {}
  /// The compiler's build log alone.
  const std::string& buildLog() const { return log_; }

 private:
  std::string log_;
};

/// The requested precision is not available on the chosen device (double without cl_khr_fp64).
class UnsupportedPrecisionError : public OpenCLError {
 public:
  using OpenCLError::OpenCLError;
};

}  // namespace stabint
