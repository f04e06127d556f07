#include "contact/self_contact.hpp"

#include "common/worker_pool.hpp"
#include "contact/box_grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>
#include <utility>

namespace stabint {
namespace {

using Vec3 = Eigen::Vector3d;

// The box a primitive sweeps in a frame that moves by `shift` over the step (the surface's mean
// motion: a body falling as a whole sweeps small boxes in it, and the pairs it finds are the same,
// contact depending on relative motion only).
template <std::size_t K>
Box sweptBox(const std::array<int, K>& v, const PositionRows& x0, const Eigen::MatrixX3d& x1, const Vec3& shift,
             double grow) {
  Box b{rowOf(x0, v[0]), rowOf(x0, v[0])};
  for (std::size_t i = 0; i < K; ++i) {
    for (const Vec3& p : {rowOf(x0, v[i]), Vec3(rowOf(x1, v[i]) - shift)}) {
      b.lo = b.lo.cwiseMin(p);
      b.hi = b.hi.cwiseMax(p);
    }
  }
  b.lo.array() -= grow;
  b.hi.array() += grow;
  return b;
}

// Two edges that share no vertex, and a vertex not of a triangle (those that share one always touch).
bool apart(const std::array<int, 2>& e, const std::array<int, 2>& f) {
  return e[0] != f[0] && e[0] != f[1] && e[1] != f[0] && e[1] != f[1];
}
bool outside(int v, const std::array<int, 3>& tri) { return tri[0] != v && tri[1] != v && tri[2] != v; }

}  // namespace

ContactSurface ContactSurface::of(const Scene& scene) {
  ContactSurface s;
  // The cloth's triangles and the tet bodies' surfaces, a face given by both once.
  std::set<std::array<int, 3>> seen;
  for (const auto& list : {scene.triangles, tetSurface(scene.tets)}) {
    for (const auto& t : list) {
      std::array<int, 3> key = t;
      std::sort(key.begin(), key.end());
      if (seen.insert(key).second) s.triangles.push_back(t);
    }
  }
  for (const auto& t : s.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      s.edges.push_back({std::min(a, b), std::max(a, b)});
      s.vertices.push_back(a);
    }
  }
  std::sort(s.edges.begin(), s.edges.end());
  s.edges.erase(std::unique(s.edges.begin(), s.edges.end()), s.edges.end());
  std::sort(s.vertices.begin(), s.vertices.end());
  s.vertices.erase(std::unique(s.vertices.begin(), s.vertices.end()), s.vertices.end());
  return s;
}

namespace {

int findRoot(std::vector<int>& parent, int i) {
  while (parent[std::size_t(i)] != i) i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
  return i;
}

}  // namespace

SelfContact::SelfContact(const Scene& scene, double thickness, double friction)
    : surface_(ContactSurface::of(scene)),
      thickness_(thickness),
      friction_(friction),
      solid_of_(static_cast<std::size_t>(scene.numParticles()), -1) {
  // The tet bodies: the particles their tets connect.
  std::vector<int> parent(static_cast<std::size_t>(scene.numParticles()));
  std::iota(parent.begin(), parent.end(), 0);
  for (const Tet& t : scene.tets)
    for (int k = 1; k < 4; ++k) parent[std::size_t(findRoot(parent, t.vertices[k]))] = findRoot(parent, t.vertices[0]);
  std::vector<int> index_of_root(parent.size(), -1);
  std::vector<char> in_tet(parent.size(), 0);
  for (const Tet& t : scene.tets)
    for (int v : t.vertices) in_tet[std::size_t(v)] = 1;
  for (std::size_t i = 0; i < parent.size(); ++i) {
    if (!in_tet[i]) continue;
    int& b = index_of_root[std::size_t(findRoot(parent, static_cast<int>(i)))];
    if (b < 0) {
      b = static_cast<int>(solids_.size());
      solids_.emplace_back();
    }
    solid_of_[i] = b;
    solids_[std::size_t(b)].push_back(static_cast<int>(i));
  }
}

namespace {

// The primitives' swept boxes of one query, and the grids' cell size.
struct SweptBoxes {
  std::vector<Box> triangles, edges, vertices;
  double cell = 0.0;
};

// Work in chunks on the worker threads, each chunk's pairs in its own list, the lists joined in
// chunk order: the serial order. `work(chunk, list)` for chunks [0, count).
template <typename Work>
std::vector<std::pair<int, int>> inChunks(int count, Work&& work) {
  std::vector<std::vector<std::pair<int, int>>> lists(static_cast<std::size_t>(count));
  parallelFor(count, [&](int chunk) { work(chunk, lists[std::size_t(chunk)]); });
  std::vector<std::pair<int, int>> joined;
  for (const auto& list : lists) joined.insert(joined.end(), list.begin(), list.end());
  return joined;
}

constexpr int kChunk = 256;
int chunksOf(std::size_t n) { return static_cast<int>((n + kChunk - 1) / kChunk); }
std::size_t chunkEnd(std::size_t n, int chunk) { return std::min(n, std::size_t(chunk + 1) * kChunk); }

// Every pair: each vertex's triangles from the triangle grid, in vertex order, and the edge pairs
// from the edge grid's cells (each cell's pairs of entries once), in chunks of cells.
ContactCandidates allPairs(const ContactSurface& surface, const std::vector<std::array<int, 2>>& edges,
                           const SweptBoxes& boxes) {
  const auto& tris = surface.triangles;
  const auto& verts = surface.vertices;
  Grid triangle_grid, edge_grid;
  parallelFor(2, [&](int which) {
    if (which == 0) triangle_grid = Grid(boxes.triangles, boxes.cell);
    if (which == 1) edge_grid = Grid(boxes.edges, boxes.cell);
  });
  ContactCandidates found;
  found.vertex_triangle = inChunks(chunksOf(verts.size()), [&](int chunk, std::vector<std::pair<int, int>>& list) {
    for (std::size_t i = std::size_t(chunk) * kChunk; i < chunkEnd(verts.size(), chunk); ++i) {
      const int v = verts[i];
      triangle_grid.query(
          boxes.vertices[i], [&](int t) { return outside(v, tris[std::size_t(t)]); },
          [&](int t) { list.emplace_back(v, t); });
    }
  });
  const std::size_t cells_per_chunk = (edge_grid.cells() + kChunk - 1) / kChunk;
  found.edge_edge = inChunks(cells_per_chunk == 0 ? 0 : kChunk, [&](int chunk, std::vector<std::pair<int, int>>& list) {
    const std::size_t first = std::size_t(chunk) * cells_per_chunk;
    edge_grid.pairsInCells(
        first, std::min(edge_grid.cells(), first + cells_per_chunk),
        [&](int i, int j) { return apart(edges[std::size_t(i)], edges[std::size_t(j)]); },
        [&](int i, int j) { list.emplace_back(i, j); });
  });
  return found;
}

// The pairs with a moved vertex, from grids of the moved primitives alone (a later round of
// impulses moves a few): each vertex against the triangles that moved, each triangle that did not
// against the vertices that moved, each edge against the edges that moved. The same pairs as a
// query of every moved primitive against all, each edge pair as (moved edge, other), the lower
// first when both moved; in another order, which events() sorts away.
ContactCandidates movedPairs(const ContactSurface& surface, const std::vector<std::array<int, 2>>& edges,
                             const SweptBoxes& boxes, const std::vector<char>& moved) {
  const auto& tris = surface.triangles;
  const auto& verts = surface.vertices;
  const auto any = [&](const auto& primitive) {
    for (int v : primitive)
      if (moved[std::size_t(v)]) return char(1);
    return char(0);
  };
  std::vector<char> moved_vertex, moved_triangle, moved_edge;
  for (int v : verts) moved_vertex.push_back(moved[std::size_t(v)]);
  for (const auto& t : tris) moved_triangle.push_back(any(t));
  for (const auto& e : edges) moved_edge.push_back(any(e));
  Grid triangle_grid, vertex_grid, edge_grid;
  parallelFor(3, [&](int which) {
    if (which == 0) triangle_grid = Grid(boxes.triangles, boxes.cell, &moved_triangle);
    if (which == 1) vertex_grid = Grid(boxes.vertices, boxes.cell, &moved_vertex);
    if (which == 2) edge_grid = Grid(boxes.edges, boxes.cell, &moved_edge);
  });
  const int vertex_chunks = chunksOf(verts.size()), triangle_chunks = chunksOf(tris.size());
  ContactCandidates found;
  found.vertex_triangle =
      inChunks(vertex_chunks + triangle_chunks, [&](int chunk, std::vector<std::pair<int, int>>& list) {
        if (chunk < vertex_chunks) {
          for (std::size_t i = std::size_t(chunk) * kChunk; i < chunkEnd(verts.size(), chunk); ++i) {
            const int v = verts[i];
            triangle_grid.query(
                boxes.vertices[i], [&](int t) { return outside(v, tris[std::size_t(t)]); },
                [&](int t) { list.emplace_back(v, t); });
          }
          return;
        }
        chunk -= vertex_chunks;
        for (std::size_t t = std::size_t(chunk) * kChunk; t < chunkEnd(tris.size(), chunk); ++t) {
          if (moved_triangle[t]) continue;
          const int ti = static_cast<int>(t);
          vertex_grid.query(
              boxes.triangles[t], [&](int k) { return outside(verts[std::size_t(k)], tris[t]); },
              [&](int k) { list.emplace_back(verts[std::size_t(k)], ti); });
        }
      });
  found.edge_edge = inChunks(chunksOf(edges.size()), [&](int chunk, std::vector<std::pair<int, int>>& list) {
    for (std::size_t q = std::size_t(chunk) * kChunk; q < chunkEnd(edges.size(), chunk); ++q) {
      const int i = static_cast<int>(q);
      edge_grid.query(
          boxes.edges[q],
          [&](int j) { return j != i && (!moved_edge[q] || i < j) && apart(edges[q], edges[std::size_t(j)]); },
          [&](int j) { moved_edge[q] ? list.emplace_back(i, j) : list.emplace_back(j, i); });
    }
  });
  return found;
}

}  // namespace

ContactCandidates SelfContact::candidates(const PositionRows& x0, const Eigen::MatrixX3d& x1,
                                          const std::vector<char>* moved, double support_reach) const {
  if (surface_.empty()) return ContactCandidates{};
  // A supports' query: the vertex-triangle pairs within support_reach, no edges.
  const bool supports_only = support_reach > 0.0;
  const double grow = 0.5 * thickness_;
  const double grow_vt = supports_only ? 0.5 * support_reach : grow;
  const auto& tris = surface_.triangles;
  static const std::vector<std::array<int, 2>> kNoEdges;
  const auto& edges = supports_only ? kNoEdges : surface_.edges;
  const auto& verts = surface_.vertices;
  SweptBoxes boxes;
  boxes.triangles.resize(tris.size());
  boxes.edges.resize(edges.size());
  boxes.vertices.resize(verts.size());
  Vec3 shift = Vec3::Zero();
  for (int v : verts) shift += rowOf(x1, v) - rowOf(x0, v);
  shift /= double(verts.size());
  const int triangle_chunks = chunksOf(tris.size()), edge_chunks = chunksOf(edges.size());
  parallelFor(triangle_chunks + edge_chunks + chunksOf(verts.size()), [&](int chunk) {
    if (chunk < triangle_chunks) {
      for (std::size_t i = std::size_t(chunk) * kChunk; i < chunkEnd(tris.size(), chunk); ++i)
        boxes.triangles[i] = sweptBox(tris[i], x0, x1, shift, grow_vt);
    } else if ((chunk -= triangle_chunks) < edge_chunks) {
      for (std::size_t i = std::size_t(chunk) * kChunk; i < chunkEnd(edges.size(), chunk); ++i)
        boxes.edges[i] = sweptBox(edges[i], x0, x1, shift, grow);
    } else {
      chunk -= edge_chunks;
      for (std::size_t i = std::size_t(chunk) * kChunk; i < chunkEnd(verts.size(), chunk); ++i)
        boxes.vertices[i] = sweptBox(std::array<int, 1>{verts[i]}, x0, x1, shift, grow_vt);
    }
  });
  double extent = 0.0;
  for (const Box& b : boxes.triangles) extent += (b.hi - b.lo).maxCoeff();
  // Cells about one triangle's swept box wide: each box covers a few cells, each cell a few boxes.
  boxes.cell = std::max(extent / double(tris.size()), 4.0 * thickness_);
  return moved ? movedPairs(surface_, edges, boxes, *moved) : allPairs(surface_, edges, boxes);
}

std::vector<ContactEvent> SelfContact::events(const PositionRows& x0, const Eigen::MatrixX3d& x1, double closer_than,
                                              const std::vector<char>* moved) const {
  std::vector<ContactEvent> out;
  if (surface_.empty()) return out;
  const ContactCandidates pairs = candidates(x0, x1, moved);
  const auto& tris = surface_.triangles;
  const auto& edges = surface_.edges;
  // The scene's size, for what counts as touching at x0.
  const double scale = std::max((x0.colwise().maxCoeff() - x0.colwise().minCoeff()).maxCoeff(), thickness_);
  // A pair passes within the step when it is coplanar (or closest) with its closest points this
  // near: a tenth of the thickness, far below any distance the impulses leave.
  const double touching = 0.1 * thickness_;
  // The narrow phase in chunks of pairs on the worker threads, joined in chunk order.
  constexpr std::size_t kChunk = 512;
  const std::size_t vt = pairs.vertex_triangle.size(), ee = pairs.edge_edge.size();
  const int vt_chunks = static_cast<int>((vt + kChunk - 1) / kChunk);
  const int chunks = vt_chunks + static_cast<int>((ee + kChunk - 1) / kChunk);
  std::vector<std::vector<ContactEvent>> found(static_cast<std::size_t>(chunks));
  parallelFor(chunks, [&](int chunk) {
    std::vector<ContactEvent>& list = found[std::size_t(chunk)];
    if (chunk < vt_chunks) {
      for (std::size_t k = std::size_t(chunk) * kChunk; k < std::min(vt, std::size_t(chunk + 1) * kChunk); ++k) {
        const auto [v, t] = pairs.vertex_triangle[k];
        const auto& tri = tris[std::size_t(t)];
        vertexTriangleEvent(x0, x1, v, tri, closer_than, touching, scale, list);
      }
      return;
    }
    const std::size_t first = std::size_t(chunk - vt_chunks) * kChunk;
    for (std::size_t k = first; k < std::min(ee, first + kChunk); ++k) {
      const auto [i, j] = pairs.edge_edge[k];
      const auto& e = edges[std::size_t(i)];
      const auto& f = edges[std::size_t(j)];
      edgeEdgeEvent(x0, x1, e, f, closer_than, touching, scale, list);
    }
  });
  for (const auto& list : found) out.insert(out.end(), list.begin(), list.end());
  std::sort(out.begin(), out.end(), [](const ContactEvent& a, const ContactEvent& b) {
    return std::tie(a.edge_edge, a.vertices) < std::tie(b.edge_edge, b.vertices);
  });
  return out;
}

namespace {

double kinetic(const Eigen::MatrixX3d& v, const Eigen::VectorXd& masses) {
  return 0.5 * (v.rowwise().squaredNorm().transpose().array() * masses.transpose().array()).sum();
}

// How the particles answer a pair's impulse: a cloth's particle alone, through its own mass; a
// tet body as a rigid body, through its mass and its inertia about its centre at the reference
// positions x (a body's contact layer stopped or pushed back alone is carried on by the rest of
// the body within the step, and its elements invert: two tet bars dropped onto each other inverted
// 583 tets). A pair whose four vertices are all of one tet body (a body touching itself) answers
// per particle. A body with a pinned particle, like a pinned particle, takes no impulse.
class Response {
 public:
  Response(const std::vector<int>& solid_of, const std::vector<std::vector<int>>& solids, const PositionRows& x,
           const Eigen::VectorXd& masses, const std::vector<int>& fixed)
      : solid_of_(solid_of), solids_(solids), x_(x), inverse_mass_(masses.cwiseInverse()) {
    for (int f : fixed) inverse_mass_[f] = 0.0;
    for (const std::vector<int>& body : solids) {
      double mass = 0.0;
      Vec3 centre = Vec3::Zero();
      bool pinned = false;
      for (int i : body) {
        mass += masses[i];
        centre += masses[i] * rowOf(x, i);
        pinned = pinned || inverse_mass_[i] == 0.0;
      }
      centre /= mass;
      Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
      for (int i : body) {
        const Vec3 r = rowOf(x, i) - centre;
        inertia += masses[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
      centres_.push_back(centre);
      inverse_body_mass_.push_back(pinned ? 0.0 : 1.0 / mass);
      inverse_inertia_.push_back(pinned ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(inertia.inverse()));
    }
  }

  // The body vertex i of `e` answers through (-1: alone).
  int bodyOf(const ContactEvent& e, int k) const {
    const int b = solid_of_[std::size_t(e.vertices[std::size_t(k)])];
    if (b < 0) return -1;
    for (int v : e.vertices)
      if (solid_of_[std::size_t(v)] != b) return b;
    return -1;  // the body touches itself
  }
  // Whether vertex k of `e` takes no share of a position push with `up` set: it is on the pair's
  // lower side, and the pair's direction within 60 degrees of the vertical (docs/method.md,
  // "Self-contact": a stack is pushed apart upwards, never into what supports it).
  static bool below(const ContactEvent& e, int k, const Vec3* up) {
    if (!up) return false;
    const double vertical = e.normal.dot(*up);
    return std::abs(vertical) >= 0.5 && e.weights[std::size_t(k)] * vertical < 0.0;
  }
  // A body's share of an impulse on `e` along `dir`: the sum of its vertices' weights and of their
  // moments about its centre.
  void share(const ContactEvent& e, int b, const Vec3& dir, double& weight, Vec3& moment,
             const Vec3* up = nullptr) const {
    weight = 0.0;
    moment.setZero();
    for (int k = 0; k < 4; ++k) {
      if (bodyOf(e, k) != b || below(e, k, up)) continue;
      const int i = e.vertices[std::size_t(k)];
      weight += e.weights[std::size_t(k)];
      moment += e.weights[std::size_t(k)] * (rowOf(x_, i) - centres_[std::size_t(b)]).cross(dir);
    }
  }
  // How far a unit impulse along `dir` (e's normal, or a tangent for friction) moves the pair's
  // relative motion along it: sum w_i^2 / m_i over the particles that answer alone, and
  // a^2 / M + t . I^-1 t over the bodies (a, t: share). With `up`, the pair's lower side takes no
  // share (below).
  double compliance(const ContactEvent& e, const Vec3& dir, const Vec3* up = nullptr) const {
    double c = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (below(e, k, up)) continue;
      const int b = bodyOf(e, k);
      const double w = e.weights[std::size_t(k)];
      if (b < 0) {
        c += w * w * inverse_mass_[e.vertices[std::size_t(k)]];
        continue;
      }
      if (firstOfBody(e, k, up)) {
        double a;
        Vec3 t;
        share(e, b, dir, a, t, up);
        c += a * a * inverse_body_mass_[std::size_t(b)] + t.dot(inverse_inertia_[std::size_t(b)] * t);
      }
    }
    return c;
  }
  bool firstOfBody(const ContactEvent& e, int k, const Vec3* up = nullptr) const {
    for (int j = 0; j < k; ++j)
      if (!below(e, j, up) && bodyOf(e, j) == bodyOf(e, k)) return false;
    return true;
  }
  double inverseMass(int i) const { return inverse_mass_[i]; }
  const Vec3& centre(int b) const { return centres_[std::size_t(b)]; }
  double inverseBodyMass(int b) const { return inverse_body_mass_[std::size_t(b)]; }
  const Eigen::Matrix3d& inverseInertia(int b) const { return inverse_inertia_[std::size_t(b)]; }
  const std::vector<int>& solidOf() const { return solid_of_; }
  const std::vector<std::vector<int>>& solids() const { return solids_; }
  const PositionRows& reference() const { return x_; }

 private:
  const std::vector<int>& solid_of_;
  const std::vector<std::vector<int>>& solids_;
  PositionRows x_;
  Eigen::VectorXd inverse_mass_;
  std::vector<Vec3> centres_;
  std::vector<double> inverse_body_mass_;
  std::vector<Eigen::Matrix3d> inverse_inertia_;
};

// Rows (velocities or positions) that impulses change through a Response: a particle's row at
// once, a body's as a pending linear and angular change, applied to all its rows by settle().
class Motion {
 public:
  Motion(const Response& response, Eigen::MatrixX3d& rows)
      : response_(response),
        rows_(rows),
        linear_(response.solids().size(), Vec3::Zero()),
        angular_(response.solids().size(), Vec3::Zero()) {}

  Vec3 at(int i) const {
    const int b = response_.solidOf()[std::size_t(i)];
    Vec3 r = rowOf(rows_, i);
    if (b >= 0)
      r += linear_[std::size_t(b)] +
           angular_[std::size_t(b)].cross(rowOf(response_.reference(), i) - response_.centre(b));
    return r;
  }
  // The pair's relative row, sum w_i row_i.
  Vec3 relative(const ContactEvent& e) const {
    Vec3 d = Vec3::Zero();
    for (int k = 0; k < 4; ++k) d += e.weights[std::size_t(k)] * at(e.vertices[std::size_t(k)]);
    return d;
  }
  // The separation of `e` along its normal (n . sum w_i row_i).
  double along(const ContactEvent& e) const { return e.normal.dot(relative(e)); }
  // An impulse `j` along `dir` (with `up`, on the pair's upper side alone); `moved` (when given)
  // flags the particles that answer alone.
  void push(const ContactEvent& e, double j, const Vec3& dir, std::vector<char>* moved = nullptr,
            const Vec3* up = nullptr) {
    for (int k = 0; k < 4; ++k) {
      if (Response::below(e, k, up)) continue;
      const int b = response_.bodyOf(e, k);
      const int i = e.vertices[std::size_t(k)];
      if (b < 0) {
        const double share = e.weights[std::size_t(k)] * response_.inverseMass(i);
        if (share == 0.0) continue;
        rows_.row(i) += (j * share) * dir.transpose();
        if (moved) (*moved)[std::size_t(i)] = 1;
        continue;
      }
      if (!response_.firstOfBody(e, k, up)) continue;
      double a;
      Vec3 t;
      response_.share(e, b, dir, a, t, up);
      linear_[std::size_t(b)] += (j * a * response_.inverseBodyMass(b)) * dir;
      angular_[std::size_t(b)] += j * (response_.inverseInertia(b) * t);
    }
  }
  // Applies the bodies' pending changes to their rows; `moved` flags the rows of bodies that changed.
  void settle(std::vector<char>* moved = nullptr) {
    for (std::size_t b = 0; b < linear_.size(); ++b) {
      if (linear_[b].isZero() && angular_[b].isZero()) continue;
      for (int i : response_.solids()[b]) {
        rows_.row(i) = at(i).transpose();
        if (moved) (*moved)[std::size_t(i)] = 1;
      }
      linear_[b].setZero();
      angular_[b].setZero();
    }
  }

 private:
  const Response& response_;
  Eigen::MatrixX3d& rows_;
  std::vector<Vec3> linear_, angular_;
};

// [project rule] Coulomb friction between the surfaces (docs/method.md, "Self-contact"): the
// pair's relative tangential velocity shrinks by at most mu times the change `normal` (>= 0) the
// impulse just applied made to its normal velocity, and never reverses. Friction removes kinetic
// energy only (an impulse that slows the relative motion it acts along, without reversing it).
void applyFriction(const ContactEvent& e, double mu, double normal, const Response& response, Motion& velocity) {
  if (!(mu > 0.0) || !(normal > 0.0)) return;
  const Vec3 relative = velocity.relative(e);
  const Vec3 tangential = relative - e.normal.dot(relative) * e.normal;
  const double slip = tangential.norm();
  if (!(slip > 0.0)) return;
  const Vec3 dir = tangential / slip;
  const double compliance = response.compliance(e, dir);
  if (!(compliance > 0.0)) return;
  velocity.push(e, -std::min(slip, mu * normal) / compliance, dir);
}

// The side of a pair a support stands for, from the held side's view (side 0: the pair's vertex or
// first edge; 1: its triangle or second edge): its contact point at x and as predicted at the step's
// end, and its vertices and weights as a support's "triangle" (a vertex or an edge padded with its
// first vertex at weight 0), for friction.
struct OtherSide {
  Vec3 start = Vec3::Zero(), end = Vec3::Zero();
  std::array<int, 3> vertices{};
  Vec3 weights = Vec3::Zero();
};
int sideOf(const ContactEvent& e, int k) { return k < (e.edge_edge ? 2 : 1) ? 0 : 1; }
OtherSide otherSide(const ContactEvent& e, int held, const PositionRows& x, const Eigen::MatrixX3d& ends) {
  OtherSide other;
  int count = 0;
  for (int k = 0; k < 4; ++k) {
    if (sideOf(e, k) == held) continue;
    const int v = e.vertices[std::size_t(k)];
    const double w = std::abs(e.weights[std::size_t(k)]);
    other.start += w * rowOf(x, v);
    other.end += w * rowOf(ends, v);
    other.vertices[std::size_t(count)] = v;
    other.weights[count++] = w;
  }
  for (int j = count; j < 3; ++j) other.vertices[std::size_t(j)] = other.vertices[0];
  return other;
}

// The compliance of one side of a pair alone: the pair's with the other side's weights zeroed.
double sideCompliance(ContactEvent e, int side, const Response& response) {
  for (int k = 0; k < 4; ++k)
    if (sideOf(e, k) != side) e.weights[std::size_t(k)] = 0.0;
  return response.compliance(e, e.normal);
}

// Each particle's support in the solve (SelfContact::stopApproach), against where the other side
// of its pair is predicted at the step's end (`ends`).
void supportPlanes(const std::vector<ContactEvent>& found, const PositionRows& x, const Eigen::MatrixX3d& ends,
                   double thickness, double reach, const Vec3& up, const Response& response, SupportSurfaces where,
                   std::vector<SupportPlane>& supports) {
  // Per particle the plane with the least room between x and the thickness (slack), the first of equals.
  std::vector<int> chosen(static_cast<std::size_t>(x.rows()), -1);
  std::vector<double> slack;
  for (const ContactEvent& e : found) {
    const double compliance[2] = {sideCompliance(e, 0, response), sideCompliance(e, 1, response)};
    for (int held = 0; held < 2; ++held) {
      // The side held rests on the other one, which stands as a plane fixed for the step:
      // - in any direction where the other side hardly moves for it (a tenth as far: a tet body
      //   far heavier than a cloth, or pinned), in every pair shape. A cloth draped over a tet bar,
      //   held on its top alone, was pushed back after the solve at the bar's sides (H ran 1.35
      //   times the largest kinetic energy above H*); with its vertices held on the bar's faces
      //   alone, the bar's corners and edges poked through its triangles and edges in the solve
      //   and were pushed back by centimetres (H up to 2.4 times the blend's band above H*, within
      //   1.1 with the cloth's triangles and edges held on them too);
      // - with `Everywhere`, also a cloth vertex resting on a triangle against gravity (their
      //   direction within 60 degrees of the vertical, the vertex above): the plane does not give
      //   way, and a vertex under a layer, pulled up against it, stayed trapped under it while its
      //   cloth was dragged away.
      const bool heavy = compliance[held] > 0.0 && compliance[1 - held] <= 0.1 * compliance[held];
      const bool rests = where == SupportSurfaces::Everywhere && held == 0 && !e.edge_edge && e.normal.dot(up) >= 0.5;
      if (!heavy && !rests) continue;
      const Vec3 normal = held == 0 ? e.normal : Vec3(-e.normal);  // the held side's outward direction
      const OtherSide other = otherSide(e, held, x, ends);
      for (int k = 0; k < 4; ++k) {
        if (sideOf(e, k) != held || e.weights[std::size_t(k)] == 0.0) continue;
        const int p = e.vertices[std::size_t(k)];
        // A tet body's particles answer as the body (Response): a support of one would hold it alone.
        if (response.inverseMass(p) == 0.0 || response.solidOf()[std::size_t(p)] >= 0) continue;
        const double gap = normal.dot(rowOf(x, p) - other.end);
        if (!(gap > 0.0)) continue;
        // On a light side, resting or slow contact only: a particle that moves relative to the
        // other side's point by more than the reach within the step is in an impact or a slide,
        // which the impulses answer. A heavy side holds at any speed: a cloth thrown at a tet
        // bar, held only where slow, slid over the bar's faces faster than the reach, crossed
        // them in the solve and was pushed back by centimetres after it (SelfContactRun,
        // AClothDropsOntoATetBarAndDrapesOverIt).
        if (!heavy && (rowOf(ends, p) - rowOf(x, p) - (other.end - other.start)).norm() > reach) continue;
        const double offset = std::min(thickness, gap);
        int& c = chosen[std::size_t(p)];
        if (c >= 0 && !(gap - offset < slack[std::size_t(c)])) continue;
        if (c < 0) {
          c = static_cast<int>(supports.size());
          supports.emplace_back();
          slack.push_back(0.0);
        }
        supports[std::size_t(c)] = SupportPlane{p, other.end + offset * normal, normal, other.vertices, other.weights};
        slack[std::size_t(c)] = gap - offset;
      }
    }
  }
}

}  // namespace

double SelfContact::stopApproach(const PositionRows& x, Eigen::MatrixX3d& v, const Eigen::MatrixX3d& predicted,
                                 double h, const Eigen::VectorXd& masses, const std::vector<int>& fixed,
                                 std::vector<SupportPlane>* supports, const Eigen::Vector3d& fall,
                                 SupportSurfaces where) const {
  if (supports) supports->clear();
  if (surface_.empty()) return 0.0;
  // What the prediction adds to the velocities' path (gravity, the colliders' projection).
  const Eigen::MatrixX3d drift = supports ? Eigen::MatrixX3d(predicted - x - h * v) : Eigen::MatrixX3d();
  const Response response(solid_of_, solids_, x, masses, fixed);
  Motion velocity(response, v);
  bool changed = false;
  const double kinetic_before = kinetic(v, masses);
  const std::vector<ContactEvent> found = events(x, predicted, thickness_);
  for (const ContactEvent& e : found) {
    const double compliance = response.compliance(e, e.normal);
    if (!(compliance > 0.0)) continue;
    double gap = 0.0, path = 0.0;
    for (int k = 0; k < 4; ++k) {
      const int i = e.vertices[std::size_t(k)];
      gap += e.weights[std::size_t(k)] * e.normal.dot(rowOf(x, i));
      path += e.weights[std::size_t(k)] * e.normal.dot(rowOf(predicted, i) - rowOf(x, i));
    }
    const double speed = velocity.along(e);
    // The approach the prediction adds to the velocities' (gravity against a supported body).
    const double drift = path / h - speed;
    // The approach speed that ends the step at the thickness with that drift, never a separating one.
    const double wanted = std::min(0.0, (thickness_ - gap) / h - std::min(drift, 0.0));
    if (!(speed < wanted)) continue;
    velocity.push(e, (wanted - speed) / compliance, e.normal);
    applyFriction(e, friction_, wanted - speed, response, velocity);
    changed = true;
  }
  velocity.settle();
  if (supports) {
    // The step's ends with the stopped velocities; a tet body's as a rigid body's: its fall, less
    // the most the colliders lift one of its particles against it (a bar lying on the ground stays).
    Eigen::MatrixX3d ends = x + h * v + drift;
    const double f = fall.norm();
    for (const std::vector<int>& body : solids_) {
      double lift = 0.0;
      if (f > 0.0)
        for (int i : body) lift = std::max(lift, -(rowOf(drift, i) - fall).dot(fall) / f);
      const Vec3 move = f > 0.0 ? Vec3(fall * (1.0 - lift / f)) : Vec3::Zero();
      for (int i : body) ends.row(i) = x.row(i) + h * v.row(i) + move.transpose();
    }
    // The step's pairs, and those near at its predicted end (a static query at the ends): within
    // the thickness and the fall under gravity over the step, the gap gravity alone closes. (The
    // colliders' wider margin, contact_tolerance more, cost three times as much on a crumpled pile,
    // and pumped the study scene's dragged pile.)
    const double reach = thickness_ + fall.norm();
    if (!(fall.norm() > 0.0)) return changed ? kinetic_before - kinetic(v, masses) : 0.0;  // nothing rests
    std::vector<ContactEvent> pairs = found;
    const double scale = std::max((x.colwise().maxCoeff() - x.colwise().minCoeff()).maxCoeff(), thickness_);
    for (const auto& [p, t] : candidates(ends, ends, nullptr, reach).vertex_triangle)
      supportPairEvent(x, ends, p, surface_.triangles[std::size_t(t)], reach, scale, pairs);
    supportPlanes(pairs, x, ends, thickness_, reach, Vec3(-fall.normalized()), response, where, *supports);
  }
  return changed ? kinetic_before - kinetic(v, masses) : 0.0;
}

double SelfContact::supportFriction(const std::vector<SupportPlane>& supports, const std::vector<double>& impulses,
                                    const PositionRows& x, Eigen::MatrixX3d& v, const Eigen::VectorXd& masses,
                                    const std::vector<int>& fixed) const {
  if (!(friction_ > 0.0) || supports.empty()) return 0.0;
  const Response response(solid_of_, solids_, x, masses, fixed);
  Motion velocity(response, v);
  const double kinetic_before = kinetic(v, masses);
  for (std::size_t i = 0; i < supports.size(); ++i) {
    const SupportPlane& s = supports[i];
    ContactEvent e;
    e.vertices = {s.particle, s.triangle[0], s.triangle[1], s.triangle[2]};
    e.weights = {1.0, -s.bary[0], -s.bary[1], -s.bary[2]};
    e.normal = s.normal;
    applyFriction(e, friction_, impulses[i] * response.inverseMass(s.particle), response, velocity);
  }
  velocity.settle();
  return kinetic_before - kinetic(v, masses);
}

SelfContactResult SelfContact::resolve(const PositionRows& x0, Eigen::MatrixX3d& x1, Eigen::MatrixX3d& v1,
                                       const Eigen::VectorXd& masses, const std::vector<int>& fixed,
                                       const std::function<bool(Eigen::MatrixX3d&)>& keep_out,
                                       const Eigen::Vector3d& up) const {
  SelfContactResult result;
  if (surface_.empty()) return result;
  const Eigen::Index n = x1.rows();
  // The bodies answer about their positions at the step's end, as the solve left them.
  const Eigen::MatrixX3d reference = x1;
  const Response response(solid_of_, solids_, reference, masses, fixed);
  const double kinetic_before = kinetic(v1, masses);

  bool clean = false;
  // The particles the last round moved: a later round checks only their pairs (the others had
  // no event at a stricter threshold and have not changed).
  std::vector<char> moved(static_cast<std::size_t>(n), 0);
  for (int round = 0; round < kRounds && !clean; ++round) {
    // The first round pushes every pair nearer than the thickness out to it; the later ones only
    // those the earlier impulses left at less than half of it, and the crossings.
    const std::vector<ContactEvent> events =
        round == 0 ? this->events(x0, x1, thickness_) : this->events(x0, x1, 0.5 * thickness_, &moved);
    clean = events.empty();
    std::fill(moved.begin(), moved.end(), 0);
    Motion position(response, x1), velocity(response, v1);
    for (const ContactEvent& e : events) {
      const double compliance = response.compliance(e, e.normal);
      if (!(compliance > 0.0)) continue;
      const double gap = position.along(e), speed = velocity.along(e);
      // The positions' push upwards where the pair is stacked and its upper side is not much
      // heavier than its lower one (a cloth under a tet body lying on the ground beside it takes
      // the push, shared by mass, rather than lifting the body at every step).
      const Vec3* stacked = up.isZero() ? nullptr : &up;
      const double push_compliance = stacked ? response.compliance(e, e.normal, stacked) : compliance;
      if (!(push_compliance > 0.0) || push_compliance < 0.5 * (compliance - push_compliance)) stacked = nullptr;
      const double push = gap < thickness_ ? (thickness_ - gap) / (stacked ? push_compliance : compliance) : 0.0;
      const double stop = speed < 0.0 ? -speed / compliance : 0.0;
      if (push == 0.0 && stop == 0.0) continue;
      ++result.events;
      if (push != 0.0) position.push(e, push, e.normal, &moved, stacked);
      if (stop != 0.0) {
        velocity.push(e, stop, e.normal);
        applyFriction(e, friction_, -speed, response, velocity);
      }
      result.positions_moved = result.positions_moved || push != 0.0;
      result.velocities_changed = result.velocities_changed || stop != 0.0;
    }
    position.settle(&moved);
    velocity.settle();
    if (!clean && result.positions_moved && keep_out) {
      const Eigen::MatrixX3d before = x1;
      if (keep_out(x1)) {
        for (Eigen::Index i = 0; i < n; ++i)
          if (x1.row(i) != before.row(i)) moved[std::size_t(i)] = 1;
      }
    }
  }

  // Impact zones: the vertices of the pairs that still cross keep x0 and move on together
  // (mass-weighted mean velocity), zones merging until nothing crosses. A pair whose vertices
  // all keep x0 already is as the last step left it.
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> frozen(static_cast<std::size_t>(n), 0);
  // The first check is of every pair; a later one only of the pairs with a vertex the last
  // zones put back (nothing else moved).
  std::vector<char> put_back;
  while (!clean) {
    bool grew = false;
    const std::vector<char> last = std::move(put_back);
    put_back.assign(static_cast<std::size_t>(n), 0);
    for (const ContactEvent& e : events(x0, x1, 0.0, last.empty() ? nullptr : &last)) {
      if (!e.crossing) continue;
      bool all_frozen = true;
      for (int v : e.vertices) all_frozen = all_frozen && (frozen[std::size_t(v)] || response.inverseMass(v) == 0.0);
      if (all_frozen) continue;
      for (int k = 1; k < 4; ++k)
        parent[std::size_t(findRoot(parent, e.vertices[std::size_t(k)]))] = findRoot(parent, e.vertices[0]);
      // A tet body joins a zone whole (put back in part, its elements would invert).
      const auto freeze = [&](int v) {
        if (frozen[std::size_t(v)]) return;
        frozen[std::size_t(v)] = 1;
        put_back[std::size_t(v)] = 1;
        parent[std::size_t(findRoot(parent, v))] = findRoot(parent, e.vertices[0]);
        grew = true;
      };
      for (int v : e.vertices) {
        freeze(v);
        const int b = solid_of_[std::size_t(v)];
        if (b >= 0)
          for (int u : solids_[std::size_t(b)]) freeze(u);
      }
    }
    if (!grew) break;
    // Each zone's momentum over its movable mass, in vertex order.
    std::vector<Eigen::Vector3d> momentum(static_cast<std::size_t>(n), Eigen::Vector3d::Zero());
    std::vector<double> mass(static_cast<std::size_t>(n), 0.0);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!frozen[std::size_t(i)] || response.inverseMass(static_cast<int>(i)) == 0.0) continue;
      const int r = findRoot(parent, static_cast<int>(i));
      momentum[std::size_t(r)] += masses[i] * v1.row(i).transpose();
      mass[std::size_t(r)] += masses[i];
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!frozen[std::size_t(i)]) continue;
      x1.row(i) = x0.row(i);
      if (response.inverseMass(static_cast<int>(i)) == 0.0) continue;
      const int r = findRoot(parent, static_cast<int>(i));
      v1.row(i) = (momentum[std::size_t(r)] / mass[std::size_t(r)]).transpose();
    }
    result.positions_moved = result.velocities_changed = true;
  }
  result.frozen = static_cast<int>(std::count(frozen.begin(), frozen.end(), 1));
  if (result.velocities_changed) result.kinetic_removed = kinetic_before - kinetic(v1, masses);
  return result;
}

}  // namespace stabint
