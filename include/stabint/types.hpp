#pragma once
/// @file
/// The library's shared value types: the enums of integrators, backends, precisions, solvers
/// and element kinds (with their names, parsers and counts), the options, and what a step
/// reports. A leaf header: the solver and the backends include it, never the stepping facade
/// stabint/simulator.hpp (docs/development.md, "Layering").
#include <stabint/enum_list.hpp>
#include <stabint/errors.hpp>
#include <stabint/options_table.h>
#include <stabint/scene.hpp>

#include <string>
#include <vector>

namespace stabint {

// The enums below come from their lists (stabint/enum_list.hpp), `X(Enumerator, "name", "doc",
// C enumerator)`: the last is the value's name in the C API (stabint/stabint_c.h), which the
// library's build checks against the C++ value; ElementKind's list has only the first two fields.

/// The integrators of docs/method.md sections 2 and 3, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_INTEGRATORS(X)                                                           \
  X(ForwardEuler, "FE", "forward Euler, for comparison", STABINT_FORWARD_EULER)          \
  X(SymplecticEuler, "SE", "symplectic Euler, for comparison", STABINT_SYMPLECTIC_EULER) \
  X(BackwardEuler, "BE", "backward Euler", STABINT_BACKWARD_EULER)                       \
  X(BDF2, "BDF2", "second-order backward differences (first step BE)", STABINT_BDF2)     \
  X(ImplicitMidpoint, "IM", "implicit midpoint", STABINT_IMPLICIT_MIDPOINT)              \
  X(EnergyBlend, "blend", "the paper's energy-tracking blend of IM with BE or FE", STABINT_ENERGY_BLEND)

/// The six integrators of docs/method.md sections 2 and 3; what each is: STABINT_INTEGRATORS.
enum class Integrator { STABINT_INTEGRATORS(STABINT_ENUMERATOR_) };
/// Number of Integrator values (they run from 0): the C API's and bindings' range check.
constexpr int kIntegratorCount = 0 STABINT_INTEGRATORS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_INTEGRATORS ("FE", "blend", ...); "?" for a value outside the enum.
constexpr const char* integratorName(Integrator integrator) {
  return enumName_(integrator, {STABINT_INTEGRATORS(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by integratorName (case-insensitive); throws InvalidInputError.
Integrator parseIntegrator(const std::string& name);
/// Every integrator, in the enum's order.
std::vector<Integrator> allIntegrators();

/// The backends, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_BACKENDS(X)                                                                                  \
  X(CpuReference, "cpu", "plain C++ in double on the host: the oracle the OpenCL backend is tested against", \
    STABINT_BACKEND_CPU)                                                                                     \
  X(OpenCL, "opencl", "OpenCL kernels on the device of SimulatorOptions::opencl", STABINT_BACKEND_OPENCL)    \
  X(Auto, "auto", "an OpenCL GPU where an iteration of the scene costs less there, else the CPU reference",  \
    STABINT_BACKEND_AUTO)

/// Where the local step and the energies run (what each value is: STABINT_BACKENDS). Auto: an
/// OpenCL GPU when there is one and an iteration of the scene is estimated to cost less there
/// (costs per device class, measured on an H200), else the CPU reference (an OpenCL CPU device such as PoCL is not
/// faster than it; take one with OpenCL); backendDescription() says which and why (docs/method.md, "Backend choice").
enum class BackendKind { STABINT_BACKENDS(STABINT_ENUMERATOR_) };
/// Number of BackendKind values (they run from 0).
constexpr int kBackendKindCount = 0 STABINT_BACKENDS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_BACKENDS ("cpu", "opencl", ...); "?" for a value outside the enum.
constexpr const char* backendName(BackendKind kind) { return enumName_(kind, {STABINT_BACKENDS(STABINT_ENUM_NAME_)}); }
/// Parses a name as printed by backendName (case-insensitive); throws InvalidInputError.
BackendKind parseBackend(const std::string& name);

/// The precisions, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_PRECISIONS(X)                                                                         \
  X(Double, "double", "needs cl_khr_fp64 (else UnsupportedPrecisionError)", STABINT_PRECISION_DOUBLE) \
  X(Float, "float", "any device", STABINT_PRECISION_FLOAT)

/// Floating-point precision of the OpenCL backend's element data and kernels (the global solve
/// is always double on the host); what each value needs: STABINT_PRECISIONS.
enum class Precision { STABINT_PRECISIONS(STABINT_ENUMERATOR_) };
/// Number of Precision values (they run from 0).
constexpr int kPrecisionCount = 0 STABINT_PRECISIONS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_PRECISIONS ("double", ...); "?" for a value outside the enum.
constexpr const char* precisionName(Precision precision) {
  return enumName_(precision, {STABINT_PRECISIONS(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by precisionName (case-insensitive); throws InvalidInputError.
Precision parsePrecision(const std::string& name);

/// The accelerations, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_ACCELERATIONS(X)                                                                         \
  X(None, "none", "plain local/global iterations", STABINT_ACCELERATION_NONE)                            \
  X(Chebyshev, "chebyshev", "Chebyshev semi-iteration (Wang 2015)", STABINT_ACCELERATION_CHEBYSHEV)      \
  X(Anderson, "anderson", "Anderson acceleration (Peng et al. 2018)", STABINT_ACCELERATION_ANDERSON)     \
  X(LBFGS, "lbfgs", "L-BFGS with the prefactored K_c as initial Hessian (Liu et al. 2017), line search", \
    STABINT_ACCELERATION_LBFGS)                                                                          \
  X(Newton, "newton", "Newton-CG: springs' projected Hessians, CG preconditioned with K_c, line search", \
    STABINT_ACCELERATION_NEWTON)

/// Acceleration of the local/global iterations (what each value is: STABINT_ACCELERATIONS).
/// Every variant keeps the objective monotone: an accelerated iterate that would raise it is
/// replaced by the plain one.
enum class Acceleration { STABINT_ACCELERATIONS(STABINT_ENUMERATOR_) };
/// Number of Acceleration values (they run from 0).
constexpr int kAccelerationCount = 0 STABINT_ACCELERATIONS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_ACCELERATIONS ("none", "lbfgs", ...); "?" for a value outside the
/// enum.
constexpr const char* accelerationName(Acceleration acceleration) {
  return enumName_(acceleration, {STABINT_ACCELERATIONS(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by accelerationName (case-insensitive); throws InvalidInputError.
Acceleration parseAcceleration(const std::string& name);

/// The global solves, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_GLOBAL_SOLVES(X)                                                                             \
  X(Factor, "factor", "the CHOLMOD factor of K_c on the host: exact (default)", STABINT_GLOBAL_SOLVE_FACTOR) \
  X(ConjugateGradient, "cg",                                                                                 \
    "Jacobi-preconditioned CG warm-started from the current iterate, run by the backend: on the OpenCL "     \
    "device with nothing read back per iteration, on the host in double for the CPU reference",              \
    STABINT_GLOBAL_SOLVE_CONJUGATE_GRADIENT)

/// How the global step of every local/global iteration solves K_c x = rhs (docs/method.md,
/// "Global solve"; what each value is: STABINT_GLOBAL_SOLVES).
enum class GlobalSolve { STABINT_GLOBAL_SOLVES(STABINT_ENUMERATOR_) };
/// Number of GlobalSolve values (they run from 0).
constexpr int kGlobalSolveCount = 0 STABINT_GLOBAL_SOLVES(STABINT_ENUM_ONE_);
/// The value's name in STABINT_GLOBAL_SOLVES ("factor", "cg", ...); "?" for a value outside the
/// enum.
constexpr const char* globalSolveName(GlobalSolve solve) {
  return enumName_(solve, {STABINT_GLOBAL_SOLVES(STABINT_ENUM_NAME_)});
}
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
enum class ElementKind { STABINT_ELEMENT_KINDS(STABINT_ENUMERATOR_) };
/// Number of ElementKind values (they run from 0; pins are last).
constexpr int kElementKindCount = 0 STABINT_ELEMENT_KINDS(STABINT_ENUM_ONE_);
/// The value's name in STABINT_ELEMENT_KINDS ("spring", "tet", ...: the JSON names, singular);
/// "?" for a value outside the enum.
constexpr const char* elementKindName(ElementKind kind) {
  return enumName_(kind, {STABINT_ELEMENT_KINDS(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by elementKindName, or the scene file's list name, its plural
/// ("springs", "tets", ...); case-insensitive; throws InvalidInputError.
ElementKind parseElementKind(const std::string& name);
/// Every element kind, in the enum's order.
std::vector<ElementKind> allElementKinds();

/// @cond
// The members of the options structs, from their rows (stabint/options_table.h).
#define STABINT_OPTION_MEMBER_(type, name, default_value, rule, doc) type name = default_value;
#define STABINT_OPTION_SUB_MEMBER_(parent, type, name, default_value, rule, doc) type name = default_value;
#define STABINT_OPTION_NESTED_MEMBER_(type, name, fields, doc) type name;
/// @endcond

/// Which OpenCL device to use, and the precision: the rows of STABINT_OPENCL_OPTIONS_TABLE
/// (stabint/options_table.h), each a member with its type and default. Empty selectors fall back
/// to the environment variables STABINT_OPENCL_PLATFORM and STABINT_OPENCL_DEVICE, then to the
/// first platform and device.
struct OpenCLOptions {
  STABINT_OPENCL_OPTIONS_FIELDS(STABINT_OPTION_SUB_MEMBER_, opencl)
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

/// The fields of OpenCLDeviceInfo, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_OPENCL_DEVICE_INFO_FIELDS(FIELD)                             \
  FIELD(platform_index, "index for OpenCLOptions.platform")                  \
  FIELD(device_index, "index within the platform, for OpenCLOptions.device") \
  FIELD(platform_name, "CL_PLATFORM_NAME")                                   \
  FIELD(device_name, "CL_DEVICE_NAME")                                       \
  FIELD(vendor, "CL_DEVICE_VENDOR")                                          \
  FIELD(fp64, "has cl_khr_fp64 (Precision.Double works)")                    \
  FIELD(gpu, "CL_DEVICE_TYPE_GPU")
/// @cond
STABINT_FIELD_TABLE_(OpenCLDeviceInfo, STABINT_OPENCL_DEVICE_INFO_FIELDS,
                     "One available OpenCL device, as listed by list_opencl_devices().")
/// @endcond

/// All devices of all platforms; empty when no OpenCL platform is installed (never throws for
/// a missing platform).
std::vector<OpenCLDeviceInfo> listOpenCLDevices();

/// How a Simulator (or BatchSimulator) steps: the integrator, the step, the solver and its
/// budget, the blend's parameters and the backend. Its members are the rows of
/// STABINT_SIMULATOR_OPTIONS_TABLE (stabint/options_table.h), each with its type, default, allowed
/// values and what it does; checked when a simulator is built.
struct SimulatorOptions {
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_OPTION_MEMBER_, STABINT_OPTION_NESTED_MEMBER_)
};

/// @cond
// The field tables of the options (stabint/field_list.hpp), from the same rows as their members,
// for the bindings (Python's keyword constructors, properties, repr and pickling). A row becomes
// the table's entry `STABINT_FIELD_(name, doc)`; the lists ignore the FIELD they are given, since
// STABINT_FIELD_TABLE_ passes them STABINT_FIELD_ itself.
#define STABINT_OPTION_ENTRY_(type, name, default_value, rule, doc) STABINT_FIELD_(name, doc)
#define STABINT_OPTION_SUB_ENTRY_(parent, type, name, default_value, rule, doc) STABINT_FIELD_(name, doc)
#define STABINT_OPTION_NESTED_ENTRY_(type, name, fields, doc) STABINT_FIELD_(name, doc)
#define STABINT_OPENCL_OPTIONS_ENTRIES_(FIELD) STABINT_OPENCL_OPTIONS_FIELDS(STABINT_OPTION_SUB_ENTRY_, opencl)
#define STABINT_SIMULATOR_OPTIONS_ENTRIES_(FIELD) \
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_OPTION_ENTRY_, STABINT_OPTION_NESTED_ENTRY_)
STABINT_FIELD_TABLE_(OpenCLOptions, STABINT_OPENCL_OPTIONS_ENTRIES_,
                     "OpenCL device choice: index or name substring; empty: STABINT_OPENCL_PLATFORM / "
                     "STABINT_OPENCL_DEVICE, then the first.")
STABINT_FIELD_TABLE_(SimulatorOptions, STABINT_SIMULATOR_OPTIONS_ENTRIES_,
                     "Options of a Simulator; every field is a row of stabint/options_table.h.")
/// @endcond

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

/// The fields of EnergyReport, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_ENERGY_REPORT_FIELDS(FIELD)                               \
  FIELD(kinetic, "K(v), J")                                               \
  FIELD(elastic, "springs, tets, triangles, hinges, pins and contact, J") \
  FIELD(external, "gravity and force fields, J")
/// @cond
STABINT_FIELD_TABLE_(EnergyReport, STABINT_ENERGY_REPORT_FIELDS, "Energies of a state, in joules.")
/// @endcond

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

/// The fields of PhaseTimes, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_PHASE_TIMES_FIELDS(FIELD)      \
  FIELD(local, "s, element projections")       \
  FIELD(gather, "s, right-hand-side assembly") \
  FIELD(transfer, "s, host<->device copies")   \
  FIELD(global, "s, sparse solves")            \
  FIELD(energy, "s, energy reductions")        \
  FIELD(bookkeeping, "s, the rest of the step")
/// @cond
STABINT_FIELD_TABLE_(PhaseTimes, STABINT_PHASE_TIMES_FIELDS, "Wall-clock seconds per phase of a step.")
/// @endcond

/// The blend's branches, `X(Enumerator, "name", "doc", C enumerator)`.
#define STABINT_BLEND_BRANCHES(X)                                                                        \
  X(None, "-", "not the blend", STABINT_BRANCH_NONE)                                                     \
  X(ImplicitMidpoint, "IM", "the IM candidate accepted", STABINT_BRANCH_IMPLICIT_MIDPOINT)               \
  X(BackwardEuler, "BE", "blended with the BE partner (too much energy)", STABINT_BRANCH_BACKWARD_EULER) \
  X(VelocityScale, "scale", "velocities scaled up (too little energy)", STABINT_BRANCH_VELOCITY_SCALE)

/// What the blend did with the implicit-midpoint candidate (None for the other integrators):
/// accepted it, blended it with a backward-Euler partner (too much energy), or scaled its
/// velocities (too little energy); from STABINT_BLEND_BRANCHES.
enum class BlendBranch { STABINT_BLEND_BRANCHES(STABINT_ENUMERATOR_) };
/// Number of BlendBranch values (they run from 0).
constexpr int kBlendBranchCount = 0 STABINT_BLEND_BRANCHES(STABINT_ENUM_ONE_);
/// The value's name in STABINT_BLEND_BRANCHES ("-", "IM", ...); "?" for a value outside the enum.
constexpr const char* blendBranchName(BlendBranch branch) {
  return enumName_(branch, {STABINT_BLEND_BRANCHES(STABINT_ENUM_NAME_)});
}
/// Parses a name as printed by blendBranchName (case-insensitive); throws InvalidInputError.
BlendBranch parseBlendBranch(const std::string& name);

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
  /// energy the contact booked as lost (<= 0, added to H*): of what the final projection out of
  /// the colliders removed, the share their restitution does not keep, and what the step's
  /// half-spaces took from the potential of the same positions (energy the projection adds is
  /// not booked: the blend takes it out), and what self-contact's correction removed (its
  /// impulses' kinetic energy less the potential its moves added).
  ///@{
  double friction = 0.0;
  double contact_projection = 0.0;
  ///@}
  int iterations = 0;          ///< local/global iterations of all solves in this step
  int energy_evaluations = 0;  ///< element energy passes (root find included)
  PhaseTimes times;            ///< wall-clock seconds per phase
};

/// The fields of StepReport, `FIELD(name, "doc")` in the struct's order (stabint/field_list.hpp).
#define STABINT_STEP_REPORT_FIELDS(FIELD)                                                                     \
  FIELD(step, "index of the step (0 = first)")                                                                \
  FIELD(time, "time at the end of the step")                                                                  \
  FIELD(energy, "H of the new state, split by term")                                                          \
  FIELD(target, "tracked target H* after the step")                                                           \
  FIELD(forcing, "energy added to H* by time-dependent potentials")                                           \
  FIELD(damping, "kinetic energy removed by damping (>= 0)")                                                  \
  FIELD(branch, "what the blend did")                                                                         \
  FIELD(alpha, "blend weight of the BE partner (0 = pure IM)")                                                \
  FIELD(velocity_scale, "factor the blend applied to the velocities (1 = none)")                              \
  FIELD(event_energy, "energy added to H* by set_state/set_positions/set_velocities since the previous step") \
  FIELD(friction, "kinetic energy friction removed (negative when a moving collider drags particles along)")  \
  FIELD(contact_projection,                                                                                   \
        "energy the contact booked as lost: the final projection's beyond restitution, the half-spaces', "    \
        "self-contact's (<= 0)")                                                                              \
  FIELD(iterations, "local/global iterations of all solves of the step")                                      \
  FIELD(energy_evaluations, "element energy passes (root find included)")                                     \
  FIELD(times, "wall-clock seconds per phase")
/// @cond
STABINT_FIELD_TABLE_(StepReport, STABINT_STEP_REPORT_FIELDS,
                     "What one step did (a copy: later steps do not change it).")
/// @endcond

}  // namespace stabint
