// Small helpers of stabint-study: directories, paths, progress lines.
#include "study.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace study {

namespace {
const auto kProgramStart = std::chrono::steady_clock::now();
}

void ensureDirectory(const std::string& path) { std::filesystem::create_directories(path); }

std::string joinPath(const std::string& dir, const std::string& name) {
  return (std::filesystem::path(dir) / name).string();
}

void appendPositions(std::ofstream& out, const Eigen::MatrixX3d& x) {
  std::vector<float> row;
  row.reserve(static_cast<size_t>(x.size()));
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    for (int c = 0; c < 3; ++c) row.push_back(static_cast<float>(x(r, c)));
  out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(row.size() * sizeof(float)));
}

Scene loadTetGenMesh(const std::string& mesh, const stabint::SolidMaterial& material) {
  std::string base = mesh;
  for (const char* ext : {".node", ".ele"})
    if (base.size() > 5 && base.compare(base.size() - 5, 5, ext) == 0) base.resize(base.size() - 5);
  return stabint::loadTetGen(base, material);
}

const char* accelerationSuffix(stabint::Acceleration acceleration) {
  if (acceleration == stabint::SimulatorOptions{}.acceleration) return "";
  switch (acceleration) {
    case stabint::Acceleration::None: return "+PD";
    case stabint::Acceleration::Anderson: return "+AA";
    case stabint::Acceleration::LBFGS: return "+LB";
    case stabint::Acceleration::Newton: return "+NT";
    case stabint::Acceleration::Chebyshev: return "+CH";
    default: return "";
  }
}

void progress(const std::string& message) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - kProgramStart).count();
  std::printf("[%6.1f s] %s\n", s, message.c_str());
  std::fflush(stdout);
}

}  // namespace study
