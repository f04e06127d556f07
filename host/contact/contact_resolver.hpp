#pragma once
// Contact resolution in the step (docs/method.md, "Contact"), one unit a stepping driver holds
// and calls: before the solve, the contact set (which (collider, particle) contact elements are
// active) kept by the broad phase, with L and the factors following it; after the solve,
// friction and the final projection on the accepted state; for checkpoints, the log of the set's
// changes that lets a restore rebuild the factors bit for bit. The per-pair rules are
// contact_rules.hpp's; the contact energy itself is an element (host/elements/contact.cpp,
// kernels/contact.cl) that acts inside every solve. It sits below the drivers (it includes
// neither them nor the facade: scripts/check_layering.sh), so that the batch can hold one too.
#include "backend/backend.hpp"
#include "contact/contact_rules.hpp"  // ContactPart
#include "contact/self_contact.hpp"   // SupportPlane

#include <stabint/types.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace stabint {

class Forcing;
class GlobalSystem;
class SceneData;

class ContactResolver {
 public:
  /// The set at time t from (x, v): the pairs near their colliders are in, the others get weight
  /// 0, and L is assembled from that (before anything is factored). The colliders move as
  /// `forcing` says (it must outlive the resolver).
  ContactResolver(SceneData& scene, const Forcing& forcing, GlobalSystem& system, const SimulatorOptions& options,
                  double t, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v);

  /// The number of (collider, particle) pairs: 0 without colliders.
  int count() const;
  /// The contact element type's block in the scene (-1 without one).
  int block() const { return block_; }

  /// The broad phase at the start of a step from (x, v) at time t (and after setState), before
  /// anything is solved: the contact set, then the half-space of each pair in it
  /// (writeHalfSpaces). A change of the set updates the factors, or, when it is large (a
  /// landing) or the updates since L was last assembled are many, assembles L and factors it
  /// again. For the pairs of `parts` only (a batch's active scenes: the pairs of the others stay
  /// as they are), from the whole scene's (x, v), with one change of L and the factors for all.
  /// Entry i of the result is 1 when the contact energy of x in parts[i] may have changed: a
  /// pair's geometry changed (refreshHalfSpaces), or a pair entered already inside. The caller evaluates that part's
  /// potential again and books the change (BatchDriver::updateContactSets: a half-space that follows x only ever lowers
  /// it).
  std::vector<char> updateSet(double t, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v,
                              const std::vector<ContactPart>& parts);
  /// The geometry each pair of the set of `parts` acts with from (x, v) at time t
  /// (writeHalfSpaces), the set as it is: after each accepted step, so that the params are always
  /// those of the state (a checkpoint's restore calls it too and continues bit for bit), and in
  /// updateSet. Entry i of the result is 1 when a pair of parts[i] changed.
  std::vector<char> refreshHalfSpaces(double t, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v,
                                      const std::vector<ContactPart>& parts);

  /// Within a solve (docs/method.md, "Contact", "Leaving within the solve"): the pairs of `parts`
  /// whose particles the iterate x (the solve's positions at its time t) and the `forces` there
  /// carry away from their colliders since the step's start (x0, v0 at t0) leave the set
  /// (separatingPairs), with one change
  /// of L and the factors for all, logged like the broad phase's. Entry i of the result is 1 when
  /// a pair of parts[i] left. A leaving pair's particle is outside: the objective does not change,
  /// only the solve's initial Hessian K_c.
  std::vector<char> releaseSeparating(double t0, const Eigen::MatrixX3d& x0, const Eigen::MatrixX3d& v0, double t,
                                      const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& forces,
                                      const std::vector<ContactPart>& parts);
  /// Within the same solve: the pairs of `parts` that releaseSeparating let go whose particles
  /// the iterate x (at t) takes back inside their geometry return to the set with it (one change,
  /// logged). Entry i of the result is 1 when a pair of parts[i] returned.
  std::vector<char> returnPenetrating(double t, const Eigen::MatrixX3d& x, const std::vector<ContactPart>& parts);
  /// Every pair of `parts` that releaseSeparating let go since the step began returns with its
  /// geometry (one change, logged), so that another solve of the same step (the blend's partner
  /// after its candidate) starts from the step's set.
  void returnReleased(const std::vector<ContactPart>& parts);
  /// Starts a step: no pair released yet.
  void forgetReleased() { released_.clear(); }

  /// Self-contact's supports in the solve (docs/method.md, "Self-contact", "Support in the
  /// solve"): per support collider (SceneSegment::support_collider), the half-spaces its
  /// particles act with in the next solve. The collider's pairs in the contact set become exactly
  /// the listed particles' (one change of L and the factors for all, logged like the broad
  /// phase's), each with its plane.
  struct Supports {
    int collider;
    std::vector<SupportPlane> planes;  // at most one per particle, the concatenation's indices
  };
  void setSupports(const std::vector<Supports>& supports);
  /// Moves every support plane of `collider` that positions `x` (the scene's rows) are inside
  /// of to pass through them, so that the supports hold no energy in a state a step ends with:
  /// a restore, which does not know the planes, gets the same potential. Returns whether a plane
  /// moved (the caller books the loss).
  bool relaxSupports(int collider, const Eigen::MatrixX3d& x);
  /// The normal impulse h w d of each of `supports` (of support collider `collider`; a scene's,
  /// its particles numbered as the rows of `x`, which are the concatenation's from `first_row`)
  /// at positions `x`: d its depth in its plane, w its weight.
  std::vector<double> supportImpulses(int collider, const std::vector<SupportPlane>& supports,
                                      const Eigen::MatrixX3d& x, int first_row) const;

  /// After the solve, for `part` on its host copies (x, v) of the accepted state at t1: friction takes kinetic energy
  /// out of v and out of `target` (H*) with it, like damping (report.friction); the final projection moves the
  /// positions out of the colliders. When it moved them (`positions_moved`), their potential is the caller's to
  /// evaluate (a batch: one pass for every scene) and to book with bookProjection.
  struct Resolved {
    bool velocities_changed = false;
    bool positions_moved = false;
    double kept = 1.0;     // the share of the projection's removal the colliders' restitution keeps
    double removed = 0.0;  // the contact energy the colliders' moves removed (>= 0)
  };
  /// `x0`: the part's positions at the step's start (rows as x's), for the projection's path rule.
  Resolved applyFrictionAndProjection(const ContactPart& part, double t1,
                                      const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0,
                                      Eigen::MatrixX3d& x, Eigen::MatrixX3d& v, double& target,
                                      StepReport& report) const;
  /// The final projection of `part` alone (no friction, nothing booked), after another
  /// correction (self-contact's impulses) moved x; returns whether it moved a particle.
  bool projectOut(const ContactPart& part, double t1,
                  const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0, Eigen::MatrixX3d& x) const;
  /// Per particle of `part` (rows as x's) at time t, the outward normal of the collider it rests
  /// on: its pair's half-space in the contact set within `margin` of x, or the collider it is
  /// inside; of several, the nearest; zero for a particle no collider holds. Self-contact's
  /// impulses do not push these particles into their collider (docs/method.md, "Self-contact").
  Eigen::MatrixX3d heldNormals(const ContactPart& part, double t, const Eigen::MatrixX3d& x, double margin) const;
  /// Books the final projection of a part whose potential went from `p` to `projected` (one
  /// energy evaluation): of the energy it removed, the share its restitution does not keep
  /// (1 - `kept`, Resolved::kept) leaves `target` (report.contact_projection); `p` becomes
  /// `projected`.
  static void bookProjection(const PotentialEnergy& projected, double kept, PotentialEnergy& p, double& target,
                             StepReport& report);

  /// The set's changes since L was last assembled, in order: e + 1 for pair e entering, -(e + 1)
  /// for one leaving, 0 closing each step's batch; checkpoints carry it.
  const std::vector<std::int32_t>& log() const { return log_; }
  /// The contact flags before a checkpoint's `log` (those L was last assembled from), from its
  /// per-block `enabled` flags, checked against them; throws InvalidInputError for a log that
  /// does not fit the flags or the scene.
  std::vector<std::uint8_t> baseFlags(const std::vector<std::vector<std::uint8_t>>& enabled,
                                      const std::vector<std::int32_t>& log) const;
  /// baseFlags from the contact block's flags alone (one scene's of a batch: its pairs and a log
  /// of them, numbered from its first pair).
  static std::vector<std::uint8_t> baseFlags(std::vector<std::uint8_t> flags, const std::vector<std::int32_t>& log);
  /// A checkpoint's set, with the scene's contact flags set to its baseFlags: L assembled and
  /// every factor computed from them, then `log` replayed on them, so that the run continues bit
  /// for bit (rank updates on other factors would differ in round-off). A group of the log without
  /// entries (one scene's of a batch, where another scene's set changed) changes nothing.
  void restore(const std::vector<std::int32_t>& log);

 private:
  double margin() const;
  bool changeSet(const std::vector<int>& entering, const std::vector<int>& leaving, bool refactor);
  // changeSet, with the change in the log (or the log restarted when L was assembled anew).
  void changeSetLogged(const std::vector<int>& entering, const std::vector<int>& leaving);
  // How far `x` lies above support element `e`'s plane (negative: inside it).
  double supportHeight(int e, const double* x) const;

  SceneData& scene_;
  const Forcing& forcing_;
  GlobalSystem& system_;
  MeshColliders meshes_;  // the queries of the mesh colliders, built once, and their pairs' bounds
  double time_step_, tolerance_;
  int block_ = -1;
  std::vector<std::int32_t> log_;
  int log_columns_ = 0;  // the log's nonzero entries
  // The pairs released since forgetReleased, each with the geometry it acted with, which a
  // return puts back (entering the set writes the collider's own).
  struct Released {
    int pair;
    std::array<double, kColliderGeometry> geometry;
  };
  std::vector<Released> released_;
  // The pairs of released_ that `returning` picks (within `parts`) enter the set again with
  // their geometry; returns them per part.
  template <class Returning>
  std::vector<char> returnReleasedIf(const std::vector<ContactPart>& parts, Returning returning);
};

}  // namespace stabint
