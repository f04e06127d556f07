#pragma once
// Self-contact's narrow phase (docs/method.md, "Self-contact"): whether a vertex-triangle or an
// edge-edge pair of a surface meets while its points move on straight paths over a step
// (continuous detection), and with which weights and direction an impulse separates it.
#include <Eigen/Core>

#include <array>
#include <vector>

namespace stabint {

/// A vertex-triangle pair (vertices p, a, b, c) or an edge-edge pair (a b against c d) that meets
/// within the step: the four vertices, the weights of the pair's separation d = sum w_i x_i
/// (1, -b_a, -b_b, -b_c for a vertex against the barycentric point of a triangle; 1 - s, s,
/// -(1 - t), -t between the closest points of two edges) and its direction n at x0.
struct ContactEvent {
  std::array<int, 4> vertices{};
  std::array<double, 4> weights{};
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  bool crossing = false;  // the pair passes (or touches) within the step; else it only ends too close
  bool edge_edge = false;
};

/// Rows of positions: a whole matrix, or a scene's rows of a batch's.
using PositionRows = Eigen::Ref<const Eigen::MatrixX3d, 0, Eigen::OuterStride<>>;

inline Eigen::Vector3d rowOf(const PositionRows& x, int i) { return x.row(i).transpose(); }
inline Eigen::Vector3d rowOf(const Eigen::MatrixX3d& x, int i) { return x.row(i).transpose(); }

/// The event of vertex `v` against triangle `tri` on the paths x0 -> x1, if they meet, onto
/// `out`: they cross or touch (closest points within `touching`) at a root or an extremum of
/// their coplanarity cubic, or end nearer than `closer_than`. `scale`, the scene's size, decides
/// what counts as touching at x0 (where the direction falls back to the triangle's normal).
void vertexTriangleEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, int v, const std::array<int, 3>& tri,
                         double closer_than, double touching, double scale, std::vector<ContactEvent>& out);
/// A self-contact support's pair (docs/method.md, "Self-contact", "Support in the solve"): vertex
/// `v` ends (at x1) within `reach` of triangle `tri`, over its face at x0 (the direction from the
/// triangle's closest point to the vertex there within 60 degrees of the face's normal: a cloth's
/// own neighbouring triangles, beside each vertex within the reach, are no support). The event's
/// weights are those of the closest point at x1, its direction that at x0.
void supportPairEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, int v, const std::array<int, 3>& tri,
                      double reach, double scale, std::vector<ContactEvent>& out);
/// The same for edges e1 and e2.
void edgeEdgeEvent(const PositionRows& x0, const Eigen::MatrixX3d& x1, const std::array<int, 2>& e1,
                   const std::array<int, 2>& e2, double closer_than, double touching, double scale,
                   std::vector<ContactEvent>& out);

}  // namespace stabint
