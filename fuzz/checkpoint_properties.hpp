#pragma once
// The promises a checkpoint restore keeps on arbitrary bytes (issue 20), checked by the mutation
// test (tests/test_checkpoint_mutation.cpp) and the checkpoint fuzzer (fuzz_checkpoint.cpp):
//   - Checkpoint::fromBytes accepts the bytes or throws a stabint::Error, nothing else;
//   - a refused restore leaves the simulator as it was: time, step count, H*, positions and
//     velocities bit for bit;
//   - a restored simulator steps, or refuses a step with a stabint::Error.
// Anything else escaping (std::bad_alloc, a standard exception) propagates to the caller.
#include <stabint/stabint.hpp>

#include <string>

namespace stabint::checkpoint_properties {

/// The scene of the seed checkpoints: a 4 x 4 spring cloth, pinned at two corners.
inline Scene scene() {
  ClothGridParams p;
  p.nx = p.ny = 4;
  return makeClothGrid(p);
}

inline SimulatorOptions options() {
  SimulatorOptions o;
  o.integrator = Integrator::EnergyBlend;
  return o;
}

/// A checkpoint of scene() after a few steps, a grab and a stiffness change: every section of
/// the format has content.
inline std::string seed() {
  Simulator sim(scene(), options());
  for (int i = 0; i < 3; ++i) sim.step();
  const int handle = sim.grab(5, 2e3);
  sim.setPinTarget(handle, sim.positions().row(5).transpose() + Eigen::Vector3d(0.05, 0.0, 0.0));
  sim.setElementStiffness(ElementKind::Spring, 2, 2e3);
  sim.step();
  return sim.checkpoint().bytes();
}

/// Overwrites the last 8 bytes with the FNV-1a 64 checksum of the others (the format's own), so
/// that changed bytes reach the field checks and the restore.
inline void resign(std::string& bytes) {
  if (bytes.size() < 8) return;
  std::uint64_t hash = 14695981039346656037ull;
  for (std::size_t i = 0; i + 8 < bytes.size(); ++i) {
    hash ^= static_cast<unsigned char>(bytes[i]);
    hash *= 1099511628211ull;
  }
  for (int b = 0; b < 8; ++b) bytes[bytes.size() - 8 + std::size_t(b)] = static_cast<char>((hash >> (8 * b)) & 0xff);
}

enum class Outcome { Unreadable, Refused, Restored };

struct Result {
  Outcome outcome = Outcome::Unreadable;
  std::string violation;  // empty when every promise held
  int steps_taken = 0;    // of `steps` after an accepted restore
};

/// Restores `bytes` into a fresh simulator of scene() that took two steps, then takes `steps`.
inline Result check(const std::string& bytes, int steps) {
  Result r;
  Checkpoint checkpoint;
  try {
    checkpoint = Checkpoint::fromBytes(bytes, "mutated");
  } catch (const Error&) {
    return r;
  }
  Simulator sim(scene(), options());
  sim.step();
  sim.step();
  const double time = sim.time(), target = sim.target();
  const int count = sim.stepCount();
  const Eigen::MatrixX3d x = sim.positions(), v = sim.velocities();
  try {
    sim.restore(checkpoint);
  } catch (const Error&) {
    r.outcome = Outcome::Refused;
    if (sim.time() != time || sim.stepCount() != count || sim.target() != target || sim.positions() != x ||
        sim.velocities() != v)
      r.violation = "a refused restore changed the simulator";
    return r;
  }
  r.outcome = Outcome::Restored;
  for (int i = 0; i < steps; ++i) {
    try {
      sim.step();
      ++r.steps_taken;
    } catch (const Error&) {
    }
  }
  return r;
}

}  // namespace stabint::checkpoint_properties
