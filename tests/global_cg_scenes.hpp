#pragma once
// The two small scenes the CG global step is tested on (tests/test_global_cg.cpp on the CPU
// reference, tests/test_opencl_global_cg.cpp across backends): a spring cloth (a 2-D Laplacian)
// and a tet bar (3-D), so both matrix structures the Jacobi preconditioner meets are covered.
#include <stabint/builders.hpp>

namespace stabint::testing {

inline Scene cgClothScene() {
  ClothGridParams p;
  p.nx = 12;
  p.ny = 10;
  return makeClothGrid(p);
}

inline Scene cgTetScene() {
  TetBarParams p;
  p.nx = 6;
  p.ny = 2;
  p.nz = 2;
  p.stiffness = 2e4;
  return makeTetBar(p);
}

}  // namespace stabint::testing
