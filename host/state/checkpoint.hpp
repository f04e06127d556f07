#pragma once
// The contents of a Checkpoint and its binary form: one place that writes and one that reads
// (with every size checked), shared by the in-memory and the file checkpoints.
#include "backend/backend.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace stabint {

/// A scene's energy books between steps: its clock, its energies, H* and the event energy the next
/// step reports. One value, which the driver keeps per scene (BatchDriver::PerScene) and a
/// checkpoint holds (CheckpointData), so that saving and restoring them is one assignment.
struct SceneBook {
  double time = 0.0;
  std::int64_t steps = 0;
  double target = 0.0;  // H*
  double kinetic = 0.0;
  PotentialEnergy potential;          // of the state at `time`
  double pending_event_energy = 0.0;  // booked by events since the last step
  // The energy the scene reports, and H summed as that report sums it, so that an event books
  // exactly the jump between the energies reported before and after it.
  EnergyReport report() const { return EnergyReport{kinetic, potential.elastic(), potential.external}; }
  double energy() const { return report().total(); }
};

/// Where the particles are and how they move: positions, velocities and, for BDF2, the previous
/// step's (has_history: the previous step is there).
struct MotionState {
  bool has_history = false;
  Eigen::MatrixX3d x, v, x_prev, v_prev;
};

/// A scene's whole state as one value, and a checkpoint's contents: the parts its owners give and
/// take as values (docs/method.md, "Checkpoints"): the book (the driver's per scene; for a whole
/// batch's, the batch's time only), the motion (the driver's host copies and the backend's
/// history slots), the forcing (Forcing::state), the elements (SceneData::elementState) and the
/// contact set's changes (ContactResolver::log). serializeCheckpoint writes it as it is.
struct CheckpointData : SceneBook {
  std::uint64_t scene_fingerprint = 0;  // sceneFingerprint() of the scene it belongs to
  std::int64_t particles = 0;
  MotionState motion;
  Forcing::State forcing;
  ElementState elements;
  /// The contact set's changes since the global matrix was last assembled: e + 1 entering,
  /// -(e + 1) leaving, 0 closing a step's batch.
  std::vector<std::int32_t> contact_log;
};

/// FNV-1a over the masses, rest positions and colliders (every field): tells a checkpoint of
/// another scene apart.
std::uint64_t sceneFingerprint(const Scene& scene);

/// What a checkpoint must fit: one scene, a Simulator's or one of a batch (whose SceneData is the
/// concatenation, so the counts are the scene's segment's).
struct RestoreTarget {
  std::uint64_t fingerprint = 0;  // sceneFingerprint() of the scene alone
  std::int64_t particles = 0;
  std::vector<int> element_counts;  // per block; the pin block's comes with the checkpoint
  int pin_block = -1;
  int contact_block = -1;  // -1: none
  std::size_t colliders = 0;
  std::string where;  // the messages' prefix ("restore: scene 2: "; "restore: " for a Simulator)
};

/// What a restore can check before it changes anything: InvalidInputError unless `d` belongs to
/// the target (particles, fingerprint, element and collider counts, its contact log, pin
/// vertices).
void checkRestorable(const CheckpointData& d, const RestoreTarget& target);

std::string serializeCheckpoint(const CheckpointData& data);
/// The checksum that ends a serialized checkpoint (FNV-1a, 64 bits), for other formats that hold
/// checkpoints (a batch's).
std::uint64_t checkpointChecksum(const char* data, std::size_t size);
/// Writes `bytes` to the file `path` (replacing it); FileFormatError naming the file and `what`
/// ("checkpoint", "batch checkpoint") when it cannot be opened or written.
void writeCheckpointFile(const std::string& path, const std::string& bytes, const std::string& what);
/// Throws FileFormatError(origin, 0, ...) for a wrong header, version, or truncated/oversized data.
CheckpointData parseCheckpoint(const std::string& bytes, const std::string& origin);

}  // namespace stabint
