#pragma once
// A spring cloth stepped with BE by a simulator and its untouched twin: the tests of refused and
// huge changes compare the one that saw them with the one that did not.
#include <stabint/stabint.hpp>

namespace stabint::testing {

/// `side` x `side` particles (6 by default), both stepped `steps` times at construction.
struct ClothAndTwin {
  Scene cloth;
  Simulator sim, twin;
  static Scene scene(int side = 6) {
    ClothGridParams p;
    p.nx = p.ny = side;
    return makeClothGrid(p);
  }
  static SimulatorOptions options() {
    SimulatorOptions o;
    o.integrator = Integrator::BackwardEuler;
    return o;
  }
  explicit ClothAndTwin(int steps, int side = 6) : cloth(scene(side)), sim(cloth, options()), twin(cloth, options()) {
    both(steps);
  }
  void both(int steps) {
    for (int i = 0; i < steps; ++i) {
      sim.step();
      twin.step();
    }
  }
  double size() const { return (cloth.positions.colwise().maxCoeff() - cloth.positions.colwise().minCoeff()).norm(); }
};

}  // namespace stabint::testing
