#pragma once
// Memory exhaustion at the public boundary: std::bad_alloc from inside a call becomes the
// documented OutOfMemoryError naming the call (include/stabint/errors.hpp), so that nothing but
// a stabint::Error leaves the library.
#include <stabint/errors.hpp>

#include <new>
#include <string>
#include <utility>

namespace stabint {

template <typename Call>
decltype(auto) reportingOutOfMemory(const char* call, Call&& body) {
  try {
    return std::forward<Call>(body)();
  } catch (const std::bad_alloc&) {
    throw OutOfMemoryError(std::string(call) + ": out of memory");
  }
}

}  // namespace stabint
