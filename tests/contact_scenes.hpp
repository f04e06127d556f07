#pragma once
// Scenes of the contact tests (docs/method.md, "Contact"): a horizontal cloth dropped onto
// colliders, a free tet bar above the ground, and collider factories.
#include <stabint/builders.hpp>
#include <stabint/scene.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <utility>

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

/// The particle at the middle of a horizontal cloth's edge at the lowest z, where the lift-off
/// tests and probe_lift_off hold it.
inline int edgeMiddle(const Scene& s) {
  int held = 0;
  const auto score = [&](int i) { return -s.positions(i, 2) - std::abs(s.positions(i, 0)); };
  for (int i = 0; i < s.numParticles(); ++i)
    if (score(i) > score(held)) held = i;
  return held;
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

/// A mesh collider: an icosphere about `center` with its vertices at `radius`, the icosahedron's
/// 20 triangles split in four `subdivisions` times (5: 20,480 triangles), counter-clockwise seen
/// from outside.
inline Collider icosphereCollider(const Eigen::Vector3d& center, double radius, int subdivisions,
                                  double friction = 0.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Eigen::Vector3d& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int, int>, int> middle;
    const auto mid = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      const auto found = middle.find(key);
      if (found != middle.end()) return found->second;
      v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
      return middle[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& [a, b, c] : f) {
      const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    f = std::move(next);
  }
  Collider c;
  c.shape = ColliderShape::Mesh;
  c.center = center;
  c.friction = friction;
  c.mesh_vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    c.mesh_vertices.row(Eigen::Index(i)) = (center + radius * v[i]).transpose();
  c.mesh_triangles = f;
  return c;
}

/// A mesh collider that is the axis-aligned box of `center` and `half_extents`: 12 triangles.
inline Collider boxMeshCollider(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents) {
  Collider c;
  c.shape = ColliderShape::Mesh;
  c.center = center;
  c.mesh_vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    c.mesh_vertices.row(i) =
        (center + half_extents.cwiseProduct(Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1)))
            .transpose();
  // Vertex i has x = +-1 by bit 0, y by bit 1, z by bit 2; each face counter-clockwise from outside.
  c.mesh_triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return c;
}

/// Self-contact (docs/method.md, "Self-contact"): a 50 x 50 (or n x n) spring cloth (1 m) standing almost upright (0.3
/// rad from the vertical), its lower edge 2 cm above a ground with friction 0.5, unpinned, with a soft bend (1 N/m): it
/// collapses and crumples into a pile of folds. With backward Euler the pile interpenetrates at once without
/// self-contact (hundreds of crossing triangle pairs).
inline Scene crumplingCloth(int n = 50) {
  ClothGridParams p;
  p.nx = p.ny = n;
  p.bend_stiffness = 1.0;
  Scene s = makeClothGrid(p);
  s.pins.clear();
  const double y_min = s.positions.col(1).minCoeff(), tilt = 0.3;
  for (int i = 0; i < s.numParticles(); ++i) {
    const double up = s.positions(i, 1) - y_min;
    s.positions(i, 1) = 0.02 + up * std::cos(tilt);
    s.positions(i, 2) = up * std::sin(tilt);
  }
  s.rest_positions = s.positions;
  Collider ground;
  ground.friction = 0.5;
  s.colliders = {ground};
  return s;
}

/// `a` and `b` as one scene (no pins, at rest, `a`'s colliders and gravity): `a`'s particles and
/// elements, then `b`'s, its indices shifted.
inline Scene combined(const Scene& a, const Scene& b) {
  const int n = a.numParticles();
  Scene s = a;
  s.pins.clear();
  s.positions.resize(n + b.numParticles(), 3);
  s.positions << a.positions, b.positions;
  s.rest_positions.resize(n + b.numParticles(), 3);
  s.rest_positions << a.rest_positions, b.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(s.positions.rows(), 3);
  s.masses.resize(s.positions.rows());
  s.masses << a.masses, b.masses;
  for (Spring spring : b.springs) {
    spring.a += n;
    spring.b += n;
    s.springs.push_back(spring);
  }
  for (const auto& t : b.triangles) s.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  for (Tet tet : b.tets) {
    for (int& v : tet.vertices) v += n;
    s.tets.push_back(tet);
  }
  for (TriangleStrain strain : b.triangle_strains) {
    for (int& v : strain.vertices) v += n;
    s.triangle_strains.push_back(strain);
  }
  for (BendingHinge hinge : b.bending_hinges) {
    for (int& v : hinge.vertices) v += n;
    s.bending_hinges.push_back(hinge);
  }
  return s;
}

/// Two copies of `one` in one scene (combined), for the caller to place.
inline Scene twoCopies(const Scene& one) { return combined(one, one); }

/// Two 25 x 25 spring cloths (0.5 m) of one scene: one lying flat 5 mm above the ground, the
/// other 15 cm above it, turned 0.4 rad about the vertical and tilted 0.2 rad, falling onto it.
/// Without self-contact the upper one lands through the lower one.
inline Scene clothOnCloth() {
  ClothGridParams p;
  p.nx = p.ny = 25;
  p.width = p.height = 0.5;
  const Scene one = makeClothGrid(p);
  const int n = one.numParticles();
  Scene s = twoCopies(one);
  const Eigen::Vector2d centre(one.positions.col(0).mean(), one.positions.col(1).mean());
  const double c = std::cos(0.4), sn = std::sin(0.4);
  for (int i = 0; i < n; ++i) {
    const double u = one.positions(i, 0) - centre.x(), w = one.positions(i, 1) - centre.y();
    s.positions.row(i) << u, 0.005, w;
    s.positions.row(n + i) << c * u - sn * w, 0.15 + 0.2 * u, sn * u + c * w;
  }
  s.rest_positions = s.positions;
  Collider ground;
  ground.friction = 0.5;
  s.colliders = {ground};
  return s;
}

/// Self-contact between two bodies: two default tet bars of one scene (1e5 Pa, 62.5 kg each),
/// one lying on a ground with friction 0.5, its bottom 1 cm above it, the other crossing it at a
/// right angle 15 cm above its top and falling onto it. Without self-contact the upper one sinks
/// into the lower one.
inline Scene barOnBar() {
  const Scene one = makeTetBar(TetBarParams{});
  const int n = one.numParticles();
  Scene s = twoCopies(one);
  const Eigen::Vector3d mid =
      0.5 * (one.positions.colwise().maxCoeff() + one.positions.colwise().minCoeff()).transpose();
  const double bottom = one.positions.col(1).minCoeff(), height = one.positions.col(1).maxCoeff() - bottom;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = one.positions.row(i).transpose() - mid;
    s.positions.row(i) << p.x(), p.y() + 0.5 * height + 0.01, p.z();
    s.positions.row(n + i) << p.z(), p.y() + 1.5 * height + 0.16, -p.x();  // turned a quarter about y
  }
  s.rest_positions = s.positions;
  Collider ground;
  ground.friction = 0.5;
  s.colliders = {ground};
  return s;
}

/// A tet bar (`params`) and a 30 x 30 spring cloth (1 m) of one scene (combined: the bar's
/// particles first), for the caller to place: the parts as built, with the bar's box centre and its
/// lowest and highest y.
struct BarAndCloth {
  Scene scene, bar, cloth;
  Eigen::Vector3d mid;
  double bottom, top;
};
inline BarAndCloth barAndCloth(const TetBarParams& params) {
  BarAndCloth b;
  b.bar = makeTetBar(params);
  ClothGridParams p;
  p.nx = p.ny = 30;
  b.cloth = makeClothGrid(p);
  b.scene = combined(b.bar, b.cloth);
  b.mid = 0.5 * (b.bar.positions.colwise().maxCoeff() + b.bar.positions.colwise().minCoeff()).transpose();
  b.bottom = b.bar.positions.col(1).minCoeff();
  b.top = b.bar.positions.col(1).maxCoeff();
  return b;
}

/// A cloth on a soft body: a tet bar (`params`, by default 1e5 Pa) lying on a ground with
/// friction 0.5, its bottom 1 cm above it, and a 30 x 30 spring cloth (1 m) flat 20 cm above its
/// top, turned 0.3 rad about the vertical, falling onto it and draping over it. Without
/// self-contact the cloth falls through the bar.
inline Scene clothOnBar(const TetBarParams& params = TetBarParams{}) {
  const BarAndCloth parts = barAndCloth(params);
  const Scene& cloth = parts.cloth;
  Scene s = parts.scene;
  const int n = parts.bar.numParticles();
  const Eigen::Vector3d& mid = parts.mid;
  const double bottom = parts.bottom, top = parts.top;
  for (int i = 0; i < n; ++i) {
    s.positions(i, 0) -= mid.x();
    s.positions(i, 1) += 0.01 - bottom;
    s.positions(i, 2) -= mid.z();
  }
  const Eigen::Vector2d centre(cloth.positions.col(0).mean(), cloth.positions.col(1).mean());
  const double c = std::cos(0.3), sn = std::sin(0.3);
  for (int i = 0; i < cloth.numParticles(); ++i) {
    const double u = cloth.positions(i, 0) - centre.x(), w = cloth.positions(i, 1) - centre.y();
    s.positions.row(n + i) << c * u - sn * w, top - bottom + 0.21, sn * u + c * w;
  }
  s.rest_positions = s.positions;
  Collider ground;
  ground.friction = 0.5;
  s.colliders = {ground};
  return s;
}

/// A soft body on a cloth: a 30 x 30 spring cloth (1 m) lying flat 5 mm above a ground with
/// friction 0.5, and a tet bar (`params`, by default 1e5 Pa, 62.5 kg, a thousand times the cloth's
/// mass) tilted 0.3 rad about x and 0.2 rad about z, its lowest corner 15 cm above the ground,
/// falling at `speed` onto it. Without self-contact the bar falls through the cloth.
inline Scene barOnCloth(double speed, const TetBarParams& params = TetBarParams{}) {
  const BarAndCloth parts = barAndCloth(params);
  const Scene& cloth = parts.cloth;
  Scene s = parts.scene;
  const int n = parts.bar.numParticles();
  const Eigen::Vector3d& mid = parts.mid;
  const double bottom = parts.bottom;
  const Eigen::Matrix3d turn =
      (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d q(s.positions(i, 0) - mid.x(), s.positions(i, 1) - bottom, s.positions(i, 2) - mid.z());
    s.positions.row(i) = (turn * q + Eigen::Vector3d(0.0, 0.15, 0.0)).transpose();
    s.velocities(i, 1) = -speed;
  }
  const Eigen::Vector2d centre(cloth.positions.col(0).mean(), cloth.positions.col(1).mean());
  for (int i = 0; i < cloth.numParticles(); ++i)
    s.positions.row(n + i) << cloth.positions(i, 0) - centre.x(), 0.005, cloth.positions(i, 1) - centre.y();
  s.rest_positions = s.positions;
  Collider ground;
  ground.friction = 0.5;
  s.colliders = {ground};
  return s;
}

}  // namespace stabint::testing
