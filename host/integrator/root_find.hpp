#pragma once
// Root find for the blend weight (docs/method.md section 5): alpha in [a, b] with
// H(alpha) = K(alpha) + P(alpha) = H*, where H - H* changes sign on the bracket.
//
// K(alpha) is an exact quadratic (three dot products), only the potential P needs an element
// pass per evaluation. [project rule] Each step solves K(alpha) + P_model(alpha) = H* exactly,
// with P interpolated by a parabola through the bracket ends and the last replaced point; every
// candidate stays inside the bracket, and a bisection follows two steps that made too little
// progress. Regula falsi wastes evaluations on the kinetic curvature (docs/method.md section 5
// has the measurements).
#include <algorithm>
#include <cmath>

namespace stabint {

/// K(alpha) = 1/2 (vv + 2 alpha vd + alpha^2 dd)
struct KineticQuadratic {
  double vv = 0.0, vd = 0.0, dd = 0.0;
  double at(double alpha) const { return 0.5 * (vv + 2.0 * alpha * vd + alpha * alpha * dd); }
};

struct RootResult {
  double x = 0.0;  // best point found (smallest |H - H*|)
  double g = 0.0;  // H - H* there
  int evaluations = 0;
};

namespace detail {
/// The root in [a, b] of q(x) = c2 x^2 + c1 x + c0, given q(a) and q(b) of opposite signs (so there
/// is exactly one). Falls back to the secant point if rounding puts both roots outside.
inline double quadraticRootInBracket(double c2, double c1, double c0, double a, double qa, double b, double qb) {
  const double secant = (a * qb - b * qa) / (qb - qa);
  const double scale = std::abs(c1) + std::abs(c2) * std::max(std::abs(a), std::abs(b));
  if (std::abs(c2) * std::abs(b - a) <= 1e-12 * scale) return secant;  // effectively linear
  const double disc = c1 * c1 - 4.0 * c2 * c0;
  if (disc < 0.0) return secant;
  // Numerically stable pair of roots.
  const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
  const double r1 = q / c2;
  const double r2 = q != 0.0 ? c0 / q : r1;
  const double lo = std::min(a, b), hi = std::max(a, b), slack = 1e-12 * (hi - lo);
  for (double r : {r1, r2})
    if (r >= lo - slack && r <= hi + slack) return std::clamp(r, lo, hi);
  return secant;
}
}  // namespace detail

/// Finds alpha in [a, b] with |K(alpha) + P(alpha) - target| <= tol, given P(a) = pa and
/// P(b) = pb with K + P - target of opposite signs at a and b, using at most `max_evaluations`
/// calls of `potential(alpha) -> double`.
template <class Potential>
RootResult findBlendWeight(const KineticQuadratic& kinetic, Potential&& potential, double target, double a, double pa,
                           double b, double pb, double tol, int max_evaluations) {
  double ga = kinetic.at(a) + pa - target;
  double gb = kinetic.at(b) + pb - target;
  RootResult best{std::abs(ga) <= std::abs(gb) ? a : b, std::abs(ga) <= std::abs(gb) ? ga : gb, 0};
  bool bisect = false;  // the last two model steps made too little progress
  int slow = 0;         // consecutive model steps that did not halve |H - H*|
  double last_g = std::abs(best.g);
  bool have_c = false;  // a third point (the end replaced last), for a quadratic model of P
  double c = 0.0, pc = 0.0;
  while (best.evaluations < max_evaluations && std::abs(best.g) > tol) {
    double x;
    if (bisect) {
      x = 0.5 * (a + b);
    } else {
      // Model P by Newton interpolation through the bracket ends (and the third point when it
      // is well separated from both): P = pa + f1 (x - a) + f2 (x - a)(x - b). The model
      // matches H - H* at a and b, so K + P_model - target has exactly one root in [a, b].
      const double f1 = (pb - pa) / (b - a);
      const double span = std::abs(b - a);
      double f2 = 0.0;
      if (have_c && std::abs(c - a) > 1e-3 * span && std::abs(c - b) > 1e-3 * span)
        f2 = ((pc - pa) / (c - a) - f1) / (c - b);
      x = detail::quadraticRootInBracket(0.5 * kinetic.dd + f2, kinetic.vd + f1 - f2 * (a + b),
                                         0.5 * kinetic.vv - target + pa - f1 * a + f2 * a * b, a, ga, b, gb);
    }
    const double px = potential(x);
    const double gx = kinetic.at(x) + px - target;
    ++best.evaluations;
    // Two model steps in a row that did not halve |H - H*| are followed by a bisection, so a
    // badly modelled P (blending two distant configurations can make it far from a parabola)
    // cannot stall the bracket on one side.
    if (bisect) {
      bisect = false;
      slow = 0;
    } else {
      slow = std::abs(gx) > 0.5 * last_g ? slow + 1 : 0;
      bisect = slow >= 2;
    }
    last_g = std::abs(gx);
    if (std::abs(gx) < std::abs(best.g)) {
      best.x = x;
      best.g = gx;
    }
    have_c = true;
    if ((gx > 0.0) == (ga > 0.0)) {  // x replaces a
      c = a, pc = pa;
      a = x, pa = px, ga = gx;
    } else {
      c = b, pc = pb;
      b = x, pb = px, gb = gx;
    }
  }
  return best;
}

}  // namespace stabint
