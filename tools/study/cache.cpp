#include "cache.hpp"

#include "study.hpp"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace study {

namespace {
constexpr char kMagic[8] = {'S', 'T', 'U', 'D', 'C', 'A', 'C', '2'};
}

std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string cachePath(const std::string& dir, const std::string& key, const std::string& description) {
  ensureDirectory(dir);
  std::ostringstream name;
  name << key << '-' << std::hex << std::setw(16) << std::setfill('0') << fnv1a(description) << ".bin";
  return joinPath(dir, name.str());
}

bool readCache(const std::string& path, const std::string& description, std::vector<double>& payload) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char magic[8];
  if (!in.read(magic, 8) || !std::equal(magic, magic + 8, kMagic)) return false;
  std::uint64_t length = 0, count = 0;
  if (!in.read(reinterpret_cast<char*>(&length), sizeof length) || length > (1u << 20)) return false;
  std::string stored(length, '\0');
  if (!in.read(&stored[0], static_cast<std::streamsize>(length)) || stored != description) return false;
  if (!in.read(reinterpret_cast<char*>(&count), sizeof count) || count > (1ull << 32)) return false;
  payload.resize(count);
  return static_cast<bool>(
      in.read(reinterpret_cast<char*>(payload.data()), static_cast<std::streamsize>(sizeof(double) * count)));
}

void writeCache(const std::string& path, const std::string& description, const std::vector<double>& payload) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + temporary);
    out.write(kMagic, 8);
    const std::uint64_t length = description.size(), count = payload.size();
    out.write(reinterpret_cast<const char*>(&length), sizeof length);
    out.write(description.data(), static_cast<std::streamsize>(length));
    out.write(reinterpret_cast<const char*>(&count), sizeof count);
    out.write(reinterpret_cast<const char*>(payload.data()), static_cast<std::streamsize>(sizeof(double) * count));
    if (!out) throw std::runtime_error("write failed: " + temporary);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot rename to " + path);
}

void appendFrames(std::vector<double>& payload, const std::vector<Eigen::MatrixX3d>& frames) {
  for (const Eigen::MatrixX3d& x : frames) payload.insert(payload.end(), x.data(), x.data() + x.size());
}

bool readFrames(PayloadReader& in, int frames, int particles, std::vector<Eigen::MatrixX3d>& out) {
  if (frames < 0 || particles <= 0) return false;
  out.assign(static_cast<size_t>(frames), Eigen::MatrixX3d(particles, 3));
  for (Eigen::MatrixX3d& x : out)
    if (!in.next(x.data(), static_cast<size_t>(x.size()))) return false;
  return true;
}

}  // namespace study
