#pragma once
// A triangle-mesh collider's queries (docs/method.md, "Contact", "Mesh colliders"): the surface
// point nearest to a point, with the side it is on, and the first crossing of a segment, over a
// bounding-volume hierarchy of the triangles (Eigen's KdBVH). The mesh is closed and consistently
// oriented (Collider validation), so inside and outside are defined: the side of a point comes
// from the angle-weighted pseudo-normal of its nearest feature (face, edge or vertex; Baerentzen
// and Aanaes 2005), exact for a point however close to an edge. Queries are in the collider's
// reference frame (its vertices as given, the reference point at Collider::center); the caller
// moves a point by the collider's translation first.
#include <stabint/scene.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <unsupported/Eigen/BVH>

#include <algorithm>
#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace stabint {

class MeshCollider {
 public:
  explicit MeshCollider(const Collider& collider);

  struct Nearest {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();    // on the surface
    Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // outward unit normal of the plane there
    double signed_distance = 0.0;                       // negative inside
  };
  /// The surface point nearest to x, when one is within `cutoff` or x is inside (a point inside
  /// the mesh's box farther than `cutoff` from the surface is looked up whatever its distance, so
  /// that a point deep inside is never taken for one outside). `normal` is the outward normal of
  /// the plane through the point that supports the mesh locally: (x - point) / |x - point| outside,
  /// its opposite inside, the feature's pseudo-normal for x on the surface.
  bool nearest(const Eigen::Vector3d& x, double cutoff, Nearest& out) const;

  /// The first point where the segment a -> b enters the mesh from outside: its parameter s in
  /// [0, 1] and the triangle's outward normal. False when the segment does not cross inward.
  bool firstEntry(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double& s, Eigen::Vector3d& normal) const;

  /// The mesh's axis-aligned bounding box.
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }

  /// Its thinnest size: the shortest distance from a triangle's centroid, straight inward along
  /// its normal, to the surface on the other side (a plate's thickness, a finger's width).
  double thickness() const { return thickness_; }

 private:
  Eigen::MatrixX3d vertices_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<Eigen::Vector3d> face_normals_;                    // unit
  std::vector<Eigen::Vector3d> vertex_normals_;                  // angle-weighted sums of the faces' normals
  std::map<std::pair<int, int>, Eigen::Vector3d> edge_normals_;  // sums of the two faces' normals
  Eigen::KdBVH<double, 3, int> tree_;
  Eigen::AlignedBox3d bounds_;
  double thickness_ = 0.0;

  Nearest nearestOnTriangle(int t, const Eigen::Vector3d& x) const;
  // The first crossing of the segment a -> b, s in [0, 1], through a triangle other than `skip`
  // that it enters (`entering`: against the triangle's normal) or leaves; -1 when none.
  int firstCrossing(const Eigen::Vector3d& a, const Eigen::Vector3d& b, bool entering, int skip, double& s) const;
};

/// What the rules last learned of each contact pair's particle against its mesh, so that a
/// particle far from a mesh is not looked up again until it may have come near, and one point is
/// not looked up twice in a row:
/// - a lower bound of the distance of a point known to be outside: the distance is 1-Lipschitz,
///   so moving from y0 to y lowers it by at most |y - y0|;
/// - the last nearest-point query, for the same point (to the bit).
/// A cache only: the rules skip a query where its answer is certain with a slack far above
/// round-off (kBoundSlack), or known, so every result is the same with or without it, and a
/// restored run, which starts with none, continues bit for bit.
class MeshPairCache {
 public:
  explicit MeshPairCache(std::size_t pairs = 0) : entries_(pairs) {}
  /// A lower bound of the distance from the surface of y (in the mesh's frame) for `pair`, which
  /// is outside; 0 when nothing is known.
  double outside(std::size_t pair, const Eigen::Vector3d& y) const {
    const Entry& e = entries_[pair];
    return e.known && e.nearest.signed_distance > 0.0 ? std::max(0.0, e.nearest.signed_distance - (y - e.y).norm())
                                                      : 0.0;
  }
  /// The nearest point of y when the pair's last query was of y.
  const MeshCollider::Nearest* nearest(std::size_t pair, const Eigen::Vector3d& y) const {
    const Entry& e = entries_[pair];
    return e.known && e.y == y ? &e.nearest : nullptr;
  }
  /// y's nearest point (the bound holds for an outside y only: a point inside records no bound).
  void record(std::size_t pair, const Eigen::Vector3d& y, const MeshCollider::Nearest& nearest) {
    entries_[pair] = Entry{y, nearest, true};
  }
  /// A bound is trusted only beyond this share of the sizes it is compared with.
  static constexpr double kBoundSlack = 1e-9;

 private:
  struct Entry {
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    MeshCollider::Nearest nearest;
    bool known = false;
  };
  std::vector<Entry> entries_;
};

/// A scene's mesh colliders: the queries of each (null for the other shapes), indexed like its
/// colliders, and what is known of their pairs, indexed like the contact elements.
struct MeshColliders {
  std::vector<std::unique_ptr<const MeshCollider>> queries;
  mutable MeshPairCache cache;
  const MeshCollider* operator[](int collider) const { return queries[static_cast<std::size_t>(collider)].get(); }
};
/// The mesh colliders of `scene`, with room for the cache of `pairs` contact elements.
MeshColliders meshColliders(const Scene& scene, int pairs);

}  // namespace stabint
