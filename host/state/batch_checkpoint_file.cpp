// The batch checkpoint's file format (include/stabint/batch.hpp): the scenes' own checkpoints
// (host/state/checkpoint.cpp) and the options the batch recorded, in one checksummed file. What a
// restore does with it is the driver's (host/driver/batch_checkpoint.cpp).
#include "common/text_reader.hpp"
#include "common/validation.hpp"
#include "state/checkpoint.hpp"

#include <stabint/batch.hpp>
#include <stabint/errors.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>

namespace stabint {
namespace {

constexpr char kBatchMagic[8] = {'S', 'T', 'B', 'B', 'T', 'C', 'H', '\n'};
// 2: the batch's options (recordedOptions) after the scenes' checkpoints.
constexpr std::uint32_t kBatchVersion = 2;
constexpr std::uint32_t kOldestBatchVersion = 1;
// An option's name or value is at most this long, and a checkpoint records at most this many:
// bounds for a file's counts, far above the table's (its longest value is a double's 17 digits,
// sign and exponent).
constexpr std::uint32_t kMostOptionText = 64;
constexpr std::int64_t kMostOptions = 256;

template <typename T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

void putText(std::string& out, const std::string& text) {
  put(out, static_cast<std::uint32_t>(text.size()));
  out += text;
}

}  // namespace

const Checkpoint& BatchCheckpoint::scene(int scene) const {
  if (scene < 0 || scene >= size())
    throw InvalidInputError("BatchCheckpoint::scene: scene " + std::to_string(scene) + " out of range (it has " +
                            std::to_string(size()) + " scenes)");
  return scenes_[std::size_t(scene)];
}

// The magic, the version, the time, the scene count, each scene's checkpoint (its size, then its
// bytes, which have their own checksum), the options (their count, then each name and value as a
// size and its characters), and a checksum of everything before it. A checkpoint read from a
// version 1 file is written as it was read (without options).
std::string BatchCheckpoint::bytes() const {
  std::string out(kBatchMagic, sizeof kBatchMagic);
  put(out, has_options_ ? kBatchVersion : kOldestBatchVersion);
  put(out, time_);
  put(out, static_cast<std::int64_t>(scenes_.size()));
  for (const Checkpoint& c : scenes_) {
    put(out, static_cast<std::int64_t>(c.bytes().size()));
    out += c.bytes();
  }
  if (has_options_) {
    put(out, static_cast<std::int64_t>(options_.size()));
    for (const auto& [name, value] : options_) {
      putText(out, name);
      putText(out, value);
    }
  }
  put(out, checkpointChecksum(out.data(), out.size()));
  return out;
}

BatchCheckpoint BatchCheckpoint::fromBytes(const std::string& bytes, const std::string& origin) {
  const auto fail = [&](const std::string& what) {
    throw FileFormatError(origin, 0, "not a valid stabint batch checkpoint: " + what);
  };
  std::size_t pos = 0;
  std::size_t end = bytes.size();
  const auto take = [&](void* to, std::size_t size, const char* what) {
    if (end - pos < size) fail(std::string("truncated at ") + what);
    std::memcpy(to, bytes.data() + pos, size);
    pos += size;
  };
  char magic[sizeof kBatchMagic];
  take(magic, sizeof magic, "the header");
  if (std::memcmp(magic, kBatchMagic, sizeof magic) != 0) fail("wrong header");
  std::uint32_t version = 0;
  take(&version, sizeof version, "the version");
  if (version < kOldestBatchVersion || version > kBatchVersion)
    fail("format version " + std::to_string(version) + ", expected " + std::to_string(kOldestBatchVersion) + " to " +
         std::to_string(kBatchVersion));
  std::uint64_t stored = 0;
  if (end - pos < sizeof stored) fail("truncated at the checksum");
  end -= sizeof stored;
  std::memcpy(&stored, bytes.data() + end, sizeof stored);
  if (stored != checkpointChecksum(bytes.data(), end))
    fail("the checksum does not match: the data is corrupted or was changed");
  BatchCheckpoint batch;
  take(&batch.time_, sizeof batch.time_, "the time");
  if (!std::isfinite(batch.time_)) fail("the time is not finite");
  // The 1e150 rule of every real a checkpoint holds (a scene's time among them).
  if (!(std::abs(batch.time_) <= validation::kMaxMagnitude)) fail("the time is beyond 1e150 in magnitude");
  std::int64_t count = 0;
  take(&count, sizeof count, "the scene count");
  if (count < 0 || static_cast<std::uint64_t>(count) > (end - pos) / sizeof(std::int64_t))
    fail("scene count " + std::to_string(count) + " does not fit the data");
  for (std::int64_t s = 0; s < count; ++s) {
    std::int64_t size = 0;
    take(&size, sizeof size, "a scene's size");
    if (size < 0 || static_cast<std::uint64_t>(size) > end - pos)
      fail("scene " + std::to_string(s) + "'s size does not fit the data");
    batch.scenes_.push_back(
        Checkpoint::fromBytes(bytes.substr(pos, std::size_t(size)), origin + ", scene " + std::to_string(s)));
    pos += std::size_t(size);
  }
  if (version >= 2) {
    // Names and values are printable ASCII without spaces, each name once; which names and values
    // a batch accepts is the restore's to check.
    const auto text = [&](const char* what) {
      std::uint32_t size = 0;
      take(&size, sizeof size, what);
      if (size == 0 || size > kMostOptionText || size > end - pos) fail(std::string(what) + ": size out of range");
      std::string t = bytes.substr(pos, size);
      pos += size;
      for (char c : t)
        if (c < '!' || c > '~') fail(std::string(what) + ": not printable text");
      return t;
    };
    std::int64_t options = 0;
    take(&options, sizeof options, "the option count");
    if (options < 0 || options > kMostOptions) fail("option count " + std::to_string(options) + " out of range");
    for (std::int64_t i = 0; i < options; ++i) {
      std::string name = text("an option's name");
      std::string value = text("an option's value");
      for (const auto& known : batch.options_)
        if (known.first == name) fail("the option " + name + " is recorded twice");
      batch.options_.emplace_back(std::move(name), std::move(value));
    }
    batch.has_options_ = true;
  }
  if (pos != end) fail(std::to_string(end - pos) + " bytes after the end");
  return batch;
}

void BatchCheckpoint::save(const std::string& path) const { writeCheckpointFile(path, bytes(), "batch checkpoint"); }

BatchCheckpoint BatchCheckpoint::load(const std::string& path) {
  // The bounded reader: regular files only, size limited.
  return fromBytes(io::readTextFile(path), path);
}

}  // namespace stabint
