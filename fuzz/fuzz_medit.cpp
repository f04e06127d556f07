// libFuzzer harness: loadMedit on arbitrary bytes.
#include "fuzz_common.hpp"

#include <stabint/io.hpp>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = stabint::fuzz::writeInput("input.mesh", data, size);
  stabint::fuzz::expectOnlyStabintErrors([&] { stabint::loadMedit(path); });
  return 0;
}
