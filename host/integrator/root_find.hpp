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

/// The root find as a resumable state machine, so that a batch of scenes can run one search per
/// scene in lockstep, one batched energy pass per round (docs/batch_design.md, "The step in
/// lockstep"): while !done(), evaluate the potential at next() and take() it. Finds alpha in [a, b] with
/// |K(alpha) + P(alpha) - target| <= tol, given P(a) = pa and P(b) = pb with K + P - target of
/// opposite signs at a and b, using at most `max_evaluations` evaluations.
class BlendWeightSearch {
 public:
  BlendWeightSearch(const KineticQuadratic& kinetic, double target, double a, double pa, double b, double pb,
                    double tol, int max_evaluations)
      : kinetic_(kinetic),
        target_(target),
        tol_(tol),
        max_evaluations_(max_evaluations),
        a_(a),
        pa_(pa),
        b_(b),
        pb_(pb) {
    ga_ = kinetic.at(a) + pa - target;
    gb_ = kinetic.at(b) + pb - target;
    best_ = RootResult{std::abs(ga_) <= std::abs(gb_) ? a : b, std::abs(ga_) <= std::abs(gb_) ? ga_ : gb_, 0};
    last_g_ = std::abs(best_.g);
  }

  bool done() const { return !(best_.evaluations < max_evaluations_ && std::abs(best_.g) > tol_); }

  /// The point to evaluate next (only while !done()).
  double next() const {
    if (bisect_) return 0.5 * (a_ + b_);
    // Model P by Newton interpolation through the bracket ends (and the third point when it is
    // well separated from both): P = pa + f1 (x - a) + f2 (x - a)(x - b). The model matches
    // H - H* at a and b, so K + P_model - target has exactly one root in [a, b].
    const double f1 = (pb_ - pa_) / (b_ - a_);
    const double span = std::abs(b_ - a_);
    double f2 = 0.0;
    if (have_c_ && std::abs(c_ - a_) > 1e-3 * span && std::abs(c_ - b_) > 1e-3 * span)
      f2 = ((pc_ - pa_) / (c_ - a_) - f1) / (c_ - b_);
    return detail::quadraticRootInBracket(0.5 * kinetic_.dd + f2, kinetic_.vd + f1 - f2 * (a_ + b_),
                                          0.5 * kinetic_.vv - target_ + pa_ - f1 * a_ + f2 * a_ * b_, a_, ga_, b_, gb_);
  }

  /// The potential px at x = next().
  void take(double x, double px) {
    const double gx = kinetic_.at(x) + px - target_;
    ++best_.evaluations;
    // Two model steps in a row that did not halve |H - H*| are followed by a bisection, so a
    // badly modelled P (blending two distant configurations can make it far from a parabola)
    // cannot stall the bracket on one side.
    if (bisect_) {
      bisect_ = false;
      slow_ = 0;
    } else {
      slow_ = std::abs(gx) > 0.5 * last_g_ ? slow_ + 1 : 0;
      bisect_ = slow_ >= 2;
    }
    last_g_ = std::abs(gx);
    if (std::abs(gx) < std::abs(best_.g)) {
      best_.x = x;
      best_.g = gx;
    }
    have_c_ = true;
    if ((gx > 0.0) == (ga_ > 0.0)) {  // x replaces a
      c_ = a_, pc_ = pa_;
      a_ = x, pa_ = px, ga_ = gx;
    } else {
      c_ = b_, pc_ = pb_;
      b_ = x, pb_ = px, gb_ = gx;
    }
  }

  const RootResult& result() const { return best_; }

 private:
  KineticQuadratic kinetic_;
  double target_, tol_;
  int max_evaluations_;
  double a_, pa_, ga_ = 0.0, b_, pb_, gb_ = 0.0;
  RootResult best_;
  bool bisect_ = false;  // the last two model steps made too little progress
  int slow_ = 0;         // consecutive model steps that did not halve |H - H*|
  double last_g_ = 0.0;
  bool have_c_ = false;  // a third point (the end replaced last), for a quadratic model of P
  double c_ = 0.0, pc_ = 0.0;
};

/// BlendWeightSearch run to the end with `potential(alpha) -> double`.
template <class Potential>
RootResult findBlendWeight(const KineticQuadratic& kinetic, Potential&& potential, double target, double a, double pa,
                           double b, double pb, double tol, int max_evaluations) {
  BlendWeightSearch search(kinetic, target, a, pa, b, pb, tol, max_evaluations);
  while (!search.done()) {
    const double x = search.next();
    search.take(x, potential(x));
  }
  return search.result();
}

}  // namespace stabint
