#pragma once
// Bracketing root find for the blend weight (method.md section 3): the Illinois variant of
// regula falsi. H(alpha) is continuous with a sign change on the bracket, so the method always
// converges, and unlike bisection it needs only a few energy evaluations in practice.
#include <cmath>

namespace stabint {

struct RootResult {
  double x = 0.0;   // best point found (smallest |g|)
  double g = 0.0;   // g at that point
  int evaluations = 0;
};

/// Finds x in [a, b] with |g(x)| <= tol, given g(a) = ga and g(b) = gb of opposite signs, using
/// at most `max_evaluations` new evaluations of g. `g` is called as g(x) -> double.
template <class Function>
RootResult illinoisRoot(Function&& g, double a, double ga, double b, double gb, double tol,
                        int max_evaluations) {
  RootResult best{std::abs(ga) <= std::abs(gb) ? a : b, std::abs(ga) <= std::abs(gb) ? ga : gb, 0};
  int side = 0;  // which end was kept last time: -1 = a, +1 = b
  while (best.evaluations < max_evaluations && std::abs(best.g) > tol) {
    const double x = (a * gb - b * ga) / (gb - ga);
    const double gx = g(x);
    ++best.evaluations;
    if (std::abs(gx) < std::abs(best.g)) {
      best.x = x;
      best.g = gx;
    }
    if ((gx > 0.0) == (gb > 0.0)) {
      b = x;
      gb = gx;
      if (side == -1) ga *= 0.5;  // a kept twice in a row: halve its weight (Illinois)
      side = -1;
    } else {
      a = x;
      ga = gx;
      if (side == +1) gb *= 0.5;
      side = +1;
    }
  }
  return best;
}

}  // namespace stabint
