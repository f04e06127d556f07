// The blend-weight root find: alpha in [a, b] with K(alpha) + P(alpha) = H*, K an exact quadratic.
#include "integrator/root_find.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace stabint {
namespace {

struct Counted {
  std::vector<double> points;
};

// With P exactly quadratic the model is exact after the first step: the root is found in at
// most two evaluations, to round-off.
TEST(RootFind, ExactForQuadraticPotential) {
  const KineticQuadratic k{2.0, -1.5, 3.0};
  auto p = [](double a) { return 1.0 - 4.0 * a + 1.7 * a * a; };
  const double target = 0.4;
  Counted c;
  auto potential = [&](double a) {
    c.points.push_back(a);
    return p(a);
  };
  const RootResult r = findBlendWeight(k, potential, target, 0.0, p(0.0), 1.0, p(1.0), 1e-13, 12);
  EXPECT_LE(r.evaluations, 2);
  EXPECT_NEAR(k.at(r.x) + p(r.x), target, 1e-13);
  for (double a : c.points) {
    EXPECT_GE(a, 0.0);
    EXPECT_LE(a, 1.0);
  }
}

// A potential far from a parabola (non-monotone, like blending two distant configurations of
// stiff springs): the bracket keeps every candidate inside and it converges within the budget.
TEST(RootFind, ConvergesInsideTheBracketForAWildPotential) {
  const KineticQuadratic k{0.1, 0.0, 0.05};
  auto p = [](double a) { return 2.0 + 6.0 * std::sin(3.0 * a) * a - 9.5 * std::pow(a, 6); };
  const double target = 1.0;
  const double ga = k.at(0.0) + p(0.0) - target, gb = k.at(1.0) + p(1.0) - target;
  ASSERT_GT(ga * -gb, 0.0);  // a sign change on [0, 1]
  std::vector<double> points;
  auto potential = [&](double a) {
    points.push_back(a);
    return p(a);
  };
  const RootResult r = findBlendWeight(k, potential, target, 0.0, p(0.0), 1.0, p(1.0), 1e-9, 40);
  EXPECT_LT(std::abs(r.g), 1e-9);
  EXPECT_NEAR(k.at(r.x) + p(r.x) - target, r.g, 1e-15);
  EXPECT_LT(r.evaluations, 40);
  for (double a : points) {
    EXPECT_GE(a, 0.0);
    EXPECT_LE(a, 1.0);
  }
}

// It stops at the evaluation budget and returns the best point seen.
TEST(RootFind, RespectsTheEvaluationBudget) {
  const KineticQuadratic k{0.0, 0.0, 0.0};
  auto p = [](double a) { return std::cbrt(a - 0.3); };
  int calls = 0;
  auto potential = [&](double a) {
    ++calls;
    return p(a);
  };
  const RootResult r = findBlendWeight(k, potential, 0.0, 0.0, p(0.0), 1.0, p(1.0), 1e-300, 5);
  EXPECT_EQ(calls, 5);
  EXPECT_EQ(r.evaluations, 5);
  EXPECT_LT(std::abs(r.g), std::abs(p(0.0)));
}

}  // namespace
}  // namespace stabint
