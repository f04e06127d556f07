#pragma once
// The mixed scenes of the batch tests (tests/test_scene_batch.cpp, tests/test_opencl_batch.cpp):
// every element type but contact, pins, a time-dependent force field and a damped body; and where
// each element type lies in a segment.
#include <stabint/builders.hpp>
#include <stabint/scene.hpp>

#include "elements/element_type.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cstddef>
#include <string>
#include <vector>

namespace stabint::testing {

/// Four scenes covering every element type but contact: springs and a pin (chain, with a
/// time-dependent force field on "all particles"), springs with a damped body (cloth), tets with
/// pins (bar), triangle strain and bending hinges (triangle cloth).
inline std::vector<Scene> mixedBatchScenes() {
  ChainPendulumParams chain;
  chain.particles = 8;
  Scene a = makeChainPendulum(chain);
  ForceField wind;
  wind.force = Eigen::Vector3d(0.0, 0.0, 0.01);
  wind.rate = Eigen::Vector3d(0.02, 0.0, 0.0);
  a.force_fields.push_back(wind);

  ClothGridParams cloth;
  cloth.nx = 6;
  cloth.ny = 5;
  cloth.damping = 0.1;
  const Scene b = makeClothGrid(cloth);

  TetBarParams bar;
  bar.nx = 3;
  bar.ny = 1;
  bar.nz = 1;
  const Scene c = makeTetBar(bar);

  ClothGridParams triangles;
  triangles.nx = 5;
  triangles.ny = 4;
  triangles.model = ClothModel::Triangles;
  const Scene d = makeClothGrid(triangles);
  return {a, b, c, d};
}

/// Position of the element type `identifier` in elementTypes() (the per-type ranges of a segment).
inline int typeIndex(const char* identifier) {
  const std::vector<const ElementType*>& types = elementTypes();
  for (std::size_t i = 0; i < types.size(); ++i)
    if (std::string(types[i]->identifier()) == identifier) return static_cast<int>(i);
  ADD_FAILURE() << "no element type " << identifier;
  return 0;
}

}  // namespace stabint::testing
