#include "common/kernel_constants.hpp"

namespace stabint {

const std::string& kernelPrelude() {
  static const std::string prelude = [] {
    std::string s = "// ---- prelude: the constants of host/common/kernel_constants.hpp ----\n";
#define STABINT_PRELUDE_INT(kernel_name, host, value) s += "#define " #kernel_name " " + std::to_string(value) + "\n";
#define STABINT_PRELUDE_REAL(kernel_name, host, value) s += "#define " #kernel_name " ((real)" #value ")\n";
    STABINT_KERNEL_INTS(STABINT_PRELUDE_INT)
    STABINT_KERNEL_REALS(STABINT_PRELUDE_REAL)
#undef STABINT_PRELUDE_INT
#undef STABINT_PRELUDE_REAL
    return s;
  }();
  return prelude;
}

}  // namespace stabint
