// Names of the public enums and small value-type helpers of simulator.hpp.
#include <stabint/simulator.hpp>

#include <algorithm>
#include <cctype>

namespace stabint {
namespace {
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}
}  // namespace

const char* integratorName(Integrator integrator) {
  switch (integrator) {
    case Integrator::ForwardEuler: return "FE";
    case Integrator::SymplecticEuler: return "SE";
    case Integrator::BackwardEuler: return "BE";
    case Integrator::BDF2: return "BDF2";
    case Integrator::ImplicitMidpoint: return "IM";
    case Integrator::EnergyBlend: return "blend";
  }
  return "?";
}

std::vector<Integrator> allIntegrators() {
  return {Integrator::ForwardEuler, Integrator::SymplecticEuler,  Integrator::BackwardEuler,
          Integrator::BDF2,         Integrator::ImplicitMidpoint, Integrator::EnergyBlend};
}

Integrator parseIntegrator(const std::string& name) {
  for (Integrator i : allIntegrators())
    if (lower(name) == lower(integratorName(i))) return i;
  throw InvalidInputError("unknown integrator '" + name + "' (expected FE, SE, BE, BDF2, IM or blend)");
}

const char* backendName(BackendKind kind) {
  switch (kind) {
    case BackendKind::OpenCL: return "opencl";
    case BackendKind::Auto: return "auto";
    default: return "cpu";
  }
}

BackendKind parseBackend(const std::string& name) {
  if (lower(name) == "cpu") return BackendKind::CpuReference;
  if (lower(name) == "opencl") return BackendKind::OpenCL;
  if (lower(name) == "auto") return BackendKind::Auto;
  throw InvalidInputError("unknown backend '" + name + "' (expected cpu, opencl or auto)");
}

const char* blendBranchName(BlendBranch branch) {
  switch (branch) {
    case BlendBranch::None: return "-";
    case BlendBranch::ImplicitMidpoint: return "IM";
    case BlendBranch::BackwardEuler: return "BE";
    case BlendBranch::VelocityScale: return "scale";
  }
  return "?";
}

const char* accelerationName(Acceleration acceleration) {
  switch (acceleration) {
    case Acceleration::None: return "none";
    case Acceleration::Chebyshev: return "chebyshev";
    case Acceleration::Anderson: return "anderson";
    case Acceleration::LBFGS: return "lbfgs";
    case Acceleration::Newton: return "newton";
  }
  return "?";
}

Acceleration parseAcceleration(const std::string& name) {
  for (Acceleration a :
       {Acceleration::None, Acceleration::Chebyshev, Acceleration::Anderson, Acceleration::LBFGS, Acceleration::Newton})
    if (lower(name) == accelerationName(a)) return a;
  throw InvalidInputError("unknown acceleration '" + name + "' (expected none, chebyshev, anderson, lbfgs or newton)");
}

const char* globalSolveName(GlobalSolve solve) {
  switch (solve) {
    case GlobalSolve::Factor: return "factor";
    case GlobalSolve::ConjugateGradient: return "cg";
  }
  return "?";
}

GlobalSolve parseGlobalSolve(const std::string& name) {
  for (GlobalSolve g : {GlobalSolve::Factor, GlobalSolve::ConjugateGradient})
    if (lower(name) == globalSolveName(g)) return g;
  throw InvalidInputError("unknown global solve '" + name + "' (expected factor or cg)");
}

PhaseTimes& PhaseTimes::operator+=(const PhaseTimes& o) {
  local += o.local;
  gather += o.gather;
  transfer += o.transfer;
  global += o.global;
  energy += o.energy;
  bookkeeping += o.bookkeeping;
  return *this;
}

std::vector<ElementKind> allElementKinds() {
  std::vector<ElementKind> kinds;
  for (int k = 0; k < kElementKindCount; ++k) kinds.push_back(static_cast<ElementKind>(k));
  return kinds;
}

ElementKind parseElementKind(const std::string& name) {
  for (ElementKind k : allElementKinds()) {
    const std::string singular = elementKindName(k);
    if (lower(name) == singular || lower(name) == singular + "s") return k;
  }
  std::string names;
  for (ElementKind k : allElementKinds())
    names += std::string(names.empty()                             ? ""
                         : k == ElementKind(kElementKindCount - 1) ? " or "
                                                                   : ", ") +
             elementKindName(k);
  throw InvalidInputError("unknown element kind '" + name + "' (expected " + names + ", or their plurals)");
}

}  // namespace stabint
