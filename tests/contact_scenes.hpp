#pragma once
// Scenes of the contact tests (docs/method.md, "Contact"): a horizontal cloth dropped onto
// colliders, a free tet bar above the ground, and collider factories.
#include <stabint/builders.hpp>
#include <stabint/scene.hpp>

namespace stabint::testing {

/// An n x n spring cloth, 1 m square, lying flat at `height` (the x-z plane), centred on the y
/// axis, without pins.
inline Scene horizontalCloth(int n, double height) {
  ClothGridParams p;
  p.nx = n;
  p.ny = n;
  Scene s = makeClothGrid(p);
  s.pins.clear();
  for (Eigen::MatrixX3d* m : {&s.positions, &s.rest_positions}) {
    Eigen::MatrixX3d r(m->rows(), 3);
    r.col(0) = m->col(0).array() - 0.5;
    r.col(1).setConstant(height);
    r.col(2) = m->col(1).array() - 0.5;
    *m = r;
  }
  return s;
}

/// The default tet bar (1 m x 0.25 m x 0.25 m, 62.5 kg) without its pins, its bottom at `lift`.
inline Scene freeBar(double lift) {
  Scene s = makeTetBar(TetBarParams{});
  s.pins.clear();
  s.positions.col(1).array() += lift - s.positions.col(1).minCoeff();
  return s;
}

inline Collider groundPlane(double y, double stiffness, double friction = 0.0) {
  Collider c;
  c.shape = ColliderShape::Plane;
  c.center = Eigen::Vector3d(0.0, y, 0.0);
  c.normal = Eigen::Vector3d::UnitY();
  c.stiffness = stiffness;
  c.friction = friction;
  return c;
}

inline Collider sphereCollider(const Eigen::Vector3d& center, double radius, double stiffness, double friction = 0.0) {
  Collider c;
  c.shape = ColliderShape::Sphere;
  c.center = center;
  c.radius = radius;
  c.stiffness = stiffness;
  c.friction = friction;
  return c;
}

inline Collider boxCollider(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents, double stiffness,
                            const Eigen::Vector3d& velocity = Eigen::Vector3d::Zero()) {
  Collider c;
  c.shape = ColliderShape::Box;
  c.center = center;
  c.half_extents = half_extents;
  c.stiffness = stiffness;
  c.velocity = velocity;
  return c;
}

/// A 12 x 12 cloth dropped onto a sphere (friction 0.5) and the ground, with a box sliding
/// across the ground under it: every shape, friction and a moving collider at once.
inline Scene clothOnColliders() {
  Scene s = horizontalCloth(12, 0.4);
  s.colliders.push_back(sphereCollider(Eigen::Vector3d(0.0, 0.0, 0.0), 0.25, 1e4, 0.5));
  s.colliders.push_back(groundPlane(-0.25, 1e4, 0.3));
  s.colliders.push_back(boxCollider(Eigen::Vector3d(-0.6, -0.2, 0.0), Eigen::Vector3d(0.1, 0.1, 0.1), 1e4,
                                    Eigen::Vector3d(0.5, 0.0, 0.0)));
  Collider capsule;
  capsule.shape = ColliderShape::Capsule;
  capsule.center = Eigen::Vector3d(-0.5, -0.1, 0.3);
  capsule.end = Eigen::Vector3d(0.5, -0.1, 0.3);
  capsule.radius = 0.08;
  capsule.stiffness = 1e4;
  s.colliders.push_back(capsule);
  return s;
}

}  // namespace stabint::testing
