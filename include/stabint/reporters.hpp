#pragma once
/// @file
/// Per-frame reporters, in the spirit of OpenMM's: objects a Simulator calls after every k-th
/// accepted step (Simulator::addReporter), to write a CSV of energies and timings, or to call a
/// function (a progress bar, a plot, a custom file).
///
/// The rules:
/// - A reporter is due after a step when the simulator's stepCount() (the steps taken, this one
///   included) is a multiple of every(): with every() = k, after steps k, 2k, 3k, ...
/// - Reporters run in the order they were added, after the step is accepted; a refused step
///   (NonFiniteStateError, EnergyLimitError, bad input) reports nothing.
/// - A reporter that throws does not undo the step: the state, time, step count and
///   lastReport() are the accepted step's. Simulator::step throws ReporterError naming the
///   reporter and the step, with the reporter's exception as its cause(); the reporters after it
///   are not called for that step. Any exception is wrapped, a stabint::Error too, so that a
///   caller can tell a failed report from a refused step.
#include <stabint/errors.hpp>
#include <stabint/types.hpp>

#include <functional>
#include <iosfwd>
#include <memory>
#include <string>

namespace stabint {

class Simulator;

/// Base of every reporter: called after every every()-th accepted step.
class Reporter {
 public:
  /// Throws InvalidInputError when `every` < 1.
  explicit Reporter(int every = 1);
  virtual ~Reporter();
  Reporter(const Reporter&) = delete;
  Reporter& operator=(const Reporter&) = delete;

  /// Reports after the steps whose stepCount() is a multiple of this.
  int every() const { return every_; }
  /// Whether a simulator that has taken `steps` steps reports now (`steps` % every() == 0).
  bool due(int steps) const { return steps % every_ == 0; }
  /// Called after an accepted step that is due: `simulator` is in the state after the step,
  /// `report` is that step's report (the same as simulator.lastReport()).
  virtual void report(const Simulator& simulator, const StepReport& report) = 0;
  /// The reporter as ReporterError's message names it.
  virtual std::string name() const;

 private:
  int every_;
};

/// Writes one CSV row per reported step: the frame (report.step + 1: the steps taken, so that 0
/// can be the initial state), time, the energies by term and their total, the target H*, the
/// booked energies (forcing, damping, event, friction, contact projection), the blend's branch,
/// alpha and velocity scale, the iterations, energy evaluations and the phase timings in seconds.
/// Numbers have 17 significant digits (timings 9), so that a reader gets the doubles back. Every
/// row is flushed as it is written: the file is complete after each report, and a full disk
/// shows at the row that did not fit. stabint-run's --csv writes this format.
class CsvReporter : public Reporter {
 public:
  /// Creates or truncates the file `path` and writes the header row; throws FileFormatError when
  /// it cannot be written.
  explicit CsvReporter(const std::string& path, int every = 1);
  /// Writes to `out` (which must outlive the reporter), called `name` in messages (e.g. "standard
  /// output").
  CsvReporter(std::ostream& out, std::string name, int every = 1);
  ~CsvReporter() override;

  /// Writes row(report.step + 1, report).
  void report(const Simulator& simulator, const StepReport& report) override;
  /// Writes one row labelled `frame`; throws FileFormatError when the write fails.
  void row(int frame, const StepReport& report);
  /// The row of the simulator's current state before any step: frame 0, its energy and target.
  void initialRow(const Simulator& simulator);
  /// "CsvReporter('path')".
  std::string name() const override;
  /// The header row's column names, comma-separated, without the newline.
  static const char* header();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Calls a function after every every()-th accepted step.
class CallbackReporter : public Reporter {
 public:
  /// The function called with the simulator and the step's report.
  using Function = std::function<void(const Simulator&, const StepReport&)>;
  /// Throws InvalidInputError for an empty function or `every` < 1. `name` is what messages call
  /// it.
  explicit CallbackReporter(Function function, int every = 1, std::string name = "CallbackReporter");
  void report(const Simulator& simulator, const StepReport& report) override;
  std::string name() const override;

 private:
  Function function_;
  std::string name_;
};

}  // namespace stabint
