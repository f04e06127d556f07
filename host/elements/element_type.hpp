#pragma once
// The generic element pipeline (docs/elements.md). Every element has the Projective-Dynamics
// form E_e = w_e/2 ||A_e x - p_e||^2 with p_e the projection of A_e x onto the element's rest
// set. An element type supplies only what is specific to it, in one file host/elements/<type>.cpp:
//   - its vertex tuple (K vertices) and the rows R of A_e (A_e x is R by 3),
//   - the coefficients of A_e (R by K, shared by the type or one set per element), its weight w_e
//     and the rest data its projection reads (P reals per element, the first of which is w_e),
//   - validation of its rest state, and
//   - the projection with the element's energy: a C++ function here and an OpenCL function in
//     kernels/<type>.cl.
// Everything else is generic over the table of types (elementTypes()): the contribution CSR,
// L = sum w_e A_e^T A_e, the right-hand-side gather, the energy reductions and the kernels.
#include "common/kernel_constants.hpp"  // PassFlags: what an element pass computes

#include <stabint/scene.hpp>
#include <stabint/types.hpp>

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace stabint {

class ElementType;

/// What an element type reads of a running simulation, beyond its scene: which elements are
/// enabled and where the forcing has moved pins and colliders at a time. SceneView implements
/// it over a SceneData and its Forcing; the element types see only this, so that they sit below the scene layer (docs/
/// development.md, "Layering").
class RunningScene {
 public:
  virtual const Scene& scene() const = 0;
  /// Index of `type`'s block (the order of elementTypes()).
  virtual int blockIndex(const ElementType& type) const = 0;
  virtual bool elementEnabled(int block, int element) const = 0;
  /// w_e as the global matrix has it now (0 for a disabled element).
  virtual double elementWeight(int block, int element) const = 0;
  /// Block `block`'s params as they are now (ElementBlock::params).
  virtual const std::vector<double>& blockParams(int block) const = 0;
  /// Pin targets move (by the scene's law or the user's ramps); then pinTarget gives them.
  virtual bool hasMovingPins() const = 0;
  virtual Eigen::Vector3d pinTarget(int pin, double t) const = 0;
  /// Colliders move (by their scene velocity or at run time); then colliderPosition gives them.
  virtual bool hasMovingColliders() const = 0;
  virtual Eigen::Vector3d colliderPosition(int collider, double t) const = 0;

 protected:
  ~RunningScene() = default;
};

/// Which term of the potential an element's energy belongs to: the blend books pins apart
/// because their targets may move.
enum class EnergyTerm { Internal, Pins };

/// All elements of one type in a scene, in the flat form every backend consumes. Element e has
/// vertices[K e + k] (k < K), the R by K row-major coefficients of A_e at
/// coefficients[R K e] (or at 0 when the type shares one A_e), and params[P e + i] (i < P) with
/// params[P e] = w_e. Its contributions w_e (A_e^T p_e) to vertex k are numbered
/// contribution_base + K e + k in the CSR.
struct ElementBlock {
  const ElementType* type = nullptr;
  int count = 0;
  std::vector<int> vertices;
  std::vector<double> coefficients;
  /// The same vertices and (per-element) coefficients in the CPU reference's lane layout, for
  /// the types that project a group of elements at once (projections::kLanes elements, the
  /// groups aligned at multiples of kLanes): entry i of element kLanes g + l at
  /// [(I g + i) kLanes + l], I = K or R K entries per element, the last group padded with the
  /// block's last element. A group then loads each entry of all its lanes as one vector instead of
  /// gathering it; empty for the other types.
  std::vector<int> lane_vertices;
  std::vector<double> lane_coefficients;
  std::vector<double> params;
  int contribution_base = 0;
  int revision = 0;  // incremented when the block is rebuilt at run time (SceneData::setPins)
  /// Incremented when params change in place at run time (a stiffness change, an element
  /// enabled or disabled: SceneData::setElementStiffness), so device copies are refreshed.
  int params_revision = 0;
  /// The element each of the last in-place changes rewrote, in order: the changes since revision
  /// r are the last params_revision - r entries, where there are that many (SceneData keeps the
  /// latest few hundred); a copy further behind refreshes the whole block. One scene's element
  /// change in a batch then costs a device copy of that scene's elements.
  std::vector<int> changed_params;
};

/// Sizes of a type's data, fixed at compile time for each type.
struct ElementShape {
  int vertices;              // K
  int rows;                  // R
  int params;                // P (weight included)
  bool shared_coefficients;  // one A_e for every element of the type
};

/// One element type. Implementations are ElementTypeOf<Kind> (element_kind.hpp).
class ElementType {
 public:
  virtual ~ElementType() = default;

  /// Name in messages ("triangle strain 3: ..."); `identifier()` prefixes its OpenCL functions
  /// (`<identifier>_project` in kernels/<identifier>.cl) and names its JSON list when it has one.
  virtual const char* name() const = 0;
  virtual const char* identifier() const = 0;
  virtual ElementShape shape() const = 0;
  /// The R by K coefficients (row-major) every element shares when shape().shared_coefficients.
  virtual std::vector<double> sharedCoefficients() const = 0;
  virtual EnergyTerm term() const = 0;
  /// Estimated time of one element in a local step on one core, in nanoseconds (Kind::kElementNs,
  /// measured: bench/bench_thread_pass.cpp): how the CPU reference weighs a pass's work when it
  /// decides whether to split it over threads (host/cpu/threaded_pass.cpp). 0 for a type without.
  virtual double elementCost() const { return 0.0; }

  // ---- the scene side --------------------------------------------------------------------------
  virtual int count(const Scene& scene) const = 0;
  /// Indices in range and distinct, parameters finite and in range, rest state valid. Throws
  /// InvalidInputError naming the element ("<name> <index>: ...").
  virtual void validate(const Scene& scene) const = 0;
  /// The block of a validated scene at t = 0 (contribution_base left to the caller).
  virtual ElementBlock build(const Scene& scene) const = 0;
  /// True when the params depend on time (pins with moving or user-driven targets); then
  /// paramsAt gives them. Both read the forcing of `data`, which a running simulation may change
  /// (Forcing::version()).
  virtual bool timeDependent(const RunningScene& data) const = 0;
  virtual void paramsAt(const RunningScene& data, double t, std::vector<double>& params) const = 0;
  /// Appends the elements of `part` to `into`, with vertex indices shifted by `offset`.
  virtual void appendShifted(Scene& into, const Scene& part, int offset) const = 0;

  // ---- run-time changes (Simulator::setElementStiffness) -----------------------------------------
  // ElementTypeOf implements them for every Kind; a type written by hand without them (one that
  // no ElementKind names) has no stiffness to change, and its elements stay enabled.
  /// False for a type whose elements carry no `stiffness` (the calls then refuse it).
  virtual bool hasStiffness() const { return false; }
  virtual double stiffness(const Scene& /*scene*/, int /*element*/) const { return 0.0; }
  virtual void setStiffness(Scene& /*scene*/, int /*element*/, double /*stiffness*/) const {}
  /// The P params of one element of a validated scene at t = 0, as build() writes them.
  virtual void elementParams(const Scene& /*scene*/, int /*element*/, double* /*params*/) const {}
  /// Weights that depend on the other types' elements of the scene, called once every block of
  /// `blocks` is built: element e of an enabled element then has weight weights[e] (SceneData
  /// keeps them and puts them in params[P e]). Empty (the default): the weights are the type's own.
  virtual std::vector<double> weightsFromBlocks(const Scene& /*scene*/,
                                                const std::vector<ElementBlock>& /*blocks*/) const {
    return {};
  }

  // ---- the math (reference, double) ------------------------------------------------------------
  /// p = projection of `ax` (R by 3, row-major) for an element with these params; returns the
  /// element's energy w/2 ||ax - p||^2.
  virtual double project(const double* ax, const double* params, double* p) const = 0;
  /// One pass over the block at positions x (`n by 3`) with `params` (block.params, or
  /// paramsAt's for a time-dependent type): adds the contributions of `flags` (kPassProjection or
  /// kPassForce) into `out` (`n by 3`, may be null without them) in element order, and returns
  /// the energy summed by EnergySum's rule (elements/energy_sum.hpp) when kPassEnergy is set
  /// (else 0).
  double pass(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x, int flags,
              Eigen::MatrixX3d* out) const {
    return passRange(block, params, x, 0, block.count, flags, out);
  }
  /// pass() over elements [first, first + count) only: the elements of one scene of a batch
  /// (docs/batch_design.md), with the same arithmetic, so a scene's energy is the sum its own
  /// simulator forms.
  virtual double passRange(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x,
                           int first, int count, int flags, Eigen::MatrixX3d* out) const = 0;
  /// passRange's per-element results instead of their sums, for a pass split over threads
  /// (host/cpu/cpu_backend.cpp): element e's energy w/2 ||A x - p||^2 at energies[e - first] when
  /// kPassEnergy is set, and with kPassProjection or kPassForce the 3 reals its vertex k
  /// contributes at contributions[3 (K (e - first) + k)], the very values passRange adds into
  /// `out`. Adding the contributions in element order and summing the energies with sumEnergies
  /// is passRange bit for bit. False (nothing written) for a
  /// type that does not provide it (its blocks take passRange); a call with count 0 asks.
  virtual bool elementResults(const ElementBlock& /*block*/, const std::vector<double>& /*params*/,
                              const Eigen::MatrixX3d& /*x*/, int /*first*/, int /*count*/, int /*flags*/,
                              double* /*energies*/, double* /*contributions*/) const {
    return false;
  }
  /// passRange for one thread of a pass split by vertices (host/cpu/cpu_backend.cpp): elements
  /// [first, first + count) computed as passRange computes them, but only their contributions
  /// to the vertices in [lo, hi) added into `out` (each vertex's in element order), and with
  /// kPassEnergy element e's energy written to energies[e - first] when its first vertex is in
  /// [lo, hi) (else untouched). Threads that own disjoint vertex ranges and each run every
  /// element touching their range thus add into `out` what passRange adds, every vertex in
  /// passRange's order. False (nothing done) for a type that does not provide it; a call with
  /// count 0 asks.
  virtual bool ownedResults(const ElementBlock& /*block*/, const std::vector<double>& /*params*/,
                            const Eigen::MatrixX3d& /*x*/, int /*first*/, int /*count*/, int /*flags*/, int /*lo*/,
                            int /*hi*/, Eigen::MatrixX3d* /*out*/, double* /*energies*/) const {
    return false;
  }

  // ---- the generic JSON form (types that have one) ---------------------------------------------
  /// Names of the numeric fields of an element in its JSON object, besides "vertices"; an empty
  /// list means the type has a hand-written JSON form (springs, tets, pins).
  struct Field {
    const char* key;
    double default_value;  // used when the key is absent
    bool required;
  };
  virtual std::vector<Field> jsonFields() const = 0;
  /// Element i as its vertices and field values (in jsonFields order).
  virtual void record(const Scene& scene, int i, std::vector<int>& vertices, std::vector<double>& values) const = 0;
  virtual void appendRecord(Scene& scene, const std::vector<int>& vertices,
                            const std::vector<double>& values) const = 0;
};

/// Every element type, in the order of the contribution numbering and of the kernels' segments.
const std::vector<const ElementType*>& elementTypes();
/// The type of an element kind users reach (STABINT_ELEMENT_KINDS), defined in the type's file.
template <ElementKind K>
const ElementType& elementTypeOf();
#define STABINT_ELEMENT_TYPE_DECLARATION(kind, name) \
  template <>                                        \
  const ElementType& elementTypeOf<ElementKind::kind>();
STABINT_ELEMENT_KINDS(STABINT_ELEMENT_TYPE_DECLARATION)
#undef STABINT_ELEMENT_TYPE_DECLARATION
/// The same for a run-time kind; throws InvalidInputError for a value outside the enum.
const ElementType& elementType(ElementKind kind);
/// The pin type, for what the element set changes at run time (grab and release).
inline const ElementType& pinElementType() { return elementTypeOf<ElementKind::Pin>(); }
/// The contact type, whose elements the contact set enables and disables at run time.
const ElementType& contactElementType();

}  // namespace stabint
