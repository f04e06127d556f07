// Pin (vertex j, target q(t), stiffness k): E = k/2 |x_j - q(t)|^2.
// A x = x_j (coefficient [1]), w = k, p = q(t): the only element whose params depend on time.
#include "elements/element_kind.hpp"

#include <cmath>

namespace stabint {
namespace {

using validation::invalid;

struct PinKind : KindDefaults<Pin> {
  static constexpr auto kList = &Scene::pins;
  static constexpr const char* kName = "pin";
  static constexpr const char* kIdentifier = elementKindName(ElementKind::Pin);
  static constexpr int kVertices = 1, kRows = 1;
  static constexpr int kParams = 4;  // k, q(t)
  // One element of a local step on one core, in ns (a copy of the target; measured by
  // thread_pass_kind/*): the CPU reference weighs a pass by it when it decides whether to put
  // it on threads.
  static constexpr double kElementNs = 3.0;
  static constexpr bool kSharedCoefficients = true;
  static constexpr std::array<double, 1> kCoefficients{1.0};
  static constexpr EnergyTerm kTerm = EnergyTerm::Pins;
  static constexpr bool kMayDependOnTime = true;

  static std::array<int*, 1> vertexRefs(Pin& pin) { return {&pin.vertex}; }

  static void check(const Scene& scene, const Pin& pin, const validation::Owner& owner) {
    validation::checkIndex(pin.vertex, scene.numParticles(), owner, "vertex");
    validation::checkStiffness(pin.stiffness, owner);
    validation::checkFinite(pin.target.position, owner, "target position");
    validation::checkFinite(pin.target.velocity, owner, "target velocity");
    validation::checkFinite(pin.target.amplitude, owner, "target amplitude");
    validation::checkFinite(pin.target.frequency, owner, "target frequency");
  }

  static bool timeDependent(const RunningScene& data) { return data.hasMovingPins(); }
  // The target comes from the forcing (the scene's law, or the user's ramp once one was set).
  static void paramsAt(const RunningScene& data, int pin, double t, double* p) {
    write(data.scene().pins[pin].stiffness, data.pinTarget(pin, t), p);
  }
  static void params(const Scene&, const Pin& pin, double* p) { write(pin.stiffness, pin.target.at(0.0), p); }
  static void write(double stiffness, const Eigen::Vector3d& q, double* p) {
    p[0] = stiffness;
    p[1] = q.x();
    p[2] = q.y();
    p[3] = q.z();
  }

  static double project(const double* ax, const double* params, double* p) {
    for (int c = 0; c < 3; ++c) p[c] = params[1 + c];
    return halfWeightedSquaredDistance(params[0], ax, p, 3);
  }
};

}  // namespace

template <>
const ElementType& elementTypeOf<ElementKind::Pin>() {
  static const ElementTypeOf<PinKind> type;
  return type;
}

}  // namespace stabint
