// The element program holds only the element types it is built for (those of the scene, and pins):
// a spring cloth's program has no tet or triangle-strain kernels, and each set of types gets its
// own source, so that the program cache (keyed by source) keeps one program per set.
#include "elements/element_type.hpp"
#include "opencl/element_program.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace stabint {
namespace {

const ElementType* typeNamed(const std::string& identifier) {
  for (const ElementType* type : elementTypes())
    if (identifier == type->identifier()) return type;
  ADD_FAILURE() << "no element type " << identifier;
  return nullptr;
}

TEST(ElementProgram, HoldsOnlyTheGivenTypes) {
  const std::string springs = ocl::elementProgramSource({typeNamed("spring"), typeNamed("pin")});
  EXPECT_NE(springs.find("spring_element("), std::string::npos);
  EXPECT_NE(springs.find("pin_element("), std::string::npos);
  for (const char* absent :
       {"tet_element(", "tet_project(", "triangle_strain_element(", "bending_hinge_element(", "contact_element("})
    EXPECT_EQ(springs.find(absent), std::string::npos) << absent;

  const std::string all = ocl::elementProgramSource(elementTypes());
  for (const ElementType* type : elementTypes())
    EXPECT_NE(all.find(std::string(type->identifier()) + "_element("), std::string::npos) << type->identifier();
  EXPECT_NE(springs, all);
}

}  // namespace
}  // namespace stabint
