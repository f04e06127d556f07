#include "state/checkpoint.hpp"

#include "contact/contact_resolver.hpp"
#include "elements/element_type.hpp"
#include "common/text_reader.hpp"
#include "common/out_of_memory.hpp"
#include "common/validation.hpp"

#include <stabint/simulator.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <type_traits>

namespace stabint {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'B', 'C', 'K', 'P', 'T', '\n'};
// 2: element stiffnesses and enabled flags; 3: collider motion and the contact set's update log
// (a version 2 checkpoint is read with the colliders on their scene laws, which is all they could
// do then, and an empty log); 4: a checksum over everything before it, at the end.
constexpr std::uint32_t kVersion = 4;
constexpr std::uint32_t kOldestVersion = 2;
constexpr std::uint32_t kFirstChecksummedVersion = 4;
// Steps a restored simulator may still take before its int step count would overflow.
constexpr std::int64_t kMostSteps = std::int64_t(1) << 30;

// FNV-1a, 64 bits: `hash` continued over `size` bytes. The scene fingerprint and the checksum of
// version 4 and later.
std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t hash) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ull;
  }
  return hash;
}
std::uint64_t checksum(const char* data, std::size_t size) { return fnv1a(data, size, 14695981039346656037ull); }

class Writer {
 public:
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void flag(bool b) { value(static_cast<std::uint8_t>(b ? 1 : 0)); }
  // Rows and columns first, then the values row by row.
  void matrix(const Eigen::MatrixX3d& m) {
    value(static_cast<std::int64_t>(m.rows()));
    for (Eigen::Index i = 0; i < m.rows(); ++i)
      for (int c = 0; c < 3; ++c) value(m(i, c));
  }
  void vector(const Eigen::Vector3d& v) {
    for (int c = 0; c < 3; ++c) value(v[c]);
  }
  void pin(const Pin& p) {
    value(static_cast<std::int64_t>(p.vertex));
    value(p.stiffness);
    vector(p.target.position);
    vector(p.target.velocity);
    vector(p.target.amplitude);
    value(p.target.frequency);
  }
  void ramp(const Forcing::Ramp& r) {
    flag(r.active);
    value(r.t0);
    value(r.t1);
    matrix(r.start);
    matrix(r.end);
  }
  void motion(const Forcing::ColliderMotion& m) {
    value(m.t0);
    value(m.t1);
    vector(m.start);
    vector(m.end);
    vector(m.velocity);
    flag(m.driven);
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class Reader {
 public:
  // Reads bytes[0, end) (the payload before a checksum); end defaults to all of them.
  Reader(const std::string& bytes, const std::string& origin, std::size_t end = std::string::npos)
      : bytes_(bytes), origin_(origin), end_(std::min(end, bytes.size())) {}

  template <typename T>
  T value(const char* what) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (end_ - pos_ < sizeof(T)) fail(std::string("truncated at ") + what);
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  // A value that is part of the state: finite and at most validation::kMaxMagnitude, the rule of
  // every input (an energy may be larger, but finite).
  double real(const char* what) {
    const auto v = value<double>(what);
    if (!std::isfinite(v)) fail(std::string(what) + ": not finite");
    if (!(std::abs(v) <= validation::kMaxMagnitude)) fail(std::string(what) + ": beyond 1e150 in magnitude");
    return v;
  }
  double energy(const char* what) {
    const auto v = value<double>(what);
    if (!std::isfinite(v)) fail(std::string(what) + ": not finite");
    return v;
  }
  bool flag(const char* what) {
    const auto b = value<std::uint8_t>(what);
    if (b > 1) fail(std::string(what) + ": not a flag");
    return b == 1;
  }
  // A matrix of `expected_rows` rows (checked before anything is allocated).
  Eigen::MatrixX3d matrix(std::int64_t expected_rows, const char* what) {
    const auto rows = value<std::int64_t>(what);
    if (rows != expected_rows)
      fail(std::string(what) + ": " + std::to_string(rows) + " rows, expected " + std::to_string(expected_rows));
    Eigen::MatrixX3d m(rows, 3);
    for (Eigen::Index i = 0; i < rows; ++i)
      for (int c = 0; c < 3; ++c) m(i, c) = real(what);
    return m;
  }
  Eigen::Vector3d vector(const char* what) {
    Eigen::Vector3d v;
    for (int c = 0; c < 3; ++c) v[c] = real(what);
    return v;
  }
  // Vertex indices are checked against the scene when the checkpoint is restored.
  Pin pin() {
    Pin p;
    const auto vertex = value<std::int64_t>("a pin");
    if (vertex < 0 || vertex > std::numeric_limits<int>::max()) fail("pin vertex out of range");
    p.vertex = static_cast<int>(vertex);
    p.stiffness = real("a pin's stiffness");
    if (!(p.stiffness >= 0.0)) fail("a pin's stiffness is negative");
    p.target.position = vector("a pin's target");
    p.target.velocity = vector("a pin's target");
    p.target.amplitude = vector("a pin's target");
    p.target.frequency = real("a pin's target");
    return p;
  }
  Forcing::Ramp ramp(std::int64_t rows, const char* what) {
    Forcing::Ramp r;
    r.active = flag(what);
    r.t0 = real(what);
    r.t1 = real(what);
    if (!(r.t1 >= r.t0)) fail(std::string(what) + ": ends before it starts");
    r.start = matrix(r.active ? rows : 0, what);
    r.end = matrix(r.active ? rows : 0, what);
    return r;
  }
  Forcing::ColliderMotion motion() {
    Forcing::ColliderMotion m;
    m.t0 = real("a collider's motion");
    m.t1 = real("a collider's motion");
    m.start = vector("a collider's motion");
    m.end = vector("a collider's motion");
    m.velocity = vector("a collider's motion");
    m.driven = flag("a collider's motion");
    if (!std::isfinite(m.t0) || !std::isfinite(m.t1) || !(m.t1 >= m.t0) || !m.start.allFinite() || !m.end.allFinite() ||
        !m.velocity.allFinite())
      fail("a collider's motion is not finite or ends before it starts");
    return m;
  }
  void expectEnd() {
    if (pos_ != end_) fail(std::to_string(end_ - pos_) + " bytes after the end");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw FileFormatError(origin_, 0, "not a valid stabint checkpoint: " + what);
  }

 private:
  const std::string& bytes_;
  const std::string& origin_;
  std::size_t end_;
  std::size_t pos_ = 0;
};

// Counts that size allocations come from an untrusted file: at most what the remaining bytes
// can hold (three doubles a row), checked before anything is allocated.
void checkCount(Reader& in, std::int64_t count, std::size_t bytes, const char* what) {
  if (count < 0 || static_cast<std::uint64_t>(count) > bytes / (3 * sizeof(double)))
    in.fail(std::string(what) + " = " + std::to_string(count) + " does not fit the data");
}

}  // namespace

std::uint64_t sceneFingerprint(const Scene& scene) {
  // The start value is one digit short of FNV's offset basis; kept, or every saved checkpoint's
  // fingerprint would change.
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&](const double* data, Eigen::Index count) {
    hash = fnv1a(data, static_cast<std::size_t>(count) * sizeof(double), hash);
  };
  mix(scene.masses.data(), scene.masses.size());
  mix(scene.rest_positions.data(), scene.rest_positions.size());
  // The colliders shape the motion as much as the masses do. A scene without colliders mixes
  // nothing here, so checkpoints of such scenes written before colliders existed still match.
  // Where run-time input moved them is state, not identity: it is saved with the forcing and
  // restored, not compared.
  for (const Collider& c : scene.colliders) {
    const double fields[] = {static_cast<double>(c.shape),
                             c.center.x(),
                             c.center.y(),
                             c.center.z(),
                             c.normal.x(),
                             c.normal.y(),
                             c.normal.z(),
                             c.half_extents.x(),
                             c.half_extents.y(),
                             c.half_extents.z(),
                             c.end.x(),
                             c.end.y(),
                             c.end.z(),
                             c.radius,
                             c.velocity.x(),
                             c.velocity.y(),
                             c.velocity.z(),
                             c.friction,
                             c.stiffness,
                             c.elastic_ratio};
    mix(fields, static_cast<Eigen::Index>(std::size(fields)));
    // A restitution other than the default: checkpoints written before it existed still match.
    if (c.restitution != 1.0) {
      const double restitution[] = {c.restitution};
      mix(restitution, 1);
    }
    // A collider on some particles only; one on all of them (the default) mixes nothing more, so
    // checkpoints written before colliders had particle ranges still match.
    if (c.num_particles != -1) {
      const double particles[] = {static_cast<double>(c.first_particle), static_cast<double>(c.num_particles)};
      mix(particles, 2);
    }
    // A mesh's surface (other shapes have none, and mix nothing here).
    if (c.shape == ColliderShape::Mesh) {
      mix(c.mesh_vertices.data(), c.mesh_vertices.size());
      for (const std::array<int, 3>& t : c.mesh_triangles) {
        const double indices[] = {double(t[0]), double(t[1]), double(t[2])};
        mix(indices, 3);
      }
    }
  }
  return hash;
}

void checkRestorable(const CheckpointData& d, const RestoreTarget& target) {
  try {
    if (d.particles != target.particles || d.scene_fingerprint != target.fingerprint)
      throw InvalidInputError("checkpoint: it belongs to another scene (" + std::to_string(d.particles) +
                              " particles, or other masses, rest shape or colliders)");
    const std::size_t num_blocks = target.element_counts.size();
    if (d.elements.stiffness.size() != num_blocks)
      throw InvalidInputError("checkpoint: it belongs to another scene (" +
                              std::to_string(d.elements.stiffness.size()) + " element kinds, the scene's build has " +
                              std::to_string(num_blocks) + ")");
    for (std::size_t b = 0; b < num_blocks; ++b) {
      const std::size_t count =
          int(b) == target.pin_block ? d.elements.pins.size() : static_cast<std::size_t>(target.element_counts[b]);
      // A scene's contact elements are one per particle and collider, the self-contact scene's
      // support collider included (a checkpoint written before every such scene had one has fewer).
      if (d.elements.stiffness[b].size() != count)
        throw InvalidInputError("checkpoint: it belongs to another scene (" +
                                std::to_string(d.elements.stiffness[b].size()) + " " + elementTypes()[b]->name() +
                                " elements, the scene has " + std::to_string(count) + ")");
    }
    const std::size_t motions = d.forcing.colliders.size();
    if (motions != 0 && motions != target.colliders)
      throw InvalidInputError("checkpoint: it belongs to another scene (" + std::to_string(motions) + " colliders)");
    // Its checks of the contact log.
    if (target.contact_block < 0)
      ContactResolver::baseFlags(std::vector<std::uint8_t>(), d.contact_log);
    else
      ContactResolver::baseFlags(d.elements.enabled[std::size_t(target.contact_block)], d.contact_log);
    for (const Pin& p : d.elements.pins)
      if (p.vertex >= d.particles)
        throw InvalidInputError("checkpoint: pin vertex " + std::to_string(p.vertex) + " out of range (the scene has " +
                                std::to_string(d.particles) + " particles)");
  } catch (const InvalidInputError& e) {
    if (target.where.empty()) throw;
    throw InvalidInputError(target.where + e.what());
  }
}

std::uint64_t checkpointChecksum(const char* data, std::size_t size) { return checksum(data, size); }

std::string serializeCheckpoint(const CheckpointData& d) {
  Writer out;
  for (char c : kMagic) out.value(c);
  out.value(kVersion);
  out.value(d.scene_fingerprint);
  out.value(d.particles);
  out.value(static_cast<std::int64_t>(d.elements.pins.size()));
  out.value(d.time);
  out.value(d.steps);
  out.value(d.target);
  out.value(d.kinetic);
  out.value(d.potential.internal);
  out.value(d.potential.pins);
  out.value(d.potential.external);
  out.value(d.pending_event_energy);
  out.flag(d.motion.has_history);
  out.matrix(d.motion.x);
  out.matrix(d.motion.v);
  out.matrix(d.motion.x_prev);
  out.matrix(d.motion.v_prev);
  for (const Pin& p : d.elements.pins) out.pin(p);
  for (const Forcing::Ramp& r : d.forcing.pins) out.ramp(r);
  out.ramp(d.forcing.user_forces);
  const ElementState& elements = d.elements;
  out.value(static_cast<std::int64_t>(elements.stiffness.size()));
  for (std::size_t b = 0; b < elements.stiffness.size(); ++b) {
    out.value(static_cast<std::int64_t>(elements.stiffness[b].size()));
    for (double k : elements.stiffness[b]) out.value(k);
    for (std::uint8_t e : elements.enabled[b]) out.flag(e != 0);
  }
  out.value(static_cast<std::int64_t>(d.forcing.colliders.size()));
  for (const Forcing::ColliderMotion& m : d.forcing.colliders) out.motion(m);
  out.value(static_cast<std::int64_t>(d.contact_log.size()));
  for (std::int32_t entry : d.contact_log) out.value(entry);
  std::string bytes = out.take();
  const std::uint64_t sum = checksum(bytes.data(), bytes.size());
  bytes.append(reinterpret_cast<const char*>(&sum), sizeof sum);
  return bytes;
}

CheckpointData parseCheckpoint(const std::string& bytes, const std::string& origin) {
  Reader header(bytes, origin);
  for (char c : kMagic)
    if (header.value<char>("the header") != c) header.fail("wrong header");
  const auto version = header.value<std::uint32_t>("the version");
  if (version < kOldestVersion || version > kVersion)
    header.fail("format version " + std::to_string(version) + ", expected " + std::to_string(kOldestVersion) + " to " +
                std::to_string(kVersion));
  // Version 4 on: the last 8 bytes are the checksum of the others, checked before any field.
  std::size_t payload = bytes.size();
  if (version >= kFirstChecksummedVersion) {
    std::uint64_t stored = 0;
    if (bytes.size() < sizeof kMagic + sizeof version + sizeof stored) header.fail("truncated at the checksum");
    payload = bytes.size() - sizeof stored;
    std::memcpy(&stored, bytes.data() + payload, sizeof stored);
    if (stored != checksum(bytes.data(), payload))
      header.fail("the checksum does not match: the data is corrupted or was changed");
  }
  Reader in(bytes, origin, payload);
  for (std::size_t i = 0; i < sizeof kMagic + sizeof version; ++i) in.value<char>("the header");
  CheckpointData d;
  d.scene_fingerprint = in.value<std::uint64_t>("the scene fingerprint");
  d.particles = in.value<std::int64_t>("the particle count");
  const auto pins = in.value<std::int64_t>("the pin count");
  checkCount(in, d.particles, payload, "particle count");
  checkCount(in, pins, payload, "pin count");
  d.time = in.real("the time");
  d.steps = in.value<std::int64_t>("the step count");
  if (d.steps < 0 || d.steps > kMostSteps)
    in.fail("step count " + std::to_string(d.steps) + " out of range [0, " + std::to_string(kMostSteps) + "]");
  d.target = in.energy("the target");
  d.kinetic = in.energy("the kinetic energy");
  if (!(d.kinetic >= 0.0)) in.fail("the kinetic energy is negative");
  d.potential.internal = in.energy("the potential energy");
  d.potential.pins = in.energy("the potential energy");
  d.potential.external = in.energy("the potential energy");
  d.pending_event_energy = in.energy("the event energy");
  d.motion.has_history = in.flag("the history flag");
  d.motion.x = in.matrix(d.particles, "positions");
  d.motion.v = in.matrix(d.particles, "velocities");
  d.motion.x_prev = in.matrix(d.particles, "previous positions");
  d.motion.v_prev = in.matrix(d.particles, "previous velocities");
  d.elements.pins.reserve(static_cast<std::size_t>(pins));
  for (std::int64_t i = 0; i < pins; ++i) d.elements.pins.push_back(in.pin());
  d.forcing.pins.reserve(static_cast<std::size_t>(pins));
  for (std::int64_t i = 0; i < pins; ++i) d.forcing.pins.push_back(in.ramp(1, "a pin target"));
  d.forcing.user_forces = in.ramp(d.particles, "the external forces");
  // Element counts are checked against the scene when restored; here only against the data
  // (a stiffness and a flag each: 9 bytes).
  const auto blocks = in.value<std::int64_t>("the element block count");
  if (blocks < 0 || blocks > 64) in.fail("element block count " + std::to_string(blocks) + " out of range");
  for (std::int64_t b = 0; b < blocks; ++b) {
    const auto count = in.value<std::int64_t>("an element count");
    if (count < 0 || static_cast<std::uint64_t>(count) > payload / 9)
      in.fail("element count " + std::to_string(count) + " does not fit the data");
    std::vector<double> stiffness(static_cast<std::size_t>(count));
    for (double& k : stiffness) {
      k = in.real("an element stiffness");
      if (!(k >= 0.0)) in.fail("an element stiffness is negative");
    }
    std::vector<std::uint8_t> enabled(static_cast<std::size_t>(count));
    for (std::uint8_t& e : enabled) e = in.flag("an element flag") ? 1 : 0;
    d.elements.stiffness.push_back(std::move(stiffness));
    d.elements.enabled.push_back(std::move(enabled));
  }
  if (version >= 3) {
    // Checked against the scene's collider count when restored (the fingerprint covers them).
    const auto colliders = in.value<std::int64_t>("the collider count");
    constexpr std::size_t kMotionBytes = 11 * sizeof(double) + 1;
    if (colliders < 0 || static_cast<std::uint64_t>(colliders) > payload / kMotionBytes)
      in.fail("collider count " + std::to_string(colliders) + " does not fit the data");
    for (std::int64_t c = 0; c < colliders; ++c) d.forcing.colliders.push_back(in.motion());
    // Entries are checked against the scene's contact set when restored.
    const auto log_size = in.value<std::int64_t>("the contact log size");
    if (log_size < 0 || static_cast<std::uint64_t>(log_size) > payload / 4)
      in.fail("contact log size " + std::to_string(log_size) + " does not fit the data");
    d.contact_log.resize(static_cast<std::size_t>(log_size));
    for (std::int32_t& entry : d.contact_log) {
      entry = in.value<std::int32_t>("a contact log entry");
      if (entry == std::numeric_limits<std::int32_t>::min()) in.fail("a contact log entry is out of range");
    }
  }
  in.expectEnd();
  return d;
}

Checkpoint Checkpoint::fromBytes(std::string bytes, const std::string& origin) {
  const CheckpointData d =
      reportingOutOfMemory("Checkpoint::fromBytes", [&] { return parseCheckpoint(bytes, origin); });
  Checkpoint c;
  c.bytes_ = std::move(bytes);
  c.time_ = d.time;
  c.step_count_ = static_cast<int>(d.steps);
  return c;
}

void writeCheckpointFile(const std::string& path, const std::string& bytes, const std::string& what) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw FileFormatError(path, 0, "cannot open the " + what + " file for writing");
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.flush();
  if (!file) throw FileFormatError(path, 0, "writing the " + what + " failed");
}

void Checkpoint::save(const std::string& path) const { writeCheckpointFile(path, bytes_, "checkpoint"); }

Checkpoint Checkpoint::load(const std::string& path) {
  // The bounded reader: regular files only, size limited (a FIFO or /dev/zero cannot hang us).
  return fromBytes(io::readTextFile(path), path);
}

}  // namespace stabint
