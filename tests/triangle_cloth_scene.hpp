#pragma once
// The triangle-element test cloth shared by the element, solver and OpenCL tests: triangle
// strain and bending hinges on a 1 m cloth pinned at its top corners.
#include <stabint/builders.hpp>

#include <cmath>

namespace stabint::testing {

/// With `limits_and_dome`, the strain limits [0.97, 1.03] (which some triangles reach) and a
/// curved rest shape (hinges with rest curvature) exercise every branch of both projections;
/// without, the cloth is flat with limits [1, 1] (as rigid as possible), a smooth energy.
inline Scene triangleCloth(int nx = 7, int ny = 6, bool limits_and_dome = true) {
  ClothGridParams p;
  p.nx = nx;
  p.ny = ny;
  p.model = ClothModel::Triangles;
  p.strain_stiffness = 500.0;
  p.strain_min = limits_and_dome ? 0.97 : 1.0;
  p.strain_max = limits_and_dome ? 1.03 : 1.0;
  p.hinge_stiffness = 0.05;
  Scene s = makeClothGrid(p);
  if (!limits_and_dome) return s;
  // A gentle dome as the rest (and start) shape.
  for (Eigen::Index j = 0; j < s.rest_positions.rows(); ++j) {
    const double x = s.rest_positions(j, 0), y = s.rest_positions(j, 1);
    s.rest_positions(j, 2) = 0.15 * std::sin(3.0 * x) * std::cos(2.0 * y);
  }
  s.positions = s.rest_positions;
  for (Pin& pin : s.pins) pin.target.position = s.rest_positions.row(pin.vertex).transpose();
  validateScene(s);
  return s;
}

}  // namespace stabint::testing
