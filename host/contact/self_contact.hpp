#pragma once
// Self-contact and contact between the bodies of one scene (docs/method.md, "Self-contact"): the
// step from x0 to the candidate x1 is made free of crossings between the scene's surface
// triangles, and every surface keeps `thickness` from every other, after the solve (as the final
// projection out of the colliders is).
//
// - Broad phase: a uniform grid over the primitives' swept boxes (x0 to x1, grown by the
//   thickness); the candidate pairs are sorted, so the result does not depend on the grid's
//   hashing order and a run repeats bit for bit.
// - Narrow phase: vertex-triangle and edge-edge pairs, by continuous detection (the times where
//   the four points are coplanar, where the pair's distance is least, and the step's end).
// - Response: an inelastic, momentum-conserving impulse per event along the pair's separating
//   direction at x0, on the positions (to `thickness` apart) and on the velocities (the approach
//   speed removed), Gauss-Seidel over the events in a fixed order, for a few rounds; what still
//   crosses after them is an impact zone whose vertices keep x0 and move on with their mean
//   velocity (x0 crosses nothing, so the fallback always ends crossing-free).
// The guard keeps no state between steps: checkpoints continue bit for bit without it.
#include "contact/pair_events.hpp"

#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <array>
#include <functional>
#include <vector>

namespace stabint {

/// The surface self-contact acts on: Scene::triangles and the tets' boundary faces (tetSurface),
/// a face both give once (docs/method.md "Self-contact"); its edges, each once (first < second,
/// ascending), and the vertices the triangles use (ascending).
struct ContactSurface {
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<int, 2>> edges;
  std::vector<int> vertices;
  static ContactSurface of(const Scene& scene);
  bool empty() const { return triangles.empty(); }
};

/// A broad phase's pairs: vertex-triangle (particle, triangle) and edge-edge (two edges of
/// ContactSurface::edges).
struct ContactCandidates {
  std::vector<std::pair<int, int>> vertex_triangle, edge_edge;
};

/// A half-space a particle acts with in a solve, n . (x - point) >= 0 (docs/method.md,
/// "Self-contact", "Support in the solve").
struct SupportPlane {
  int particle;
  Eigen::Vector3d point, normal;
  // The pair's other side and its contact point's weights: a triangle, or a vertex or an edge
  // padded with its first vertex at weight 0.
  std::array<int, 3> triangle;
  Eigen::Vector3d bary;
};

/// What SelfContact::resolve did in one step.
struct SelfContactResult {
  int events = 0;                // impulses applied
  int frozen = 0;                // vertices of impact zones put back at x0
  double kinetic_removed = 0.0;  // >= 0: what the impulses and the zones took from the motion
  bool positions_moved = false;
  bool velocities_changed = false;
};

/// Where a cloth vertex may get a support in the solve (SimulatorOptions::self_contact_supports 1
/// and 2): on a triangle whose side hardly moves under the pair's impulse (a tet body far heavier
/// than the vertex, or pinned), in any direction; everywhere, also on any triangle it rests on
/// against gravity.
enum class SupportSurfaces { HeavyBodies, Everywhere };

class SelfContact {
 public:
  /// `scene`'s surface (ContactSurface::of); thickness > 0; `friction`, the Coulomb coefficient
  /// between the surfaces (>= 0).
  SelfContact(const Scene& scene, double thickness, double friction = 0.0);
  bool empty() const { return surface_.empty(); }
  const ContactSurface& surface() const { return surface_; }

  /// The broad phase of the path x0 -> x1: every pair that may meet on it or end within the
  /// thickness (with `moved`, a flag per particle, only the pairs with a moved vertex); with
  /// `support_reach`, only the vertex-triangle pairs that may come that near (supports' query).
  ContactCandidates candidates(const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0,
                               const Eigen::MatrixX3d& x1, const std::vector<char>* moved = nullptr,
                               double support_reach = 0.0) const;
  /// The pairs that meet on the path x0 -> x1 (crossing or touching within the step, or ending
  /// closer than `closer_than`), sorted (vertex-triangle before edge-edge, then by vertices);
  /// with `moved`, only the pairs with a moved vertex.
  std::vector<ContactEvent> events(const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0,
                                   const Eigen::MatrixX3d& x1, double closer_than,
                                   const std::vector<char>* moved = nullptr) const;

  /// Makes the step x0 -> x1 crossing-free and leaves the surfaces `thickness` apart where it
  /// can, moving x1 and v1 (rows as x0's) by the impulses; `masses` are the scene's, and the
  /// `fixed` vertices (pins) take no impulse. `keep_out`, called after each round of impulses
  /// with x1, may move particles again (the colliders' projection); returns whether it did. `up`
  /// (unit, against gravity; zero: none): a pair stacked along it, whose upper side is not much
  /// heavier than its lower one, has its positions pushed apart by moving its upper side alone,
  /// so that a body resting on another is lifted out of it and never pushes the lower one into
  /// what supports it (shock propagation). `held` (rows as x1's; null: none): per particle, the
  /// outward normal of the collider holding it (ContactResolver::heldNormals), zero where none;
  /// the positions' push never moves a held side into its collider.
  SelfContactResult resolve(const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x0, Eigen::MatrixX3d& x1,
                            Eigen::MatrixX3d& v1, const Eigen::VectorXd& masses, const std::vector<int>& fixed,
                            const std::function<bool(Eigen::MatrixX3d&)>& keep_out = {},
                            const Eigen::Vector3d& up = Eigen::Vector3d::Zero(),
                            const Eigen::MatrixX3d* held = nullptr) const;

  /// Before a step's solve, from the state (x, v) at its start and the positions `predicted` for
  /// its end (the caller's: free flight under gravity, kept out of the colliders): the pairs that
  /// meet on the path x -> predicted lose the approach speed that would bring them nearer than
  /// the thickness, by inelastic impulses on v alone (momentum kept, pins fixed). The solve then
  /// stops the rest of each body through its elements, where the positions' correction after the
  /// solve (resolve) would stretch the few elements at a contact's edge. Returns the kinetic
  /// energy removed (>= 0). With `supports`, also each particle's support in the solve: a cloth
  /// vertex of a vertex-triangle pair keeps its side of the triangle where the prediction (as
  /// stopped; a tet body's rigidly: `fall`, h^2 g, less what the colliders lift it) puts the
  /// triangle at the step's end, the thickness apart or as far as it is now (never inside at x:
  /// the support adds no energy to the state it starts from); of several, the nearest; on the
  /// surfaces `where` names. `held` (as resolve's, at the prediction): a side a collider holds
  /// takes no share of an impulse pushing it into the collider where the other side is heavy
  /// (moving at most a tenth as far under it).
  double stopApproach(const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x, Eigen::MatrixX3d& v,
                      const Eigen::MatrixX3d& predicted, double h, const Eigen::VectorXd& masses,
                      const std::vector<int>& fixed, std::vector<SupportPlane>* supports = nullptr,
                      const Eigen::Vector3d& fall = Eigen::Vector3d::Zero(),
                      SupportSurfaces where = SupportSurfaces::Everywhere,
                      const Eigen::MatrixX3d* held = nullptr) const;

  /// Coulomb friction of the supports after the solve (docs/method.md, "Self-contact",
  /// "Friction"): for each support (rows as v's), its normal impulse `impulses[i]` (h w d, from
  /// its depth d in its plane at the solve's end) lets the relative tangential velocity of its
  /// vertex and triangle shrink by at most mu times it over the vertex's mass, never reversing,
  /// by an impulse on both (momentum kept, pins fixed). Returns the kinetic energy removed.
  double supportFriction(const std::vector<SupportPlane>& supports, const std::vector<double>& impulses,
                         const Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>& x, Eigen::MatrixX3d& v,
                         const Eigen::VectorXd& masses, const std::vector<int>& fixed) const;
  double friction() const { return friction_; }
  double thickness() const { return thickness_; }

  /// Rounds of impulses before the impact zones.
  static constexpr int kRounds = 8;
  /// Sweeps of a round's pushes as accumulated impulses, and the largest move (over the
  /// thickness) that ends them.
  static constexpr int kSweeps = 16;
  static constexpr double kSweepTolerance = 1e-3;

 private:
  ContactSurface surface_;
  double thickness_;
  double friction_;
  // The tet bodies (the particles their tets connect, ascending), which answer impulses as rigid
  // bodies, and each particle's body (-1: none).
  std::vector<int> solid_of_;
  std::vector<std::vector<int>> solids_;
};

}  // namespace stabint
