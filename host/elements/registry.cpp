// The table of element types. Its order is the order of the contribution numbering, of the
// blocks in SceneData and of the segments of the OpenCL element pass.
#include "elements/element_type.hpp"

namespace stabint {

const ElementType& springElementType();
const ElementType& tetElementType();
const ElementType& triangleStrainElementType();
const ElementType& bendingHingeElementType();
const ElementType& contactElementType();
const ElementType& pinElementType();

const std::vector<const ElementType*>& elementTypes() {
  static const std::vector<const ElementType*> types = {
      &springElementType(),
      &tetElementType(),
      &triangleStrainElementType(),
      &bendingHingeElementType(),
      // Contact before pins: grab and release rebuild only the last block (pins).
      &contactElementType(),
      &pinElementType(),
  };
  return types;
}

}  // namespace stabint
