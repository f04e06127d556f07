// libFuzzer harness: loadSceneFile on arbitrary bytes. Mesh entries resolve relative to the
// input's directory, which holds only the input itself, so a mesh entry exercises the other
// loaders on JSON text (or a missing file).
#include "fuzz_common.hpp"

#include <stabint/io.hpp>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = stabint::fuzz::writeInput("input.json", data, size);
  stabint::fuzz::expectOnlyStabintErrors([&] { stabint::loadSceneFile(path); });
  return 0;
}
