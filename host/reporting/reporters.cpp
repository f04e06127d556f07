// The built-in reporters (include/stabint/reporters.hpp): the CSV of per-step energies and
// timings (stabint-run's --csv writes it too) and the callback.
#include <stabint/reporters.hpp>
#include <stabint/simulator.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <ostream>
#include <string>
#include <utility>

namespace stabint {

Reporter::Reporter(int every) : every_(every) {
  if (every < 1) throw InvalidInputError("Reporter: every must be >= 1, got " + std::to_string(every));
}
Reporter::~Reporter() = default;
std::string Reporter::name() const { return "Reporter"; }

// ---- CsvReporter ---------------------------------------------------------------------------------

// Every write is checked and flushed: a full disk (/dev/full) or a closed file is a
// FileFormatError at the row that failed, not a file silently cut short.
struct CsvReporter::Impl {
  Impl(std::ostream* out, std::string name) : out(out), name(std::move(name)) {}

  void check() const {
    if (!*out) {
      throw FileFormatError(
          name, 0,
          std::string("write failed") + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
    }
  }
  void write(const char* text) {
    errno = 0;
    *out << text;
    out->flush();
    check();
  }

  std::ofstream file;
  std::ostream* out;
  std::string name;
};

const char* CsvReporter::header() {
  return "frame,time,kinetic,elastic,external,total,target,forcing,damping,event_energy,friction,contact_projection,"
         "branch,alpha,velocity_scale,iterations,energy_evaluations,local_s,gather_s,transfer_s,global_s,energy_s,"
         "bookkeeping_s";
}

CsvReporter::CsvReporter(const std::string& path, int every)
    : Reporter(every), impl_(std::make_unique<Impl>(nullptr, path)) {
  errno = 0;
  impl_->file.open(path);
  impl_->out = &impl_->file;
  if (!impl_->file) {
    throw FileFormatError(
        path, 0, std::string("cannot write") + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
  }
  impl_->write((std::string(header()) + "\n").c_str());
}

CsvReporter::CsvReporter(std::ostream& out, std::string name, int every)
    : Reporter(every), impl_(std::make_unique<Impl>(&out, std::move(name))) {
  impl_->write((std::string(header()) + "\n").c_str());
}

CsvReporter::~CsvReporter() = default;

void CsvReporter::report(const Simulator&, const StepReport& report) { row(report.step + 1, report); }

void CsvReporter::row(int frame, const StepReport& r) {
  const EnergyReport& e = r.energy;
  const PhaseTimes& t = r.times;
  char buf[768];
  std::snprintf(buf, sizeof(buf),
                "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%.17g,%.17g,%d,%d,%.9g,%.9g,%."
                "9g,%.9g,%.9g,%.9g\n",
                frame, r.time, e.kinetic, e.elastic, e.external, e.total(), r.target, r.forcing, r.damping,
                r.event_energy, r.friction, r.contact_projection, blendBranchName(r.branch), r.alpha, r.velocity_scale,
                r.iterations, r.energy_evaluations, t.local, t.gather, t.transfer, t.global, t.energy, t.bookkeeping);
  impl_->write(buf);
}

void CsvReporter::initialRow(const Simulator& simulator) {
  StepReport initial;
  initial.time = simulator.time();
  initial.energy = simulator.energy();
  initial.target = simulator.target();
  row(simulator.stepCount(), initial);
}

std::string CsvReporter::name() const { return "CsvReporter('" + impl_->name + "')"; }

// ---- CallbackReporter ----------------------------------------------------------------------------

CallbackReporter::CallbackReporter(Function function, int every, std::string name)
    : Reporter(every), function_(std::move(function)), name_(std::move(name)) {
  if (!function_) throw InvalidInputError("CallbackReporter: the function is empty");
}

void CallbackReporter::report(const Simulator& simulator, const StepReport& report) { function_(simulator, report); }

std::string CallbackReporter::name() const { return name_; }

}  // namespace stabint
