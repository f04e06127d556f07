// The public class BatchSimulator (include/stabint/batch.hpp): its construction, step and
// getters over its driver, BatchDriver (batch_simulator.cpp); its input is in batch_input.cpp, its
// checkpoints in batch_checkpoint.cpp.
#include "driver/batch_simulator.hpp"

#include "common/out_of_memory.hpp"

#include <cstddef>
#include <memory>
#include <string>

namespace stabint {

BatchSimulator::BatchSimulator(const std::vector<Scene>& scenes, const SimulatorOptions& options)
    : impl_(reportingOutOfMemory("BatchSimulator", [&] { return std::make_unique<Impl>(scenes, options); })) {}
BatchSimulator::~BatchSimulator() = default;
BatchSimulator::BatchSimulator(BatchSimulator&&) noexcept = default;
BatchSimulator& BatchSimulator::operator=(BatchSimulator&&) noexcept = default;

const BatchStepReport& BatchSimulator::step() {
  return reportingOutOfMemory("BatchSimulator::step", [&]() -> const BatchStepReport& { return impl_->step(); });
}
int BatchSimulator::size() const { return impl_->size(); }
bool BatchSimulator::active(int scene) const {
  impl_->checkScene(scene, "active");
  return impl_->book(scene).active;
}
Eigen::MatrixX3d BatchSimulator::positions(int scene) const {
  impl_->checkScene(scene, "positions");
  return impl_->positions(scene);
}
Eigen::MatrixX3d BatchSimulator::velocities(int scene) const {
  impl_->checkScene(scene, "velocities");
  return impl_->velocities(scene);
}
const Eigen::MatrixX3d& BatchSimulator::allPositions() const { return impl_->allPositions(); }
int BatchSimulator::firstParticle(int scene) const {
  impl_->checkScene(scene, "firstParticle");
  return impl_->segment(scene).first_particle;
}
int BatchSimulator::numParticles(int scene) const {
  impl_->checkScene(scene, "numParticles");
  return impl_->segment(scene).num_particles;
}
double BatchSimulator::time() const { return impl_->time(); }
double BatchSimulator::time(int scene) const {
  impl_->checkScene(scene, "time");
  return impl_->book(scene).time;
}
int BatchSimulator::stepCount(int scene) const {
  impl_->checkScene(scene, "stepCount");
  return static_cast<int>(impl_->book(scene).steps);
}
double BatchSimulator::target(int scene) const {
  impl_->checkScene(scene, "target");
  return impl_->target(scene);
}
EnergyReport BatchSimulator::energy(int scene) const {
  impl_->checkScene(scene, "energy");
  return impl_->energy(scene);
}
double BatchSimulator::energyScale(int scene) const {
  impl_->checkScene(scene, "energyScale");
  return impl_->book(scene).energy_scale;
}
const SimulatorOptions& BatchSimulator::options() const { return impl_->options(); }
std::string BatchSimulator::backendDescription() const { return impl_->backendDescription(); }
}  // namespace stabint
