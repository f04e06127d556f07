#pragma once
// On-disk cache of reference runs: one file per (scene, settings) in <out>/cache/, named by a
// hash of the full description and checked against it on read, so a changed setting never
// reads a stale file. The payload is a flat array of doubles that each reference lays out.
#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace study {

std::uint64_t fnv1a(const std::string& text);
/// <dir>/<key>-<16 hex digits of fnv1a(description)>.bin, creating <dir>.
std::string cachePath(const std::string& dir, const std::string& key, const std::string& description);
/// False when the file is missing, of another format, or for another description.
bool readCache(const std::string& path, const std::string& description, std::vector<double>& payload);
/// Written to a temporary name and renamed, so an interrupted run leaves no half file.
void writeCache(const std::string& path, const std::string& description, const std::vector<double>& payload);

/// Sequential reader of a payload; every read checks the bounds (a short file reads as invalid).
class PayloadReader {
 public:
  explicit PayloadReader(const std::vector<double>& payload) : data_(payload) {}
  bool next(double& value) {
    if (pos_ >= data_.size()) return false;
    value = data_[pos_++];
    return true;
  }
  bool next(double* out, size_t count) {
    if (data_.size() - pos_ < count) return false;
    std::copy(data_.begin() + static_cast<std::ptrdiff_t>(pos_),
              data_.begin() + static_cast<std::ptrdiff_t>(pos_ + count), out);
    pos_ += count;
    return true;
  }
  bool done() const { return pos_ == data_.size(); }

 private:
  const std::vector<double>& data_;
  size_t pos_ = 0;
};

/// The references of one kind that this process has loaded or computed, each kept once by its
/// description: the subcommands of one `all` run share them, so one computed by `prefetch` still
/// counts as computed by this run. The lock guards the map alone: `prefetch` computes two
/// references at once, each outside it (two threads making the same one keep the first).
template <class Reference>
class LoadedReferences {
 public:
  /// The reference of `description`, from memory or made by `make()` (its value).
  template <class Make>
  const Reference& get(const std::string& description, Make&& make) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      const auto found = loaded_.find(description);
      if (found != loaded_.end()) return *found->second;
    }
    auto made = std::make_unique<const Reference>(make());
    const std::lock_guard<std::mutex> lock(mutex_);
    return *loaded_.emplace(description, std::move(made)).first->second;
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<const Reference>> loaded_;
};

/// Frames of positions: appended row-major as stored by Eigen (column-major per frame).
void appendFrames(std::vector<double>& payload, const std::vector<Eigen::MatrixX3d>& frames);
bool readFrames(PayloadReader& in, int frames, int particles, std::vector<Eigen::MatrixX3d>& out);

}  // namespace study
