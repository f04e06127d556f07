#pragma once
/// @file
/// The library's shared value types: the enums of integrators, backends, precisions, solvers
/// and element kinds (with their names, parsers and counts), the options, and what a step
/// reports. A leaf header: the solver and the backends include it, never the stepping facade
/// stabint/simulator.hpp (docs/development.md, "Layering").
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>

#include <string>
#include <vector>

namespace stabint {

/// The six integrators of docs/method.md sections 2 and 3.
enum class Integrator {
  ForwardEuler,      ///< FE, for comparison
  SymplecticEuler,   ///< SE, for comparison
  BackwardEuler,     ///< BE
  BDF2,              ///< second-order backward differences (first step BE)
  ImplicitMidpoint,  ///< IM
  EnergyBlend,       ///< the paper's energy-tracking blend of IM with BE or FE
};
/// Number of Integrator values (they run from 0): the C API's and bindings' range check. Raise it
/// with a new value.
constexpr int kIntegratorCount = 6;
const char* integratorName(Integrator integrator);  ///< "FE", "SE", "BE", "BDF2", "IM", "blend"
/// Parses a name as printed by integratorName (case-insensitive); throws InvalidInputError.
Integrator parseIntegrator(const std::string& name);
/// Every integrator, in the enum's order.
std::vector<Integrator> allIntegrators();

/// Where the local step and the energies run. Auto: an OpenCL GPU when there is one and the scene
/// is large enough for it (a threshold per device class), else the CPU reference (an OpenCL CPU
/// device such as PoCL is not faster than it; take one with OpenCL); backendDescription() says
/// which and why (docs/method.md, "Backend choice").
enum class BackendKind {
  CpuReference,  ///< plain C++ in double on the host: the oracle the OpenCL backend is tested against
  OpenCL,        ///< OpenCL kernels on the device of SimulatorOptions::opencl
  Auto           ///< an OpenCL GPU for a scene large enough for it, else the CPU reference
};
/// Number of BackendKind values (they run from 0).
constexpr int kBackendKindCount = 3;
const char* backendName(BackendKind kind);  ///< "cpu", "opencl", "auto"
/// Parses a name as printed by backendName (case-insensitive); throws InvalidInputError.
BackendKind parseBackend(const std::string& name);

/// Floating-point precision of the OpenCL backend's element data and kernels (the global solve
/// is always double on the host).
enum class Precision {
  Double,  ///< needs cl_khr_fp64 (else UnsupportedPrecisionError)
  Float    ///< any device
};
/// Number of Precision values (they run from 0).
constexpr int kPrecisionCount = 2;

/// Acceleration of the local/global iterations. Every variant keeps the objective monotone: an
/// accelerated iterate that would raise it is replaced by the plain one.
enum class Acceleration {
  None,       ///< plain local/global iterations
  Chebyshev,  ///< Chebyshev semi-iteration (Wang 2015)
  Anderson,   ///< Anderson acceleration (Peng et al. 2018)
  LBFGS,      ///< L-BFGS with the prefactored K_c as initial Hessian (Liu et al. 2017), line search
  Newton,     ///< Newton-CG: springs' projected Hessians, CG preconditioned with K_c, line search
};
/// Number of Acceleration values (they run from 0).
constexpr int kAccelerationCount = 5;
const char* accelerationName(Acceleration acceleration);  ///< "none", "chebyshev", "anderson", "lbfgs", "newton"
/// Parses a name as printed by accelerationName (case-insensitive); throws InvalidInputError.
Acceleration parseAcceleration(const std::string& name);

/// How the global step of every local/global iteration solves K_c x = rhs (docs/method.md,
/// "Global solve").
enum class GlobalSolve {
  Factor,             ///< the CHOLMOD factor of K_c on the host: exact (default)
  ConjugateGradient,  ///< Jacobi-preconditioned CG warm-started from the current iterate, run by
                      ///< the backend: on the OpenCL device with nothing read back per iteration,
                      ///< on the host in double for the CPU reference
};
/// Number of GlobalSolve values (they run from 0).
constexpr int kGlobalSolveCount = 2;
const char* globalSolveName(GlobalSolve solve);  ///< "factor", "cg"
/// Parses a name as printed by globalSolveName (case-insensitive); throws InvalidInputError.
GlobalSolve parseGlobalSolve(const std::string& name);

/// The element types a user reaches by ElementKind, one line each, `KIND(Enumerator, name)`: the
/// enumerator, and the type's name in JSON and messages, whose plural is its Scene list
/// (Scene::springs). The enum, the names and the library's table of element types (its order,
/// that of the contribution numbering) come from this list; pins stay last (grab and release
/// rebuild only the last block). Adding an element type users can reach is one line here beside
/// its own files (docs/elements.md, "How to add an element type").
#define STABINT_ELEMENT_KINDS(KIND)       \
  KIND(Spring, "spring")                  \
  KIND(Tet, "tet")                        \
  KIND(TriangleStrain, "triangle_strain") \
  KIND(BendingHinge, "bending_hinge")     \
  KIND(Pin, "pin")

/// The element types of a Scene, one per element list (Spring: Scene::springs, Tet: tets,
/// TriangleStrain: triangle_strains, BendingHinge: bending_hinges, Pin: pins, grabbed handles
/// included), for the run-time element changes (Simulator::setElementStiffness,
/// setElementEnabled). From STABINT_ELEMENT_KINDS.
enum class ElementKind {
/// @cond
#define STABINT_ELEMENT_KIND_ENUMERATOR(kind, name) kind,
  /// @endcond
  STABINT_ELEMENT_KINDS(STABINT_ELEMENT_KIND_ENUMERATOR)
#undef STABINT_ELEMENT_KIND_ENUMERATOR
};
/// Number of ElementKind values (they run from 0; pins are last).
constexpr int kElementKindCount = static_cast<int>(ElementKind::Pin) + 1;
/// "spring", "tet", "triangle_strain", "bending_hinge", "pin" (the JSON names, singular); "?"
/// for a value outside the enum.
constexpr const char* elementKindName(ElementKind kind) {
  switch (kind) {
    /// @cond
#define STABINT_ELEMENT_KIND_CASE(kind, name) \
  case ElementKind::kind: return name;
    STABINT_ELEMENT_KINDS(STABINT_ELEMENT_KIND_CASE)
#undef STABINT_ELEMENT_KIND_CASE
    /// @endcond
  }
  return "?";
}
/// Parses a name as printed by elementKindName, or the scene file's list name ("springs",
/// "tets", "triangle_strains", "bending_hinges", "pins"); throws InvalidInputError.
ElementKind parseElementKind(const std::string& name);
/// Every element kind, in the enum's order.
std::vector<ElementKind> allElementKinds();

/// Which OpenCL device to use. Empty strings fall back to the environment variables
/// STABINT_OPENCL_PLATFORM and STABINT_OPENCL_DEVICE, then to the first platform and device.
/// Each selector is either an index ("0") or a case-insensitive substring of the name.
struct OpenCLOptions {
  std::string platform;                     ///< platform selector; empty: environment, then the first
  std::string device;                       ///< device selector; empty: environment, then the first
  Precision precision = Precision::Double;  ///< of the kernels and the device's data
};

/// One available OpenCL device, as listed by listOpenCLDevices().
struct OpenCLDeviceInfo {
  int platform_index = 0;     ///< index for OpenCLOptions::platform
  int device_index = 0;       ///< index within the platform, for OpenCLOptions::device
  std::string platform_name;  ///< CL_PLATFORM_NAME
  std::string device_name;    ///< CL_DEVICE_NAME
  std::string vendor;         ///< CL_DEVICE_VENDOR (with the name, picks the device's launch sizes)
  bool fp64 = false;          ///< has cl_khr_fp64 (Precision::Double works)
  bool gpu = false;           ///< CL_DEVICE_TYPE_GPU
};
/// All devices of all platforms; empty when no OpenCL platform is installed (never throws for
/// a missing platform).
std::vector<OpenCLDeviceInfo> listOpenCLDevices();

/// How a Simulator (or BatchSimulator) steps: the integrator, the step, the solver and its
/// budget, the blend's parameters and the backend. Checked when a simulator is built.
struct SimulatorOptions {
  Integrator integrator = Integrator::EnergyBlend;  ///< the blend by default
  double time_step = 1.0 / 30.0;                    ///< h > 0

  /// Local/global iterations per implicit solve (the real-time budget). When `tolerance` > 0 the
  /// solve instead runs until the relative change of the objective is below it (reference
  /// runs), at most `max_iterations`.
  ///@{
  int iterations = 10;
  double tolerance = 0.0;
  int max_iterations = 1000;
  ///@}
  /// The solver of every local/global solve (default L-BFGS, the most accurate at its cost on
  /// every scene measured: docs/method.md, "Which solver is the default"; None is plain
  /// iterations); the spectral-radius estimate of the plain iteration that the Chebyshev
  /// recurrence uses (in (0, 1)); the number of past iterates Anderson acceleration combines
  /// (>= 1); the curvature pairs L-BFGS keeps (in [1, 50]).
  ///@{
  Acceleration acceleration = Acceleration::LBFGS;
  double chebyshev_rho = 0.98;
  int anderson_window = 5;
  int lbfgs_history = 5;
  ///@}
  /// L-BFGS's stopping rule by accuracy (Acceleration::LBFGS only; 0: off): a solve stops once the
  /// gradient of its objective, in the norm of L-BFGS's inverse Hessian (sqrt(g.H g), the Newton
  /// decrement), has fallen to gradient_tolerance times its value at the warm start; `iterations`
  /// stays the cap (docs/method.md, "L-BFGS"). In [0, 1).
  double gradient_tolerance = 0.0;

  /// The global step's solver. With ConjugateGradient every global step runs `cg_iterations`
  /// CG iterations (>= 1; a fixed count: the OpenCL device reads nothing back), or, when
  /// `cg_tolerance` > 0, stops earlier once ||rhs - K_c x|| <= cg_tolerance ||rhs|| in every
  /// column (the device then reads back the residual after every CG iteration).
  ///@{
  GlobalSolve global_solve = GlobalSolve::Factor;
  int cg_iterations = 20;
  double cg_tolerance = 0.0;
  ///@}

  /// Energy-tracking blend (docs/method.md, "The blend").
  int be_iterations = 3;           ///< budget of the BE partner solve, warm-started at x_n
  double energy_tolerance = 1e-3;  ///< tau = energy_tolerance * (K + E_int + E_scale)
  /// Largest factor by which one step may scale the velocities up to restore missing energy:
  /// energy comes back over a few steps, never as a kinetic jump of a nearly resting body.
  double max_velocity_scale = 2.0;
  int max_root_evaluations = 12;  ///< energy evaluations of the root find

  /// Energy ceiling, off when 0: a step whose energy H exceeds the tracked target H* by more than
  /// energy_limit * E_scale (energyScale()) is refused with EnergyLimitError, keeping the last
  /// accepted state, so that an explicit or midpoint run that gains energy stops long before it
  /// overflows. Energy lost (damping, BE) is never refused.
  double energy_limit = 0.0;

  /// Contact (docs/method.md, "Contact"): after every step, no particle stays deeper than this
  /// inside a collider (m, >= 0); the final projection that moves it out is booked in H*. It also
  /// sets the contact set's margin, contact_tolerance + time_step^2 |gravity|: a particle that is
  /// (or, at its velocity, will be) that close to a collider carries its contact term.
  double contact_tolerance = 1e-2;

  BackendKind backend = BackendKind::CpuReference;  ///< where the element work runs
  OpenCLOptions opencl;                             ///< device and precision (backend OpenCL or Auto)
};

/// Energies of a state (docs/method.md section 1). `elastic` includes every element's energy
/// (springs, tets, triangle strain, hinges, pins and contact);
/// `external` is gravity plus force fields, -sum (m g + f(t)).x.
struct EnergyReport {
  double kinetic = 0.0;   ///< K(v), J
  double elastic = 0.0;   ///< E_int(x), J
  double external = 0.0;  ///< U_ext(x, t), J
  /// H = K + E_int + U_ext.
  double total() const { return kinetic + elastic + external; }
};

/// Wall-clock seconds per phase. `local` is the per-element projection, `gather` the per-vertex
/// right-hand-side assembly, `transfer` host<->device copies, `global` the sparse solves,
/// `energy` energy reductions, `bookkeeping` everything else of the step.
struct PhaseTimes {
  double local = 0.0;        ///< s, element projections
  double gather = 0.0;       ///< s, right-hand-side assembly
  double transfer = 0.0;     ///< s, host<->device copies
  double global = 0.0;       ///< s, sparse solves
  double energy = 0.0;       ///< s, energy reductions
  double bookkeeping = 0.0;  ///< s, the rest of the step
  /// The sum of the phases.
  double total() const { return local + gather + transfer + global + energy + bookkeeping; }
  /// Adds another report's times, phase by phase.
  PhaseTimes& operator+=(const PhaseTimes& o);
};

/// What the blend did with the implicit-midpoint candidate (None for the other integrators):
/// accepted it, blended it with a backward-Euler partner (too much energy), or scaled its
/// velocities (too little energy).
enum class BlendBranch {
  None,              ///< not the blend
  ImplicitMidpoint,  ///< the IM candidate accepted
  BackwardEuler,     ///< blended with the BE partner (too much energy)
  VelocityScale      ///< velocities scaled up (too little energy)
};
const char* blendBranchName(BlendBranch branch);  ///< "-", "IM", "BE", "scale"

/// What one step did: its energies, the energy book of H*, the blend's decision, the work done
/// and the time per phase (Simulator::step, Simulator::lastReport).
struct StepReport {
  int step = 0;                            ///< index of this step (0 = first)
  double time = 0.0;                       ///< time at the end of the step
  EnergyReport energy;                     ///< H(x_{n+1}, v_{n+1}, t_{n+1}) split by term
  double target = 0.0;                     ///< tracked target H* after the step (all integrators track it)
  double forcing = 0.0;                    ///< energy added to H* by time-dependent potentials this step
  double damping = 0.0;                    ///< kinetic energy removed by damping this step (>= 0)
  BlendBranch branch = BlendBranch::None;  ///< what the blend did
  double alpha = 0.0;                      ///< blend weight of the BE partner (0 = pure IM)
  double velocity_scale = 1.0;             ///< factor the blend applied to the velocities (1 = none)
  /// Energy added to H* by discontinuous input since the previous step (setState, setPositions,
  /// setVelocities): the jump of H it caused, booked as the user's work (docs/method.md).
  double event_energy = 0.0;
  /// Contact (docs/method.md, "Contact"): kinetic energy removed by friction this step (taken
  /// from H* like damping; negative when a moving collider drags particles along), and the
  /// energy the final projection out of the colliders removed (<= 0, added to H*; energy it adds
  /// is not booked: the blend takes it out).
  ///@{
  double friction = 0.0;
  double contact_projection = 0.0;
  ///@}
  int iterations = 0;          ///< local/global iterations of all solves in this step
  int energy_evaluations = 0;  ///< element energy passes (root find included)
  PhaseTimes times;            ///< wall-clock seconds per phase
};

}  // namespace stabint
