// libFuzzer harness: loadTetGen on arbitrary bytes. One input holds both files: the .node part,
// then a line "@ele", then the .ele part (no such line: the whole input is the .node file and the
// .ele file is empty).
#include "fuzz_common.hpp"

#include <stabint/io.hpp>

#include <cstring>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char kSeparator[] = "\n@ele\n";
  const std::string input(reinterpret_cast<const char*>(data), size);
  const size_t at = input.find(kSeparator);
  const size_t node_size = at == std::string::npos ? size : at + 1;
  const size_t ele_start = at == std::string::npos ? size : at + std::strlen(kSeparator);
  stabint::fuzz::writeInput("input.node", data, node_size);
  stabint::fuzz::writeInput("input.ele", data + ele_start, size - ele_start);
  const std::string base = stabint::fuzz::workDir() + "/input";
  stabint::fuzz::expectOnlyStabintErrors([&] { stabint::loadTetGen(base); });
  return 0;
}
