#pragma once
// What the loader fuzz harnesses share: each libFuzzer input is written to a file in a private
// temporary directory (the loaders take paths), the loader runs on it, and only stabint::Error
// may come out. Anything else escaping — std::bad_alloc, a JSON library exception — reaches
// std::terminate, which libFuzzer reports as a crash with the input that caused it; so do
// sanitizer reports, hangs (-timeout) and runaway memory (-rss_limit_mb).
#include <stabint/errors.hpp>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

namespace stabint::fuzz {

/// The harness's directory, created once per process and removed at a normal exit.
inline const std::string& workDir() {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/stabint_fuzz_XXXXXX";
    if (!::mkdtemp(pattern.data())) std::abort();
    return pattern;
  }();
  static const int cleanup = std::atexit([] {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  });
  (void)cleanup;
  return dir;
}

/// Writes `size` bytes to `name` inside workDir() and returns the full path.
inline std::string writeInput(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = workDir() + "/" + name;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

/// Runs `load`; a stabint::Error is the expected answer to a bad input.
template <typename Load>
void expectOnlyStabintErrors(const Load& load) {
  try {
    load();
  } catch (const stabint::Error&) {
  }
}

}  // namespace stabint::fuzz
