// Simulator: a batch of one (docs/batch_design.md, "A Simulator is a batch of one"). Stepping,
// the blend, forcing, contact, damping, events, element changes and checkpoints are the one
// stepping driver's (BatchDriver, batch_simulator.hpp) on one segment that is the whole scene, in
// its Simulator mode (BatchDriver::forSimulator): a refused step throws and changes nothing,
// messages are the whole scene's, and a checkpoint restores at any time. What is left here maps
// the public calls onto scene 0 and keeps the report of the last completed step.
#include <stabint/simulator.hpp>

#include "driver/batch_simulator.hpp"
#include "state/checkpoint.hpp"
#include "common/out_of_memory.hpp"

#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace stabint {

struct Simulator::Impl {
  Impl(const Scene& scene, const SimulatorOptions& options) : driver(BatchDriver::forSimulator(scene, options)) {}

  const BatchDriver::PerScene& state() const { return driver->book(0); }
  double time() const { return driver->time(); }
  FrameInput input(const char* call) const { return driver->frameInput(0, call); }

  // A refusal throws from inside the driver's step before anything is committed: the report of
  // the last completed step stays.
  const StepReport& step() {
    report = driver->step().scenes[0];
    return report;
  }

  // The reporters due after an accepted step, in the order they were added (a copy of the list:
  // a reporter may add or remove reporters). One that throws stops the rest for this step and
  // becomes a ReporterError; the step stands.
  void runReporters(const Simulator& simulator) {
    if (reporters.empty()) return;
    const int steps = simulator.stepCount();
    const std::vector<std::shared_ptr<Reporter>> due = reporters;
    for (const std::shared_ptr<Reporter>& reporter : due) {
      if (!reporter->due(steps)) continue;
      try {
        reporter->report(simulator, report);
      } catch (...) {
        const std::exception_ptr cause = std::current_exception();
        std::string what;
        try {
          std::rethrow_exception(cause);
        } catch (const std::exception& e) {
          what = e.what();
        } catch (...) {
          what = "an exception not derived from std::exception";
        }
        throw ReporterError("reporter " + reporter->name() + " failed after step " + std::to_string(report.step) +
                                " (the step is kept): " + what,
                            report.step, cause);
      }
    }
  }

  std::unique_ptr<BatchDriver> driver;
  StepReport report;  // of the last completed step (lastReport)
  std::vector<std::shared_ptr<Reporter>> reporters;
};

Simulator::Simulator(const Scene& scene, const SimulatorOptions& options)
    : impl_(reportingOutOfMemory("Simulator", [&] { return std::make_unique<Impl>(scene, options); })) {}
Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

const StepReport& Simulator::step() {
  const StepReport& report =
      reportingOutOfMemory("Simulator::step", [&]() -> const StepReport& { return impl_->step(); });
  reportingOutOfMemory("Simulator::step", [&] { impl_->runReporters(*this); });
  return report;
}

void Simulator::addReporter(std::shared_ptr<Reporter> reporter) {
  if (!reporter) throw InvalidInputError("addReporter: the reporter is null");
  for (const std::shared_ptr<Reporter>& r : impl_->reporters) {
    if (r == reporter) throw InvalidInputError("addReporter: " + reporter->name() + " is already attached");
  }
  reportingOutOfMemory("Simulator::addReporter", [&] { impl_->reporters.push_back(std::move(reporter)); });
}
bool Simulator::removeReporter(const std::shared_ptr<Reporter>& reporter) {
  auto& list = impl_->reporters;
  for (auto it = list.begin(); it != list.end(); ++it) {
    if (*it == reporter) {
      list.erase(it);
      return true;
    }
  }
  return false;
}
void Simulator::clearReporters() { impl_->reporters.clear(); }
const std::vector<std::shared_ptr<Reporter>>& Simulator::reporters() const { return impl_->reporters; }
const Eigen::MatrixX3d& Simulator::positions() const { return impl_->driver->allPositions(); }
const Eigen::MatrixX3d& Simulator::velocities() const { return impl_->driver->allVelocities(); }
double Simulator::time() const { return impl_->time(); }
int Simulator::stepCount() const { return static_cast<int>(impl_->state().steps); }
double Simulator::target() const { return impl_->driver->target(0); }
EnergyReport Simulator::energy() const { return impl_->driver->energy(0); }
double Simulator::energyScale() const { return impl_->state().energy_scale; }
const Scene& Simulator::scene() const { return impl_->driver->publicScene(); }
const SimulatorOptions& Simulator::options() const { return impl_->driver->options(); }
const StepReport& Simulator::lastReport() const { return impl_->report; }
std::string Simulator::backendDescription() const { return impl_->driver->backendDescription(); }

// ---- per-frame input, events and element changes: the driver's on scene 0 ------------------------
void Simulator::setPinTarget(int pin, const Eigen::Vector3d& target) {
  impl_->input("setPinTarget").setPinTarget(pin, target, impl_->time());
}
Eigen::Vector3d Simulator::pinTarget(int pin) const { return impl_->input("pinTarget").pinTarget(pin, impl_->time()); }
void Simulator::setExternalForces(const Eigen::MatrixX3d& forces) { impl_->driver->setExternalForces(0, forces); }
void Simulator::setColliderPosition(int collider, const Eigen::Vector3d& position) {
  impl_->input("setColliderPosition").setColliderPosition(collider, position, impl_->time());
}
void Simulator::setColliderVelocity(int collider, const Eigen::Vector3d& velocity) {
  impl_->input("setColliderVelocity").setColliderVelocity(collider, velocity, impl_->time());
}
Eigen::Vector3d Simulator::colliderPosition(int collider) const {
  return impl_->input("colliderPosition").colliderPosition(collider, impl_->time());
}
Eigen::Vector3d Simulator::colliderVelocity(int collider) const {
  return impl_->input("colliderVelocity").colliderVelocity(collider, impl_->time());
}
void Simulator::setState(const Eigen::MatrixX3d& positions, const Eigen::MatrixX3d& velocities) {
  impl_->driver->setState(0, positions, velocities);
}
void Simulator::setPositions(const Eigen::MatrixX3d& positions) { setState(positions, velocities()); }
void Simulator::setVelocities(const Eigen::MatrixX3d& velocities) { setState(positions(), velocities); }
void Simulator::setIterations(int iterations) { impl_->driver->setIterations(iterations); }
int Simulator::grab(int vertex, double stiffness) { return impl_->driver->grab(0, vertex, stiffness); }
void Simulator::release(int pin) { impl_->driver->release(0, pin); }
void Simulator::setElementStiffness(ElementKind kind, int index, double stiffness) {
  impl_->driver->changeElements(0, kind, {index}, &stiffness, true);
}
void Simulator::setElementStiffness(ElementKind kind, const std::vector<int>& indices, double stiffness) {
  impl_->driver->changeElements(0, kind, indices, &stiffness, true);
}
void Simulator::setElementEnabled(ElementKind kind, int index, bool enabled) {
  impl_->driver->changeElements(0, kind, {index}, nullptr, enabled);
}
void Simulator::setElementEnabled(ElementKind kind, const std::vector<int>& indices, bool enabled) {
  impl_->driver->changeElements(0, kind, indices, nullptr, enabled);
}
bool Simulator::elementEnabled(ElementKind kind, int index) const {
  return impl_->driver->elementChanges(0, "elementEnabled").enabled(kind, index);
}

// ---- checkpoints: scene 0's, in the format a batch's scenes share -------------------------------
Checkpoint Simulator::checkpoint() const { return impl_->driver->checkpointOf(impl_->driver->batchData(), 0); }

// The batch of one takes the checkpoint's time, as restoring a whole batch does; a refused
// restore changes nothing, its factors included (BatchDriver::restoreChecked), and its message
// starts with "restore: ".
void Simulator::restore(const Checkpoint& checkpoint) {
  reportingOutOfMemory("Simulator::restore", [&] {
    const CheckpointData d = parseCheckpoint(checkpoint.bytes(), "restore: checkpoint");
    impl_->driver->restoreAll(d.time, {d});
    impl_->report = StepReport{};
  });
}

}  // namespace stabint
