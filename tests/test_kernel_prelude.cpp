// The prelude every OpenCL program starts with (host/common/kernel_constants.hpp) against the host's
// constants, without a device: each entry of the lists is one `#define` with the host's value, and
// the prelude defines nothing else. tests/test_opencl_kernel_prelude.cpp compiles it and reads the
// values back from a device.
#include "elements/contact.hpp"
#include "elements/element_type.hpp"
#include "common/kernel_constants.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <set>
#include <string>

namespace stabint {
namespace {

// The text of `#define name ...` up to the end of its line, or "" when the prelude has none.
std::string definition(const std::string& prelude, const std::string& name) {
  const std::string key = "\n#define " + name + " ";
  const std::size_t at = prelude.find(key);
  if (at == std::string::npos) return "";
  const std::size_t begin = at + key.size();
  return prelude.substr(begin, prelude.find('\n', begin) - begin);
}

TEST(KernelPrelude, DefinesEveryIntegerWithTheHostValue) {
  const std::string& prelude = kernelPrelude();
#define STABINT_CHECK_INT(kernel_name, host, value)                                                           \
  EXPECT_EQ(definition(prelude, #kernel_name), std::to_string(static_cast<long long>(host))) << #kernel_name; \
  EXPECT_EQ(static_cast<long long>(host), static_cast<long long>(value)) << #kernel_name;
  STABINT_KERNEL_INTS(STABINT_CHECK_INT)
#undef STABINT_CHECK_INT
}

// A real is `((real)<literal>)`: the literal must read back as the host's double exactly.
TEST(KernelPrelude, DefinesEveryRealWithTheHostValue) {
  const std::string& prelude = kernelPrelude();
#define STABINT_CHECK_REAL(kernel_name, host, value)                                     \
  {                                                                                      \
    const std::string text = definition(prelude, #kernel_name);                          \
    const std::string head = "((real)", tail = ")";                                      \
    ASSERT_GT(text.size(), head.size() + tail.size()) << #kernel_name << ": " << text;   \
    EXPECT_EQ(text.substr(0, head.size()), head) << #kernel_name;                        \
    EXPECT_EQ(text.substr(text.size() - 1), tail) << #kernel_name;                       \
    const std::string literal = text.substr(head.size(), text.size() - head.size() - 1); \
    char* end = nullptr;                                                                 \
    EXPECT_EQ(std::strtod(literal.c_str(), &end), host) << #kernel_name << ": " << text; \
    EXPECT_EQ(*end, '\0') << #kernel_name << ": " << text;                               \
  }
  STABINT_KERNEL_REALS(STABINT_CHECK_REAL)
#undef STABINT_CHECK_REAL
}

// One `#define` per entry, no two entries with one name: what the kernels see is the lists.
TEST(KernelPrelude, DefinesTheListsAndNothingElse) {
  std::set<std::string> names;
  std::size_t entries = 0;
#define STABINT_NAME(kernel_name, host, value) \
  names.insert(#kernel_name);                  \
  ++entries;
  STABINT_KERNEL_INTS(STABINT_NAME)
  STABINT_KERNEL_REALS(STABINT_NAME)
#undef STABINT_NAME
  EXPECT_EQ(names.size(), entries) << "a kernel name appears twice in host/common/kernel_constants.hpp";
  const std::string& prelude = kernelPrelude();
  std::size_t defines = 0;
  for (std::size_t at = prelude.find("#define"); at != std::string::npos; at = prelude.find("#define", at + 1))
    ++defines;
  EXPECT_EQ(defines, entries) << prelude;
  // Only preprocessor lines and comments: the prelude declares no code of its own.
  std::size_t begin = 0;
  while (begin < prelude.size()) {
    const std::size_t end = prelude.find('\n', begin);
    const std::string line = prelude.substr(begin, end - begin);
    EXPECT_TRUE(line.rfind("#define ", 0) == 0 || line.rfind("//", 0) == 0) << line;
    if (end == std::string::npos) break;
    begin = end + 1;
  }
}

// The codes the shapes have in the kernels are the public enum's values (also static_asserts in
// elements/contact.hpp), and the geometry the host writes has the kernels' layout.
TEST(KernelPrelude, ColliderGeometryFollowsTheLayout) {
  Collider capsule;
  capsule.shape = ColliderShape::Capsule;
  capsule.center = Eigen::Vector3d(1, 2, 3);
  capsule.end = Eigen::Vector3d(4, 5, 6);
  capsule.radius = 0.5;
  double g[kColliderGeometry];
  colliderGeometryAt(capsule, capsule.center, g);
  EXPECT_EQ(g[kGeometryShape], 3.0);
  EXPECT_EQ(definition(kernelPrelude(), "COLLIDER_CAPSULE"), "3");
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(g[kGeometryCenter + c], capsule.center[c]);
    EXPECT_EQ(g[kGeometryA + c], capsule.end[c]);
  }
  EXPECT_EQ(g[kGeometryRadius], 0.5);
  // A contact element's params: its weight, then the geometry at kContactGeometry.
  const ElementShape shape = contactElementType().shape();
  EXPECT_EQ(shape.params, kContactGeometry + kColliderGeometry);
}

}  // namespace
}  // namespace stabint
