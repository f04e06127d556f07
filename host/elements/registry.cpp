// The table of element types. Its order is the order of the contribution numbering, of the
// blocks in SceneData and of the segments of the OpenCL element pass.
#include "elements/element_type.hpp"

#include <stabint/errors.hpp>

#include <string>

namespace stabint {

// The kinds users reach, in their list's order, and the contact type (its pairs are the
// simulator's, not the user's) before the pins, which stay last: grab and release rebuild only the
// last block.
const std::vector<const ElementType*>& elementTypes() {
  static const std::vector<const ElementType*> types = [] {
    std::vector<const ElementType*> t{
#define STABINT_ELEMENT_TYPE(kind, name) &elementTypeOf<ElementKind::kind>(),
        STABINT_ELEMENT_KINDS(STABINT_ELEMENT_TYPE)
#undef STABINT_ELEMENT_TYPE
    };
    t.insert(t.end() - 1, &contactElementType());
    return t;
  }();
  return types;
}

const ElementType& elementType(ElementKind kind) {
  switch (kind) {
#define STABINT_ELEMENT_TYPE_CASE(kind, name) \
  case ElementKind::kind: return elementTypeOf<ElementKind::kind>();
    STABINT_ELEMENT_KINDS(STABINT_ELEMENT_TYPE_CASE)
#undef STABINT_ELEMENT_TYPE_CASE
  }
  throw InvalidInputError("element kind " + std::to_string(static_cast<int>(kind)) + " is not an ElementKind value");
}

}  // namespace stabint
