// libFuzzer harness: Checkpoint::fromBytes and Simulator::restore on arbitrary bytes, re-signed
// with a matching checksum first so that mutations reach the field checks and the restore
// (checkpoint_properties.hpp); seed: fuzz/corpus/checkpoint/seed.ckpt, checkpoint_properties::seed()
// written to a file. Only stabint::Error may come out; a refused restore that changed
// the simulator aborts, which libFuzzer reports as a crash with the input.
#include "checkpoint_properties.hpp"
#include "fuzz_common.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  stabint::checkpoint_properties::resign(bytes);
  stabint::fuzz::expectOnlyStabintErrors([&] {
    if (!stabint::checkpoint_properties::check(bytes, 2).violation.empty()) std::abort();
  });
  return 0;
}
