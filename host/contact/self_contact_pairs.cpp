// Finding the pairs of self-contact (docs/method.md, "Self-contact"): the surface's primitives,
// the broad phase over swept boxes in a moving frame, and the narrow phase's events.
#include "contact/self_contact.hpp"

#include "common/worker_pool.hpp"
#include "contact/box_grid.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
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

}  // namespace stabint
