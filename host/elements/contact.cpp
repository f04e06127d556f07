// Contact (docs/method.md, "Contact"): one element per (collider, particle) pair, each collider
// with the particles it acts on (every particle of the scene, or its own scene's in a batch),
//   E = w_j/2 |x_j - p_j|^2,   p_j = the closest point of the collider's outside to x_j,
// so E = 0 and p_j = x_j out of contact. A x = x_j (coefficient [1]), w_j = stiffness * m_j for
// the pairs of the contact set (the broad phase of host/contact/ enables them),
// 0 for the others, which then neither enter the global matrix nor pull their particle toward
// its previous iterate. The elements are not a Scene list: they are every collider against its
// particles (firstContactElement numbers them), so this type implements ElementType itself,
// with the generic pass's (kindPass) arithmetic over the pairs of the set. Its params depend on
// time when a collider moves, like a pin's target, and its energy is booked with the pins'
// (EnergyTerm::Pins) so that the forcing rule books a moving collider's work.
#include "elements/contact.hpp"

#include "elements/element_kind.hpp"
#include "elements/energy_sum.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace stabint {

void colliderGeometryAt(const Collider& collider, const Eigen::Vector3d& position, double* g) {
  g[kGeometryShape] = static_cast<double>(static_cast<int>(collider.shape));
  const Eigen::Vector3d& center = position;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  switch (collider.shape) {
    case ColliderShape::Plane: a = collider.normal.normalized(); break;
    case ColliderShape::Box: a = collider.half_extents; break;
    case ColliderShape::Capsule: a = collider.end + (position - collider.center); break;
    case ColliderShape::Sphere: break;
    case ColliderShape::Mesh: break;
  }
  for (int c = 0; c < 3; ++c) g[kGeometryCenter + c] = center[c], g[kGeometryA + c] = a[c];
  // A mesh's pairs in the contact set act with half-spaces only (host/contact/); as a geometry of
  // its own it is a point sphere, which holds nothing.
  g[kGeometryRadius] = collider.shape == ColliderShape::Mesh ? 0.0 : collider.radius;
}

IndexRange colliderParticles(const Scene& scene, int c) {
  const Collider& collider = scene.colliders[static_cast<std::size_t>(c)];
  if (collider.num_particles < 0) return {0, scene.numParticles()};
  return {collider.first_particle, collider.num_particles};
}

int firstContactElement(const Scene& scene, int c) {
  int first = 0;
  for (int i = 0; i < c; ++i) first += colliderParticles(scene, i).count;
  return first;
}

namespace {

using validation::invalid;

// The diagonal of L at each particle from the elements of the internal energy (not the pins,
// not contact): sum over its elements of w_e times the squared coefficients of its column of A_e.
std::vector<double> elasticDiagonal(int n, const std::vector<ElementBlock>& blocks) {
  std::vector<double> diagonal(static_cast<std::size_t>(n), 0.0);
  for (const ElementBlock& block : blocks) {
    if (block.type->term() != EnergyTerm::Internal) continue;
    const ElementShape shape = block.type->shape();
    const std::size_t K = static_cast<std::size_t>(shape.vertices), R = static_cast<std::size_t>(shape.rows);
    const std::size_t P = static_cast<std::size_t>(shape.params);
    for (std::size_t e = 0; e < static_cast<std::size_t>(block.count); ++e) {
      const double w = block.params[P * e];
      const double* a = block.coefficients.data() + (shape.shared_coefficients ? 0 : R * K * e);
      for (std::size_t k = 0; k < K; ++k) {
        double column = 0.0;
        for (std::size_t r = 0; r < R; ++r) column += a[r * K + k] * a[r * K + k];
        diagonal[static_cast<std::size_t>(block.vertices[K * e + k])] += w * column;
      }
    }
  }
  return diagonal;
}

// One vertex, one row, the shared coefficient 1 (A x = x_j).
struct ContactKind {
  static constexpr int kParams = kContactGeometry + kColliderGeometry;  // w_j, the collider's geometry

  static double project(const double* ax, const double* params, double* p) {
    // Out of the contact set (weight 0) the element does nothing: skip the geometry.
    if (params[0] == 0.0) {
      for (int c = 0; c < 3; ++c) p[c] = ax[c];
      return 0.0;
    }
    closestPointOutside(params + kContactGeometry, ax, p);
    return halfWeightedSquaredDistance(params[0], ax, p, 3);
  }
};

// A mesh collider's surface: finite vertices, triangles of three distinct vertices with an area,
// closed and consistently oriented (every edge run once in each direction, by two triangles),
// enclosing a positive volume (counter-clockwise seen from outside), so that its inside is defined.
void checkMesh(const Collider& c, const validation::Owner& owner) {
  const Eigen::MatrixX3d& v = c.mesh_vertices;
  const auto& triangles = c.mesh_triangles;
  if (v.rows() < 4 || triangles.size() < 4)
    invalid(owner, ": a mesh needs at least 4 vertices and 4 triangles (it has ", v.rows(), " and ", triangles.size(),
            ")");
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const Eigen::Vector3d p = v.row(i).transpose();
    if (!p.allFinite() || !(p.cwiseAbs().maxCoeff() <= validation::kMaxMagnitude))
      invalid(owner, ": mesh_vertices[", i, "] ", validation::vec(p), " is not finite or exceeds ",
              validation::kMaxMagnitude);
  }
  const int n = static_cast<int>(v.rows());
  std::map<std::pair<int, int>, int> directed;  // edge -> how many triangles run it that way
  double volume = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::array<int, 3>& f = triangles[t];
    for (int k = 0; k < 3; ++k) validation::checkIndex(f[k], n, owner, "mesh_triangles", long(3 * t + k));
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])
      invalid(owner, ": mesh_triangles[", t, "] repeats a vertex (", f[0], ", ", f[1], ", ", f[2], ")");
    const Eigen::Vector3d a = v.row(f[0]).transpose(), b = v.row(f[1]).transpose(), d = v.row(f[2]).transpose();
    const double scale = std::max({(b - a).squaredNorm(), (d - a).squaredNorm(), (d - b).squaredNorm()});
    if (!((b - a).cross(d - a).squaredNorm() > 1e-24 * scale * scale))
      invalid(owner, ": mesh_triangles[", t, "] has no area");
    volume += a.dot(b.cross(d)) / 6.0;
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    const auto back = directed.find({edge.second, edge.first});
    if (count != 1 || back == directed.end() || back->second != 1)
      invalid(owner, ": the mesh is not a closed, consistently oriented surface at its edge (", edge.first, ", ",
              edge.second, "): ", count, " triangle(s) run it that way and ", back == directed.end() ? 0 : back->second,
              " the other way (each edge must be run once each way)");
  }
  if (!(volume > 0.0))
    invalid(owner, ": the mesh encloses a volume of ", volume,
            " (its triangles must run counter-clockwise seen from outside)");
}

void checkCollider(const Scene& scene, const Collider& c, const validation::Owner& owner) {
  const int shape = static_cast<int>(c.shape);
  if (shape < 0 || shape >= kColliderShapeCount) invalid(owner, ": shape ", shape, " is not a ColliderShape value");
  validation::checkFinite(c.center, owner, "center");
  validation::checkFinite(c.velocity, owner, "velocity");
  if (!std::isfinite(c.friction) || !(c.friction >= 0.0) || !(c.friction <= validation::kMaxMagnitude))
    invalid(owner, ": friction ", c.friction, " must be finite and >= 0");
  if (!std::isfinite(c.stiffness) || !(c.stiffness > 0.0) || !(c.stiffness <= validation::kMaxMagnitude))
    invalid(owner, ": stiffness ", c.stiffness, " must be finite and > 0");
  if (!std::isfinite(c.elastic_ratio) || !(c.elastic_ratio >= 0.0) || !(c.elastic_ratio <= validation::kMaxMagnitude))
    invalid(owner, ": elastic_ratio ", c.elastic_ratio, " must be finite and >= 0");
  if (!(c.restitution >= 0.0) || !(c.restitution <= 1.0))
    invalid(owner, ": restitution ", c.restitution, " must be in [0, 1]");
  // w_j = stiffness m_j enters the global matrix: it must be a finite number for every particle.
  if (scene.masses.size() > 0 && !std::isfinite(c.stiffness * scene.masses.maxCoeff()))
    invalid(owner, ": stiffness ", c.stiffness, " times the largest mass is not finite");
  const int n = scene.numParticles();
  const bool all_particles = c.num_particles == -1;
  if (!all_particles && (c.num_particles < 0 || c.first_particle < 0 || c.first_particle > n - c.num_particles))
    invalid(owner, ": first_particle ", c.first_particle, " and num_particles ", c.num_particles,
            " do not name particles of the scene's ", n, " (num_particles -1: every particle)");
  switch (c.shape) {
    case ColliderShape::Plane:
      validation::checkFinite(c.normal, owner, "normal");
      if (!(c.normal.norm() > 0.0)) invalid(owner, ": normal ", validation::vec(c.normal), " of the plane is zero");
      break;
    case ColliderShape::Box:
      validation::checkFinite(c.half_extents, owner, "half_extents");
      if (!(c.half_extents.minCoeff() > 0.0))
        invalid(owner, ": half_extents ", validation::vec(c.half_extents), " of the box must be > 0");
      break;
    case ColliderShape::Mesh: checkMesh(c, owner); break;
    case ColliderShape::Capsule: validation::checkFinite(c.end, owner, "end"); [[fallthrough]];
    case ColliderShape::Sphere:
      validation::checkFinite(c.radius, owner, "radius");
      if (!(c.radius > 0.0))
        invalid(owner, ": radius ", c.radius, " of the ", colliderShapeName(c.shape), " must be > 0");
      break;
  }
}

class ContactElementType final : public ElementType {
  static constexpr int P = ContactKind::kParams;

 public:
  const char* name() const override { return "contact"; }
  const char* identifier() const override { return "contact"; }
  ElementShape shape() const override { return {1, 1, P, true}; }
  std::vector<double> sharedCoefficients() const override { return {1.0}; }
  EnergyTerm term() const override { return EnergyTerm::Pins; }

  int count(const Scene& scene) const override {
    return firstContactElement(scene, static_cast<int>(scene.colliders.size()));
  }

  void validate(const Scene& scene) const override {
    for (std::size_t i = 0; i < scene.colliders.size(); ++i)
      checkCollider(scene, scene.colliders[i], validation::Owner{"collider", i});
  }

  // Collider by collider, each over its particles (firstContactElement).
  ElementBlock build(const Scene& scene) const override {
    ElementBlock block;
    block.type = this;
    block.count = count(scene);
    block.coefficients = {1.0};
    block.vertices.reserve(block.count);
    for (std::size_t c = 0; c < scene.colliders.size(); ++c) {
      const IndexRange particles = colliderParticles(scene, static_cast<int>(c));
      for (int j = particles.first; j < particles.end(); ++j) block.vertices.push_back(j);
    }
    writeParams(scene, block.params);
    return block;
  }

  bool timeDependent(const RunningScene& data) const override { return data.hasMovingColliders(); }
  // The scene's params (weights, and each pair's geometry where the collider's reference point is
  // at Collider::center) with every pair's geometry moved by its collider's translation at t.
  void paramsAt(const RunningScene& data, double t, std::vector<double>& params) const override {
    const Scene& scene = data.scene();
    params = data.blockParams(data.blockIndex(*this));
    double* out = params.data();
    for (int c = 0; c < static_cast<int>(scene.colliders.size()); ++c) {
      const Eigen::Vector3d shift = data.colliderPosition(c, t) - scene.colliders[static_cast<std::size_t>(c)].center;
      for (int k = 0; k < colliderParticles(scene, c).count; ++k, out += P)
        translateGeometry(shift, out + kContactGeometry);
    }
  }

  // [project rule] w_j = stiffness m_j + elastic_ratio D_j, D_j the diagonal of L at the
  // particle from the elements of the internal energy (docs/method.md, "Contact", "The contact
  // weight"): with the default ratio 1 a pair is at least as stiff as the elements that press its
  // particle into the collider, so a heavy or stiff body stops on its contact layer within the
  // step instead of sinking into the collider (where the final projection then crushed the
  // layer). Computed once, from the scene's elements as built: a run-time stiffness change does
  // not move it, so a checkpoint's restore rebuilds the same weights.
  std::vector<double> weightsFromBlocks(const Scene& scene, const std::vector<ElementBlock>& blocks) const override {
    const std::vector<double> diagonal = elasticDiagonal(scene.numParticles(), blocks);
    std::vector<double> weights(static_cast<std::size_t>(count(scene)));
    std::size_t e = 0;
    for (std::size_t c = 0; c < scene.colliders.size(); ++c) {
      const IndexRange particles = colliderParticles(scene, static_cast<int>(c));
      for (int j = particles.first; j < particles.end(); ++j, ++e) {
        const Collider& collider = scene.colliders[c];
        weights[e] =
            collider.stiffness * scene.masses[j] + collider.elastic_ratio * diagonal[static_cast<std::size_t>(j)];
        if (!std::isfinite(weights[e]))
          invalid(validation::Owner{"collider", c}, ": its contact weight at particle ", j, " (stiffness ",
                  collider.stiffness, ", elastic_ratio ", collider.elastic_ratio, ", element stiffness ",
                  diagonal[static_cast<std::size_t>(j)], ") is not finite");
      }
    }
    return weights;
  }

  // The params of pair e as build() writes them (SceneData::setElementEnabled puts them back when
  // the pair enters the contact set).
  // (A walk over the colliders: a contact set change enters pairs one by one, and batches have
  // one or two colliders per scene.)
  void elementParams(const Scene& scene, int e, double* params) const override {
    int c = 0;
    IndexRange particles = colliderParticles(scene, 0);
    for (; e >= particles.count; particles = colliderParticles(scene, ++c)) e -= particles.count;
    const Collider& collider = scene.colliders[static_cast<std::size_t>(c)];
    params[0] = 0.0;  // the weight is SceneData's, from weightsFromBlocks
    colliderGeometryAt(collider, collider.center, params + kContactGeometry);
  }

  // A part's colliders act on the part's particles only, shifted with them: in a batch
  // (concatenateScenes) one scene's colliders must not touch another scene's particles.
  void appendShifted(Scene& into, const Scene& part, int offset) const override {
    for (std::size_t c = 0; c < part.colliders.size(); ++c) {
      Collider collider = part.colliders[c];
      const IndexRange particles = colliderParticles(part, static_cast<int>(c));
      collider.first_particle = particles.first + offset;
      collider.num_particles = particles.count;
      into.colliders.push_back(collider);
    }
  }

  double project(const double* ax, const double* params, double* p) const override {
    return ContactKind::project(ax, params, p);
  }
  // kindPass's arithmetic (bit for bit) for the pairs of the contact set only: the others, weight
  // 0 and most of them, add nothing.
  double passRange(const ElementBlock& block, const std::vector<double>& params, const Eigen::MatrixX3d& x, int first,
                   int count, int flags, Eigen::MatrixX3d* out) const override {
    const bool write = (flags & (kPassProjection | kPassForce)) != 0;
    const bool force = (flags & kPassForce) != 0;
    const Eigen::Index n = x.rows();
    const double* xs = x.data();
    double* os = write ? out->data() : nullptr;
    EnergySum energy;
    for (int e = first; e < first + count; ++e) {
      const double* prm = params.data() + std::size_t(P) * std::size_t(e);
      const double w = prm[0];
      if (w == 0.0) continue;
      const int j = block.vertices[std::size_t(e)];
      const double ax[3] = {xs[j], xs[n + j], xs[2 * n + j]};
      double p[3];
      const double element_energy = ContactKind::project(ax, prm, p);
      if (flags & kPassEnergy) energy.add(e - first, element_energy);
      if (!write) continue;
      for (int i = 0; i < 3; ++i) p[i] = w * (force ? p[i] - ax[i] : p[i]);
      os[j] += p[0];
      os[n + j] += p[1];
      os[2 * n + j] += p[2];
    }
    return energy.total();
  }

  // Colliders have their own JSON form (host/io/json/scene_reader.cpp, scene_writer.cpp).
  std::vector<Field> jsonFields() const override { return {}; }
  void record(const Scene&, int, std::vector<int>&, std::vector<double>&) const override {}
  void appendRecord(Scene&, const std::vector<int>&, const std::vector<double>&) const override {}

 private:
  // Each pair with its collider's geometry where the scene puts it, and weight 0: the weights
  // depend on the other types' elements, so SceneData puts them in (weightsFromBlocks).
  static void writeParams(const Scene& scene, std::vector<double>& params) {
    const int colliders = static_cast<int>(scene.colliders.size());
    params.resize(std::size_t(P) * std::size_t(firstContactElement(scene, colliders)));
    double* out = params.data();
    for (int c = 0; c < colliders; ++c) {
      const Collider& collider = scene.colliders[static_cast<std::size_t>(c)];
      double geometry[kColliderGeometry];
      colliderGeometryAt(collider, collider.center, geometry);
      const IndexRange particles = colliderParticles(scene, c);
      for (int j = particles.first; j < particles.end(); ++j, out += P) {
        out[0] = 0.0;
        for (int i = 0; i < kColliderGeometry; ++i) out[kContactGeometry + i] = geometry[i];
      }
    }
  }
};

}  // namespace

const ElementType& contactElementType() {
  static const ContactElementType type;
  return type;
}

}  // namespace stabint
