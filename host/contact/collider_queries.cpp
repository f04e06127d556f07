#include "contact/collider_queries.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stabint {
namespace {

// [project rule] The swept test's searches: golden-section steps for a box's closest approach
// (a convex function of the segment's parameter) and bisection steps for the entry; 60 of each
// take the parameter to 1e-12 of the segment.
constexpr int kSearchSteps = 60;

// The parameter u in [0, 1] of the point of segment a + u d nearest to segment c + w e (w in
// [0, 1]): Ericson's closest points of two segments, well conditioned but for parallel ones,
// where any nearest pair serves.
double closestOnSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& c,
                        const Eigen::Vector3d& e) {
  const double dd = d.squaredNorm(), ee = e.squaredNorm();
  if (!(dd > 0.0)) return 0.0;
  const Eigen::Vector3d r = a - c;
  const double f = e.dot(r);
  if (!(ee > 0.0)) return std::clamp(-d.dot(r) / dd, 0.0, 1.0);
  const double de = d.dot(e), dr = d.dot(r), denominator = dd * ee - de * de;
  double u = denominator > 0.0 ? std::clamp((de * f - dr * ee) / denominator, 0.0, 1.0) : 0.0;
  const double w = (de * u + f) / ee;
  if (w < 0.0) u = std::clamp(-dr / dd, 0.0, 1.0);
  if (w > 1.0) u = std::clamp((de - dr) / dd, 0.0, 1.0);
  return u;
}

}  // namespace

const double* pairGeometry(const SceneData& scene, int block, int e, const double* collider,
                           const Eigen::Vector3d& shift, double* pair) {
  if (!scene.elementEnabled(block, e)) return collider;
  const ElementBlock& b = scene.blocks()[static_cast<std::size_t>(block)];
  const double* params = b.params.data() + std::size_t(b.type->shape().params) * std::size_t(e) + kContactGeometry;
  std::copy(params, params + kColliderGeometry, pair);
  translateGeometry(shift, pair);
  return pair;
}

double knownOutside(const MeshColliders& meshes, const MeshCollider& mesh, int e, const Eigen::Vector3d& y) {
  return std::max(std::sqrt(mesh.bounds().squaredExteriorDistance(y)), meshes.cache.outside(std::size_t(e), y));
}

bool surelyBeyond(double bound, double distance, const Eigen::Vector3d& y) {
  return bound > distance + MeshPairCache::kBoundSlack * (1.0 + distance + y.cwiseAbs().maxCoeff());
}

MeshCollider::Nearest nearestOf(const MeshColliders& meshes, const MeshCollider& mesh, int e,
                                const Eigen::Vector3d& y) {
  if (const MeshCollider::Nearest* known = meshes.cache.nearest(std::size_t(e), y)) return *known;
  MeshCollider::Nearest n;
  mesh.nearest(y, std::numeric_limits<double>::infinity(), n);
  meshes.cache.record(std::size_t(e), y, n);
  return n;
}

bool withinMargin(const double* g, const double* x, double margin) {
  double grown[kColliderGeometry];
  std::copy(g, g + kColliderGeometry, grown);
  const int shape = static_cast<int>(g[kGeometryShape]);
  if (shape == static_cast<int>(ColliderShape::Plane)) {
    for (int c = 0; c < 3; ++c) grown[kGeometryCenter + c] += margin * g[kGeometryA + c];
  } else if (shape == static_cast<int>(ColliderShape::Box)) {
    for (int c = 0; c < 3; ++c) grown[kGeometryA + c] += margin;
  } else {
    grown[kGeometryRadius] += margin;
  }
  double p[3];
  return closestPointOutside(grown, x, p);
}

double signedDistance(const double* g, const double* x) {
  const int shape = static_cast<int>(g[kGeometryShape]);
  const double* center = g + kGeometryCenter;
  const double* a = g + kGeometryA;
  if (shape == static_cast<int>(ColliderShape::Plane))
    return (x[0] - center[0]) * a[0] + (x[1] - center[1]) * a[1] + (x[2] - center[2]) * a[2];
  if (shape == static_cast<int>(ColliderShape::Box)) {
    double outside = 0.0, largest = -std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
      const double q = std::abs(x[c] - center[c]) - a[c];
      outside += q > 0.0 ? q * q : 0.0;
      largest = std::max(largest, q);
    }
    return std::sqrt(outside) + std::min(largest, 0.0);
  }
  Eigen::Vector3d s(center[0], center[1], center[2]);
  const Eigen::Vector3d xv(x[0], x[1], x[2]);
  if (shape == static_cast<int>(ColliderShape::Capsule)) {
    const Eigen::Vector3d ab = Eigen::Vector3d(a[0], a[1], a[2]) - s;
    const double length2 = ab.squaredNorm();
    const double u = length2 > 0.0 ? std::clamp((xv - s).dot(ab) / length2, 0.0, 1.0) : 0.0;
    s += u * ab;
  }
  return (xv - s).norm() - g[kGeometryRadius];
}

void planeGeometry(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double* plane) {
  plane[kGeometryShape] = static_cast<double>(static_cast<int>(ColliderShape::Plane));
  for (int c = 0; c < 3; ++c) plane[kGeometryCenter + c] = point[c], plane[kGeometryA + c] = normal[c];
  plane[kGeometryRadius] = 0.0;
}

void supportingPlane(const double* g, const Eigen::Vector3d& y, double* plane) {
  const int shape = static_cast<int>(g[kGeometryShape]);
  if (shape == static_cast<int>(ColliderShape::Plane)) {
    std::copy(g, g + kColliderGeometry, plane);
    return;
  }
  const double* center = g + kGeometryCenter;
  const double* a = g + kGeometryA;
  if (shape == static_cast<int>(ColliderShape::Box)) {
    const double yv[3] = {y[0], y[1], y[2]};
    double p[3];
    if (closestPointOutside(g, yv, p)) {  // inside: p moved y along one axis, to its nearest face
      int axis = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(p[c] - yv[c]) > std::abs(p[axis] - yv[axis])) axis = c;
      planeGeometry(Eigen::Vector3d(p[0], p[1], p[2]),
                    Eigen::Vector3d::Unit(axis) * (y[axis] < center[axis] ? -1.0 : 1.0), plane);
      return;
    }
    Eigen::Vector3d q;  // the nearest surface point
    for (int c = 0; c < 3; ++c) q[c] = std::clamp(y[c], center[c] - a[c], center[c] + a[c]);
    Eigen::Vector3d d = y - q;
    if (!(d.norm() > 0.0)) {  // y on a face: that face's normal
      int axis = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(y[c] - center[c]) - a[c] > std::abs(y[axis] - center[axis]) - a[axis]) axis = c;
      d = Eigen::Vector3d::Unit(axis) * (y[axis] < center[axis] ? -1.0 : 1.0);
    }
    planeGeometry(q, d / d.norm(), plane);
    return;
  }
  // A sphere, or a capsule: about the nearest point s of its axis.
  Eigen::Vector3d s(center[0], center[1], center[2]);
  if (shape == static_cast<int>(ColliderShape::Capsule)) {
    const Eigen::Vector3d ab = Eigen::Vector3d(a[0], a[1], a[2]) - s;
    const double length2 = ab.squaredNorm();
    s += (length2 > 0.0 ? std::clamp((y - s).dot(ab) / length2, 0.0, 1.0) : 0.0) * ab;
  }
  const Eigen::Vector3d r = y - s;
  const Eigen::Vector3d normal = r.norm() > 0.0 ? Eigen::Vector3d(r / r.norm()) : Eigen::Vector3d::UnitY();
  planeGeometry(s + g[kGeometryRadius] * normal, normal, plane);
}

double sweep(const double* g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double& distance, bool* enters) {
  const auto f = [&](double s) {
    const Eigen::Vector3d y = a + s * (b - a);
    const double yv[3] = {y[0], y[1], y[2]};
    return signedDistance(g, yv);
  };
  const int shape = static_cast<int>(g[kGeometryShape]);
  const Eigen::Vector3d center(g[kGeometryCenter], g[kGeometryCenter + 1], g[kGeometryCenter + 2]);
  double best = 1.0;
  if (shape == static_cast<int>(ColliderShape::Box)) {
    double lo = 0.0, hi = 1.0, f_best = f(1.0);
    constexpr double kGolden = 0.6180339887498949;
    double s1 = hi - kGolden * (hi - lo), s2 = lo + kGolden * (hi - lo), f1 = f(s1), f2 = f(s2);
    for (int i = 0; i < kSearchSteps && f_best >= 0.0; ++i) {
      if (f1 < f_best) best = s1, f_best = f1;
      if (f2 < f_best) best = s2, f_best = f2;
      if (f1 < f2) {
        hi = s2, s2 = s1, f2 = f1, s1 = hi - kGolden * (hi - lo), f1 = f(s1);
      } else {
        lo = s1, s1 = s2, f1 = f2, s2 = lo + kGolden * (hi - lo), f2 = f(s2);
      }
    }
  } else {
    const Eigen::Vector3d axis =
        shape == static_cast<int>(ColliderShape::Capsule)
            ? Eigen::Vector3d(Eigen::Vector3d(g[kGeometryA], g[kGeometryA + 1], g[kGeometryA + 2]) - center)
            : Eigen::Vector3d(Eigen::Vector3d::Zero());
    best = closestOnSegment(a, b - a, center, axis);
  }
  distance = f(best);
  if (enters) *enters = distance < 0.0;
  if (distance >= 0.0) return best;
  // It enters between 0 (outside) and `best` (inside): the crossing, from the outside.
  double out = 0.0, in = best;
  for (int i = 0; i < kSearchSteps; ++i) {
    const double mid = 0.5 * (out + in);
    (f(mid) < 0.0 ? in : out) = mid;
  }
  distance = f(out);
  return out;
}

double halfThickness(const Collider& collider) {
  if (collider.shape == ColliderShape::Box) return collider.half_extents.minCoeff();
  if (collider.shape == ColliderShape::Plane) return std::numeric_limits<double>::infinity();
  return collider.radius;
}

double halfDepthBelow(const Collider& collider, const Eigen::Vector3d& n) {
  if (collider.shape != ColliderShape::Box) return halfThickness(collider);
  Eigen::Index axis = 0;
  n.cwiseAbs().maxCoeff(&axis);
  return collider.half_extents[axis];
}

}  // namespace stabint
