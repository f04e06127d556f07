#include "contact/pair_events.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>

namespace stabint {
namespace {

using Vec3 = Eigen::Vector3d;

// Barycentric weights (of a, b, c) of the point of triangle abc closest to p (Ericson, "Real-Time
// Collision Detection", 5.1.5). A degenerate triangle gives its closest vertex or edge point.
Vec3 closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) return {1, 0, 0};  // degenerate: its first vertex
  const double v = vb / sum, w = vc / sum;
  return {1 - v - w, v, w};
}

// Parameters (s on p1 q1, t on p2 q2) of the closest points of two segments (Ericson 5.1.9).
std::pair<double, double> closestOnSegments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kTiny = 1e-300;
  if (a <= kTiny && e <= kTiny) return {0.0, 0.0};
  double s = 0.0, t = 0.0;
  if (a <= kTiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;  // parallel: any s
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return {s, t};
}

// The times in (0, 1] worth a look for a pair whose coplanarity is the cubic
// f(t) = c[0] + c[1] t + c[2] t^2 + c[3] t^3: its roots in [0, 1] (sign changes, bisected to the
// last bit) and its extrema in (0, 1) (where a pair that touches without crossing is closest),
// ascending.
int timesToCheck(const double c[4], double out[8]) {
  auto f = [&](double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; };
  double knots[4] = {0.0, 0.0, 0.0, 0.0};
  int k = 0;
  knots[k++] = 0.0;
  // f'(t) = 3 c3 t^2 + 2 c2 t + c1.
  const double qa = 3.0 * c[3], qb = 2.0 * c[2], qc = c[1];
  double extrema[2];
  int ne = 0;
  if (qa != 0.0) {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double sq = std::sqrt(disc);
      const double q = -0.5 * (qb + (qb >= 0.0 ? sq : -sq));
      const double r1 = q != 0.0 ? q / qa : 0.0, r2 = q != 0.0 ? qc / q : 0.0;
      extrema[ne++] = std::min(r1, r2);
      if (r1 != r2) extrema[ne++] = std::max(r1, r2);
    }
  } else if (qb != 0.0) {
    extrema[ne++] = -qc / qb;
  }
  int n = 0;
  for (int i = 0; i < ne; ++i)
    if (extrema[i] > 0.0 && extrema[i] < 1.0) knots[k++] = extrema[i];
  knots[k++] = 1.0;
  for (int i = 0; i + 1 < k; ++i) {
    double lo = knots[i], hi = knots[i + 1];
    double flo = f(lo), fhi = f(hi);
    if (flo == 0.0 && i == 0) out[n++] = 0.0;
    if ((flo < 0.0 && fhi > 0.0) || (flo > 0.0 && fhi < 0.0)) {
      for (int it = 0; it < 80 && hi - lo > 0.0; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        const double fm = f(mid);
        if ((fm < 0.0) == (flo < 0.0)) {
          lo = mid;
          flo = fm;
        } else {
          hi = mid;
        }
      }
      out[n++] = hi;
    } else if (fhi == 0.0) {
      out[n++] = hi;
    }
    if (i + 2 < k) out[n++] = knots[i + 1];  // the extremum itself
  }
  std::sort(out, out + n);
  return static_cast<int>(std::unique(out, out + n) - out);
}

// The coplanarity cubic of four moving points, f(t) = ((u x w) . q)(t) with u, w, q linear in t.
void coplanarityCubic(const Vec3& u0, const Vec3& u1, const Vec3& w0, const Vec3& w1, const Vec3& q0, const Vec3& q1,
                      double c[4]) {
  const Vec3 du = u1 - u0, dw = w1 - w0, dq = q1 - q0;
  const Vec3 c0 = u0.cross(w0), c1 = u0.cross(dw) + du.cross(w0), c2 = du.cross(dw);
  c[0] = c0.dot(q0);
  c[1] = c0.dot(dq) + c1.dot(q0);
  c[2] = c1.dot(dq) + c2.dot(q0);
  c[3] = c2.dot(dq);
}

Vec3 lerp(const Vec3& a, const Vec3& b, double t) { return a + t * (b - a); }

// The pair's direction at x0: from the second primitive's closest point to the first's, or,
// where they touch at x0, `fallback` turned against the pair's relative motion `motion`.
bool separatingDirection(const Vec3& gap, const Vec3& fallback, const Vec3& motion, double scale, Vec3& n) {
  const double length = gap.norm();
  if (length > 1e-12 * scale) {
    n = gap / length;
    return true;
  }
  const double f = fallback.norm();
  if (!(f > 0.0)) return false;
  n = fallback / f;
  if (n.dot(motion) > 0.0) n = -n;
  return true;
}

}  // namespace

void supportPairEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, int v, const std::array<int, 3>& tri,
                      double reach, double scale, std::vector<ContactEvent>& out) {
  const Vec3 p0 = rowOf(x0, v), a0 = rowOf(x0, tri[0]), b0 = rowOf(x0, tri[1]), c0 = rowOf(x0, tri[2]);
  const Vec3 w_start = closestOnTriangle(p0, a0, b0, c0);
  const Vec3 gap = p0 - (w_start[0] * a0 + w_start[1] * b0 + w_start[2] * c0);
  const Vec3 face = (b0 - a0).cross(c0 - a0);
  const double length = gap.norm();
  if (!(length > 1e-12 * scale) || !(std::abs(face.dot(gap)) >= 0.5 * face.norm() * length)) return;
  const Vec3 p1 = rowOf(x1, v), a1 = rowOf(x1, tri[0]), b1 = rowOf(x1, tri[1]), c1 = rowOf(x1, tri[2]);
  const Vec3 w = closestOnTriangle(p1, a1, b1, c1);
  if (!((p1 - (w[0] * a1 + w[1] * b1 + w[2] * c1)).norm() < reach)) return;
  ContactEvent e;
  e.normal = gap / length;
  e.vertices = {v, tri[0], tri[1], tri[2]};
  e.weights = {1.0, -w[0], -w[1], -w[2]};
  out.push_back(e);
}

void vertexTriangleEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, int v, const std::array<int, 3>& tri,
                         double closer_than, double touching, double scale, std::vector<ContactEvent>& out) {
  double times[8];
  const Vec3 p0 = rowOf(x0, v), p1 = rowOf(x1, v);
  const Vec3 a0 = rowOf(x0, tri[0]), a1 = rowOf(x1, tri[0]);
  const Vec3 b0 = rowOf(x0, tri[1]), b1 = rowOf(x1, tri[1]);
  const Vec3 c0 = rowOf(x0, tri[2]), c1 = rowOf(x1, tri[2]);
  // The pair's distance shrinks over the step by at most the largest motion of the particle
  // relative to a vertex of the triangle: a pair farther apart than that (and the thickness)
  // at x0 cannot meet.
  const Vec3 dp = p1 - p0;
  const double relative = std::sqrt(
      std::max({(dp - (a1 - a0)).squaredNorm(), (dp - (b1 - b0)).squaredNorm(), (dp - (c1 - c0)).squaredNorm()}));
  const double reach = relative + std::max(closer_than, touching);
  // First by the triangle's bounding sphere about its centroid (most pairs stop here).
  const Vec3 centroid = (a0 + b0 + c0) / 3.0;
  const double radius = std::sqrt(
      std::max({(a0 - centroid).squaredNorm(), (b0 - centroid).squaredNorm(), (c0 - centroid).squaredNorm()}));
  if ((p0 - centroid).norm() - radius > reach) return;
  const Vec3 w_start = closestOnTriangle(p0, a0, b0, c0);
  const double d_start = (p0 - (w_start[0] * a0 + w_start[1] * b0 + w_start[2] * c0)).norm();
  if (d_start > reach) return;
  double cubic[4];
  coplanarityCubic(b0 - a0, b1 - a1, c0 - a0, c1 - a1, p0 - a0, p1 - a1, cubic);
  const int count = timesToCheck(cubic, times);
  bool found = false, crossing = false;
  Vec3 bary;
  for (int i = 0; i < count && !found; ++i) {
    const double s = times[i];
    const Vec3 p = lerp(p0, p1, s), a = lerp(a0, a1, s), b = lerp(b0, b1, s), c = lerp(c0, c1, s);
    const Vec3 w = closestOnTriangle(p, a, b, c);
    if ((p - (w[0] * a + w[1] * b + w[2] * c)).norm() <= touching) found = crossing = true, bary = w;
  }
  if (!found) {
    const Vec3 w = closestOnTriangle(p1, a1, b1, c1);
    if ((p1 - (w[0] * a1 + w[1] * b1 + w[2] * c1)).norm() < closer_than) found = true, bary = w;
  }
  if (!found) return;
  const Vec3 gap = p0 - (w_start[0] * a0 + w_start[1] * b0 + w_start[2] * c0);
  const Vec3 motion = (p1 - p0) - (bary[0] * (a1 - a0) + bary[1] * (b1 - b0) + bary[2] * (c1 - c0));
  ContactEvent e;
  if (!separatingDirection(gap, (b0 - a0).cross(c0 - a0), motion, scale, e.normal)) return;
  e.vertices = {v, tri[0], tri[1], tri[2]};
  e.weights = {1.0, -bary[0], -bary[1], -bary[2]};
  e.crossing = crossing;
  out.push_back(e);
}

void edgeEdgeEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, const std::array<int, 2>& e1,
                   const std::array<int, 2>& e2, double closer_than, double touching, double scale,
                   std::vector<ContactEvent>& out) {
  double times[8];
  const Vec3 a0 = rowOf(x0, e1[0]), a1 = rowOf(x1, e1[0]), b0 = rowOf(x0, e1[1]), b1 = rowOf(x1, e1[1]);
  const Vec3 c0 = rowOf(x0, e2[0]), c1 = rowOf(x1, e2[0]), d0 = rowOf(x0, e2[1]), d1 = rowOf(x1, e2[1]);
  // As for a vertex and a triangle: the largest relative motion of two of the four ends bounds
  // how much nearer the edges can come.
  double relative = 0.0;
  for (const Vec3& u : {Vec3(a1 - a0), Vec3(b1 - b0)})
    for (const Vec3& w : {Vec3(c1 - c0), Vec3(d1 - d0)}) relative = std::max(relative, (u - w).squaredNorm());
  relative = std::sqrt(relative);
  const double reach = relative + std::max(closer_than, touching);
  // The exact gap at x0 first: the broad phase's boxes hold only near pairs, and a bounding-sphere
  // test before it stops few of them (6 % on a crumpling cloth) for three square roots each.
  const auto q0 = closestOnSegments(a0, b0, c0, d0);
  const Vec3 gap = lerp(a0, b0, q0.first) - lerp(c0, d0, q0.second);
  if (gap.norm() > reach) return;
  double cubic[4];
  coplanarityCubic(b0 - a0, b1 - a1, d0 - c0, d1 - c1, c0 - a0, c1 - a1, cubic);
  const int count = timesToCheck(cubic, times);
  bool found = false, crossing = false;
  std::pair<double, double> st;
  for (int k = 0; k < count && !found; ++k) {
    const double s = times[k];
    const Vec3 a = lerp(a0, a1, s), b = lerp(b0, b1, s), c = lerp(c0, c1, s), d = lerp(d0, d1, s);
    const auto q = closestOnSegments(a, b, c, d);
    if ((lerp(a, b, q.first) - lerp(c, d, q.second)).norm() <= touching) found = crossing = true, st = q;
  }
  if (!found) {
    const auto q = closestOnSegments(a1, b1, c1, d1);
    if ((lerp(a1, b1, q.first) - lerp(c1, d1, q.second)).norm() < closer_than) found = true, st = q;
  }
  if (!found) return;
  const Vec3 motion =
      (lerp(a1, b1, st.first) - lerp(a0, b0, st.first)) - (lerp(c1, d1, st.second) - lerp(c0, d0, st.second));
  ContactEvent e;
  if (!separatingDirection(gap, (b0 - a0).cross(d0 - c0), motion, scale, e.normal)) return;
  e.vertices = {e1[0], e1[1], e2[0], e2[1]};
  e.edge_edge = true;
  e.weights = {1.0 - st.first, st.first, -(1.0 - st.second), -st.second};
  e.crossing = crossing;
  out.push_back(e);
}

}  // namespace stabint
