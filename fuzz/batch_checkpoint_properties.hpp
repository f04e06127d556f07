#pragma once
// The promises a batch's restore keeps on arbitrary bytes, as checkpoint_properties.hpp states
// them for a Simulator, checked by the mutation test (tests/test_checkpoint_mutation.cpp) and the
// batch checkpoint fuzzer (fuzz_batch_checkpoint.cpp):
//   - BatchCheckpoint::fromBytes accepts the bytes or throws a stabint::Error, nothing else;
//   - a refused restore leaves the batch as it was: its time, and every scene's step count, H*,
//     activity, positions and velocities bit for bit;
//   - a restored batch steps: BatchSimulator::step reports a scene's blow-up as its refusal and
//     throws nothing.
#include "checkpoint_properties.hpp"

#include <stabint/batch.hpp>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace stabint::batch_checkpoint_properties {

/// The batch of the seed: checkpoint_properties::scene() and a 3 x 3 cloth.
inline std::vector<Scene> scenes() {
  ClothGridParams small;
  small.nx = small.ny = 3;
  return {checkpoint_properties::scene(), makeClothGrid(small)};
}

/// A whole-batch checkpoint after a few steps, a grab in scene 0 and a stiffness change in
/// scene 1: every section of every scene's checkpoint has content.
inline std::string seed() {
  BatchSimulator batch(scenes(), checkpoint_properties::options());
  for (int i = 0; i < 3; ++i) batch.step();
  const int handle = batch.grab(0, 5, 2e3);
  batch.setPinTarget(0, handle, batch.positions(0).row(5).transpose() + Eigen::Vector3d(0.05, 0.0, 0.0));
  batch.setElementStiffness(1, ElementKind::Spring, 2, 2e3);
  batch.step();
  return batch.checkpoint().bytes();
}

/// Re-signs what a batch checkpoint's layout still frames (each scene's checkpoint whose size fits,
/// then the whole: the header is 8 magic bytes, a 4-byte version, the time, the scene count, each
/// scene's size and bytes, and the checksum), so that changed bytes reach the field checks and the
/// restore.
inline void resign(std::string& bytes) {
  std::size_t pos = 8 + 4 + 8;
  std::int64_t count = 0;
  if (bytes.size() >= pos + sizeof count + 8) {
    std::memcpy(&count, bytes.data() + pos, sizeof count);
    pos += sizeof count;
    for (std::int64_t s = 0; s < count && s < 64; ++s) {
      std::int64_t size = 0;
      if (bytes.size() < pos + sizeof size + 8) break;
      std::memcpy(&size, bytes.data() + pos, sizeof size);
      pos += sizeof size;
      if (size < 8 || std::uint64_t(size) > bytes.size() - 8 - pos) break;
      std::string scene = bytes.substr(pos, std::size_t(size));
      checkpoint_properties::resign(scene);
      bytes.replace(pos, std::size_t(size), scene);
      pos += std::size_t(size);
    }
  }
  checkpoint_properties::resign(bytes);
}

using checkpoint_properties::Outcome;
using checkpoint_properties::Result;

/// Restores `bytes` into a fresh batch of scenes() that took two steps, then takes `steps`.
inline Result check(const std::string& bytes, int steps) {
  Result r;
  BatchCheckpoint checkpoint;
  try {
    checkpoint = BatchCheckpoint::fromBytes(bytes, "mutated");
  } catch (const Error&) {
    return r;
  }
  BatchSimulator batch(scenes(), checkpoint_properties::options());
  batch.step();
  batch.step();
  const double time = batch.time();
  const Eigen::MatrixX3d x = batch.allPositions();
  std::vector<Eigen::MatrixX3d> v;
  std::vector<double> targets;
  std::vector<int> counts;
  std::vector<bool> active;
  for (int s = 0; s < batch.size(); ++s) {
    v.push_back(batch.velocities(s));
    targets.push_back(batch.target(s));
    counts.push_back(batch.stepCount(s));
    active.push_back(batch.active(s));
  }
  try {
    batch.restore(checkpoint);
  } catch (const Error&) {
    r.outcome = Outcome::Refused;
    bool same = batch.time() == time && batch.allPositions() == x;
    for (int s = 0; s < batch.size(); ++s)
      same = same && batch.velocities(s) == v[std::size_t(s)] && batch.target(s) == targets[std::size_t(s)] &&
             batch.stepCount(s) == counts[std::size_t(s)] && batch.active(s) == active[std::size_t(s)];
    if (!same) r.violation = "a refused restore changed the batch";
    return r;
  }
  r.outcome = Outcome::Restored;
  for (int i = 0; i < steps; ++i) {
    const BatchStepReport& report = batch.step();
    bool stepped = false;
    for (const std::string& refusal : report.refusals) stepped = stepped || refusal.empty();
    if (stepped) ++r.steps_taken;
  }
  return r;
}

}  // namespace stabint::batch_checkpoint_properties
