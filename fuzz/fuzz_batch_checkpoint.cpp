// libFuzzer harness: BatchCheckpoint::fromBytes and BatchSimulator::restore on arbitrary bytes,
// re-signed first (each framed scene's checkpoint and the whole) so that mutations reach the field
// checks and the restore (batch_checkpoint_properties.hpp); seed:
// fuzz/corpus/batch_checkpoint/seed.bckpt, batch_checkpoint_properties::seed() written to a file.
// Only stabint::Error may come out; a refused restore that changed the batch aborts, which
// libFuzzer reports as a crash with the input.
#include "batch_checkpoint_properties.hpp"
#include "fuzz_common.hpp"

#include <cstdlib>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  stabint::batch_checkpoint_properties::resign(bytes);
  stabint::fuzz::expectOnlyStabintErrors([&] {
    if (!stabint::batch_checkpoint_properties::check(bytes, 2).violation.empty()) std::abort();
  });
  return 0;
}
