// Small helpers of stabint-study: directories, paths, progress lines.
#include "study.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>

namespace study {

namespace {
const auto kProgramStart = std::chrono::steady_clock::now();
}

void ensureDirectory(const std::string& path) { std::filesystem::create_directories(path); }

std::string joinPath(const std::string& dir, const std::string& name) {
  return (std::filesystem::path(dir) / name).string();
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
