#include "contact/mesh_collider.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stabint {
namespace {

using Vec = Eigen::Vector3d;

// The nearest point of triangle (a, b, c) to p (Ericson, "Real-Time Collision Detection", 5.1.5)
// and the feature it lies on: -1 the face, 0-2 a vertex, 3 + k the edge from vertex k to k + 1.
Vec closestOnTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c, int& feature) {
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return feature = 0, a;
  const Vec bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return feature = 1, b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return feature = 3, Vec(a + d1 / (d1 - d3) * ab);
  const Vec cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return feature = 2, c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return feature = 5, Vec(a + d2 / (d2 - d6) * ac);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return feature = 4, Vec(b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b));
  const double denominator = 1.0 / (va + vb + vc);
  return feature = -1, Vec(a + ab * (vb * denominator) + ac * (vc * denominator));
}

std::pair<int, int> edgeKey(int i, int j) { return {std::min(i, j), std::max(i, j)}; }

// The segment a + s (b - a), s in [0, 1], against a box: whether some s in [0, limit] is in it
// (the slab test).
bool segmentMeetsBox(const Vec& a, const Vec& d, double limit, const Eigen::AlignedBox3d& box) {
  double lo = 0.0, hi = limit;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (a[k] < box.min()[k] || a[k] > box.max()[k]) return false;
      continue;
    }
    double t0 = (box.min()[k] - a[k]) / d[k], t1 = (box.max()[k] - a[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
    if (lo > hi) return false;
  }
  return true;
}

}  // namespace

MeshCollider::MeshCollider(const Collider& collider)
    : vertices_(collider.mesh_vertices), triangles_(collider.mesh_triangles) {
  const std::size_t n = triangles_.size();
  face_normals_.resize(n);
  vertex_normals_.assign(static_cast<std::size_t>(vertices_.rows()), Vec::Zero());
  std::vector<int> objects(n);
  std::vector<Eigen::AlignedBox3d> boxes(n);
  for (std::size_t t = 0; t < n; ++t) {
    const std::array<int, 3>& f = triangles_[t];
    const Vec p[3] = {vertices_.row(f[0]).transpose(), vertices_.row(f[1]).transpose(),
                      vertices_.row(f[2]).transpose()};
    const Vec normal = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    face_normals_[t] = normal;
    for (int k = 0; k < 3; ++k) {
      // Angle-weighted: the face's angle at the vertex.
      const Vec u = (p[(k + 1) % 3] - p[k]).normalized(), w = (p[(k + 2) % 3] - p[k]).normalized();
      vertex_normals_[static_cast<std::size_t>(f[k])] += std::acos(std::clamp(u.dot(w), -1.0, 1.0)) * normal;
      // An Eigen vector default-constructs uninitialized: the first face's normal starts the sum.
      const auto [edge, first] = edge_normals_.emplace(edgeKey(f[k], f[(k + 1) % 3]), normal);
      if (!first) edge->second += normal;
    }
    objects[t] = static_cast<int>(t);
    boxes[t] = Eigen::AlignedBox3d(p[0]);
    boxes[t].extend(p[1]).extend(p[2]);
    bounds_.extend(boxes[t]);
  }
  tree_.init(objects.begin(), objects.end(), boxes.begin(), boxes.end());
  // Each triangle's centroid, straight inward to the far side (a closed mesh always has one).
  const double reach = 2.0 * bounds_.diagonal().norm();
  thickness_ = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < n; ++t) {
    const std::array<int, 3>& f = triangles_[t];
    const Vec centroid = (vertices_.row(f[0]) + vertices_.row(f[1]) + vertices_.row(f[2])).transpose() / 3.0;
    double s = 0.0;
    if (firstCrossing(centroid, centroid - reach * face_normals_[t], false, static_cast<int>(t), s) >= 0)
      thickness_ = std::min(thickness_, s * reach);
  }
}

MeshCollider::Nearest MeshCollider::nearestOnTriangle(int t, const Vec& x) const {
  const std::array<int, 3>& f = triangles_[static_cast<std::size_t>(t)];
  int feature = -1;
  Nearest out;
  out.point = closestOnTriangle(x, vertices_.row(f[0]).transpose(), vertices_.row(f[1]).transpose(),
                                vertices_.row(f[2]).transpose(), feature);
  const Vec& pseudo = feature < 0   ? face_normals_[static_cast<std::size_t>(t)]
                      : feature < 3 ? vertex_normals_[static_cast<std::size_t>(f[feature])]
                                    : edge_normals_.at(edgeKey(f[feature - 3], f[(feature - 2) % 3]));
  const Vec d = x - out.point;
  const double distance = d.norm();
  const bool outside = d.dot(pseudo) >= 0.0;
  out.signed_distance = outside ? distance : -distance;
  out.normal = distance > 0.0 ? Vec((outside ? 1.0 : -1.0) * d / distance) : pseudo.normalized();
  return out;
}

bool MeshCollider::nearest(const Vec& x, double cutoff, Nearest& out) const {
  // The triangle nearest to x; of two as near, the one listed first (the same on every run).
  struct Minimizer {
    typedef double Scalar;
    const MeshCollider& mesh;
    const Vec& x;
    double limit;  // squared distances beyond it are not looked at
    int best = -1;
    double best_squared = std::numeric_limits<double>::infinity();
    double minimumOnVolume(const Eigen::AlignedBox3d& box) const {
      const double d = box.squaredExteriorDistance(x);
      return d <= limit ? d : std::numeric_limits<double>::max();
    }
    double minimumOnObject(int t) {
      const std::array<int, 3>& f = mesh.triangles_[static_cast<std::size_t>(t)];
      int feature = -1;
      const double d =
          (x - closestOnTriangle(x, mesh.vertices_.row(f[0]).transpose(), mesh.vertices_.row(f[1]).transpose(),
                                 mesh.vertices_.row(f[2]).transpose(), feature))
              .squaredNorm();
      if (d < best_squared || (d == best_squared && t < best)) best = t, best_squared = d;
      return d;
    }
  };
  Minimizer near{*this, x, cutoff * cutoff};
  Eigen::BVMinimize(tree_, near);
  if (near.best < 0 || near.best_squared > near.limit) {
    if (!bounds_.contains(x)) return false;
    Minimizer any{*this, x, std::numeric_limits<double>::infinity()};
    Eigen::BVMinimize(tree_, any);
    if (any.best < 0) return false;
    out = nearestOnTriangle(any.best, x);
    return out.signed_distance < 0.0;
  }
  out = nearestOnTriangle(near.best, x);
  return true;
}

int MeshCollider::firstCrossing(const Vec& a, const Vec& b, bool entering, int skip, double& s) const {
  struct Intersector {
    const MeshCollider& mesh;
    const Vec a, d;
    bool entering;
    int skip;
    double best_s = std::numeric_limits<double>::infinity();
    int best = -1;
    bool intersectVolume(const Eigen::AlignedBox3d& box) const {
      return segmentMeetsBox(a, d, std::min(1.0, best_s), box);
    }
    bool intersectObject(int t) {
      if (t == skip) return false;
      const std::array<int, 3>& f = mesh.triangles_[static_cast<std::size_t>(t)];
      const double along = d.dot(mesh.face_normals_[static_cast<std::size_t>(t)]);
      if (!(entering ? along < 0.0 : along > 0.0)) return false;  // the other way, or grazing
      // Moeller and Trumbore's segment-triangle test.
      const Vec p0 = mesh.vertices_.row(f[0]).transpose();
      const Vec e1 = mesh.vertices_.row(f[1]).transpose() - p0, e2 = mesh.vertices_.row(f[2]).transpose() - p0;
      const Vec q = d.cross(e2);
      const double det = e1.dot(q);
      if (det == 0.0) return false;
      const Vec r = a - p0;
      const double u = r.dot(q) / det;
      if (u < 0.0 || u > 1.0) return false;
      const Vec rxe1 = r.cross(e1);
      const double v = d.dot(rxe1) / det;
      if (v < 0.0 || u + v > 1.0) return false;
      const double hit = e2.dot(rxe1) / det;
      if (hit < 0.0 || hit > 1.0) return false;
      if (hit < best_s || (hit == best_s && t < best)) best_s = hit, best = t;
      return false;  // look on: a nearer crossing may follow
    }
  };
  Intersector crossing{*this, a, b - a, entering, skip};
  Eigen::BVIntersect(tree_, crossing);
  s = crossing.best_s;
  return crossing.best;
}

bool MeshCollider::firstEntry(const Vec& a, const Vec& b, double& s, Vec& normal) const {
  const int t = firstCrossing(a, b, true, -1, s);
  if (t < 0) return false;
  normal = face_normals_[static_cast<std::size_t>(t)];
  return true;
}

MeshColliders meshColliders(const Scene& scene, int pairs) {
  MeshColliders meshes;
  meshes.queries.resize(scene.colliders.size());
  bool any = false;
  for (std::size_t c = 0; c < scene.colliders.size(); ++c) {
    if (scene.colliders[c].shape != ColliderShape::Mesh) continue;
    meshes.queries[c] = std::make_unique<MeshCollider>(scene.colliders[c]);
    any = true;
  }
  if (any) meshes.cache = MeshPairCache(static_cast<std::size_t>(pairs));
  return meshes;
}

}  // namespace stabint
