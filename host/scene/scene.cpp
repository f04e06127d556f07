// Scene model: pin and force-field time laws, validation, and the geometric helpers builders and
// loaders share (rest volumes, mass lumping, cloth springs).
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>

#include "elements/element_type.hpp"
#include "scene/lumping.hpp"
#include "common/validation.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <map>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace stabint {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

bool isZero(const Eigen::Vector3d& v) { return (v.array() == 0.0).all(); }

// Oscillation with a zero amplitude or a zero frequency contributes nothing at any t.
bool oscillates(const Eigen::Vector3d& amplitude, double frequency) { return frequency != 0.0 && !isZero(amplitude); }

}  // namespace

Eigen::Vector3d PinTarget::at(double t) const {
  return position + velocity * t + amplitude * std::sin(kTwoPi * frequency * t);
}

bool PinTarget::moving() const { return !isZero(velocity) || oscillates(amplitude, frequency); }

Eigen::Vector3d ForceField::at(double t) const {
  return force + rate * t + amplitude * std::sin(kTwoPi * frequency * t);
}

bool ForceField::timeDependent() const { return !isZero(rate) || oscillates(amplitude, frequency); }

// --- validation ---------------------------------------------------------------------------------

namespace {

using validation::checkFinite;
using validation::checkIndex;
using validation::invalid;
using validation::Owner;
using validation::vec;

void checkRows(const Eigen::MatrixX3d& m, const char* name) {
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if (!m.row(i).allFinite()) invalid(name, " row ", i, " is not finite");
    if (!(m.row(i).cwiseAbs().maxCoeff() <= validation::kMaxMagnitude)) {
      invalid(name, " row ", i, " ", vec(m.row(i).transpose()), " exceeds ", validation::kMaxMagnitude,
              " in magnitude");
    }
  }
}

void checkParticles(const Scene& s) {
  const int n = s.numParticles();
  if (n == 0) invalid("scene '", s.name, "' has no particles (positions has 0 rows)");
  if (s.rest_positions.rows() != n) {
    invalid("rest_positions has ", s.rest_positions.rows(), " rows but positions has ", n);
  }
  if (s.velocities.rows() != n) {
    invalid("velocities has ", s.velocities.rows(), " rows but positions has ", n);
  }
  if (s.masses.size() != n) invalid("masses has ", s.masses.size(), " entries but positions has ", n, " rows");
  checkRows(s.positions, "positions");
  checkRows(s.rest_positions, "rest_positions");
  checkRows(s.velocities, "velocities");
  for (int j = 0; j < n; ++j) {
    const double m = s.masses[j];
    if (!(m > 0.0) || !std::isfinite(m)) invalid("masses[", j, "] = ", m, " must be > 0 and finite");
  }
  if (!s.gravity.allFinite()) invalid("gravity ", vec(s.gravity), " is not finite");
  if (!(s.gravity.cwiseAbs().maxCoeff() <= validation::kMaxMagnitude)) {
    invalid("gravity ", vec(s.gravity), " exceeds ", validation::kMaxMagnitude, " in magnitude");
  }
}

// Diagonal of the box around the positions, rest positions and pin targets: the largest
// distance a force acts over in the scene.
double sceneSize(const Scene& s) {
  Eigen::Vector3d lo = s.positions.colwise().minCoeff().cwiseMin(s.rest_positions.colwise().minCoeff()).transpose();
  Eigen::Vector3d hi = s.positions.colwise().maxCoeff().cwiseMax(s.rest_positions.colwise().maxCoeff()).transpose();
  for (const Pin& pin : s.pins) {
    lo = lo.cwiseMin(pin.target.position - pin.target.amplitude.cwiseAbs());
    hi = hi.cwiseMax(pin.target.position + pin.target.amplitude.cwiseAbs());
  }
  return (hi - lo).norm();
}

// The energy a scene holds or can exchange must be finite: 0.5 m |v|^2 per particle and in all,
// the work of gravity M |g| size, and k L^2 of each spring and pin over L = its rest length or
// the scene's size. Each value may be within kMaxMagnitude and their product still overflow
// (mass 1e308 at speed 1e10): such a scene failed its first step as a "blow-up".
void checkEnergyScale(const Scene& s) {
  double kinetic = 0.0, total_mass = 0.0;
  for (int j = 0; j < s.numParticles(); ++j) {
    const double m = s.masses[j], speed = s.velocities.row(j).norm();
    const double k = 0.5 * m * speed * speed;
    if (!std::isfinite(k)) {
      invalid("particle ", j, ": kinetic energy 0.5 m |v|^2 of masses[", j, "] = ", m, " at speed ", speed,
              " overflows");
    }
    kinetic += k;
    total_mass += m;
  }
  if (!std::isfinite(kinetic)) invalid("the total kinetic energy 0.5 sum m |v|^2 of masses and velocities overflows");
  if (!std::isfinite(total_mass)) invalid("the total of masses overflows");
  const double size = sceneSize(s);
  const double g = s.gravity.norm();
  if (!std::isfinite(total_mass * g * size)) {
    invalid("gravity ", vec(s.gravity), ": the work it can do, total mass ", total_mass, " x |g| x scene size ", size,
            " overflows");
  }
  const auto checkWork = [](double k, double length, const Owner& owner, const char* length_is) {
    if (!std::isfinite(k * length * length)) {
      invalid(owner, ": energy k L^2 of stiffness ", k, " over ", length_is, " L = ", length, " overflows");
    }
  };
  for (size_t i = 0; i < s.springs.size(); ++i) {
    checkWork(s.springs[i].stiffness, std::max(s.springs[i].rest_length, size), Owner{"spring", i},
              "the larger of rest length and scene size");
  }
  for (size_t i = 0; i < s.pins.size(); ++i) checkWork(s.pins[i].stiffness, size, Owner{"pin", i}, "the scene size");
  // A collider's weight is stiffness m_j (1/s^2 times kg): the heaviest particle's, as deep as
  // the scene is large.
  const double heaviest = s.numParticles() > 0 ? s.masses.maxCoeff() : 0.0;
  for (size_t i = 0; i < s.colliders.size(); ++i)
    checkWork(s.colliders[i].stiffness * heaviest, size, Owner{"collider", i}, "the scene size");
}

void checkSurface(const Scene& s) {
  for (size_t i = 0; i < s.triangles.size(); ++i) {
    for (long k = 0; k < 3; ++k) checkIndex(s.triangles[i][k], s.numParticles(), Owner{"triangle", i}, "vertices", k);
  }
}

void checkForceFields(const Scene& s) {
  const int n = s.numParticles();
  for (size_t i = 0; i < s.force_fields.size(); ++i) {
    const ForceField& f = s.force_fields[i];
    const Owner owner{"force field", i};
    for (size_t k = 0; k < f.particles.size(); ++k) {
      checkIndex(f.particles[k], n, owner, "particles", static_cast<long>(k));
    }
    checkFinite(f.force, owner, "force");
    checkFinite(f.rate, owner, "rate");
    checkFinite(f.amplitude, owner, "amplitude");
    checkFinite(f.frequency, owner, "frequency");
  }
}

void checkBodies(const Scene& s) {
  const int n = s.numParticles();
  for (size_t i = 0; i < s.bodies.size(); ++i) {
    const Body& body = s.bodies[i];
    const Owner owner{"body", i, &body.name};
    if (!(body.damping >= 0.0 && body.damping <= 1.0)) {
      invalid(owner, ": damping ", body.damping, " outside [0, 1]");
    }
    for (size_t k = 0; k < body.particles.size(); ++k) {
      checkIndex(body.particles[k], n, owner, "particles", static_cast<long>(k));
    }
    // A particle listed twice would count twice in the body's momentum and inertia.
    std::vector<int> sorted = body.particles;
    std::sort(sorted.begin(), sorted.end());
    const auto dup = std::adjacent_find(sorted.begin(), sorted.end());
    if (dup != sorted.end()) invalid(owner, ": particle ", *dup, " listed twice");
  }
}

}  // namespace

void validateScene(const Scene& scene) {
  // Particle data first: every later check indexes into it.
  checkParticles(scene);
  for (const ElementType* type : elementTypes()) type->validate(scene);
  checkSurface(scene);
  checkForceFields(scene);
  checkBodies(scene);
  checkEnergyScale(scene);
}

int elementCount(const Scene& scene) {
  int count = 0;
  for (const ElementType* type : elementTypes()) count += type->count(scene);
  return count;
}

std::string elementSummary(const Scene& scene) {
  std::string out;
  for (const ElementType* type : elementTypes()) {
    const int count = type->count(scene);
    if (count == 0) continue;
    out += (out.empty() ? "" : ", ") + std::to_string(count) + " " + type->name() + (count == 1 ? "" : "s");
  }
  return out.empty() ? "no elements" : out;
}

// --- geometry -----------------------------------------------------------------------------------

double signedVolume(const Eigen::MatrixX3d& rest_positions, const std::array<int, 4>& v) {
  const Eigen::Vector3d x0 = rest_positions.row(v[0]).transpose();
  Eigen::Matrix3d dm;
  dm.col(0) = rest_positions.row(v[1]).transpose() - x0;
  dm.col(1) = rest_positions.row(v[2]).transpose() - x0;
  dm.col(2) = rest_positions.row(v[3]).transpose() - x0;
  return dm.determinant() / 6.0;
}

namespace {

template <size_t K>
void checkElementIndices(const std::array<int, K>& element, Eigen::Index n, const char* kind, size_t i) {
  for (int v : element) {
    if (v < 0 || v >= n) invalid(kind, " ", i, ": index ", v, " out of range [0, ", n, ")");
  }
}

// Lumping leaves particles that no element touches at zero; they still need a positive mass.
Eigen::VectorXd withMinimumMass(Eigen::VectorXd masses, double min_mass) {
  for (Eigen::Index j = 0; j < masses.size(); ++j) {
    if (masses[j] == 0.0) masses[j] = min_mass;
  }
  return masses;
}

// Adds density |measure(e)| / K of each element e to its K vertices.
template <std::size_t K, typename Vertices, typename Measure>
std::optional<lumping::Failure> addShares(std::size_t count, Vertices vertices, Measure measure, double density,
                                          const char* density_name, const char* measured, Eigen::VectorXd& masses) {
  for (std::size_t i = 0; i < count; ++i) {
    const std::array<int, K>& v = vertices(i);
    // Mass is a property of the shape, not of its vertex order: |V|, so that an inverted tet is
    // reported by validation as inverted rather than as a negative mass.
    const double size = std::abs(measure(v));
    const double share = density * (size / static_cast<double>(K));  // divided first: no overflow on the way
    const auto failure = [&](const std::string& happened) {
      return lumping::Failure{i, validation::cat("mass share ", density_name, " ", density, " x ", measured, " ", size,
                                                 " / ", K, " ", happened)};
    };
    if (!std::isfinite(share)) return failure("is not finite");
    if (share == 0.0 && size != 0.0) return failure("underflows to 0");
    for (const int j : v) {
      if (!std::isfinite(masses[j] + share)) {
        return lumping::Failure{i, validation::cat("the lumped mass of particle ", j, " overflows when its share ",
                                                   share, " is added to ", masses[j])};
      }
      masses[j] += share;
    }
  }
  return std::nullopt;
}

double triangleArea(const Eigen::MatrixX3d& x, const std::array<int, 3>& t) {
  const Eigen::Vector3d e1 = (x.row(t[1]) - x.row(t[0])).transpose();
  const Eigen::Vector3d e2 = (x.row(t[2]) - x.row(t[0])).transpose();
  return 0.5 * e1.cross(e2).norm();
}

}  // namespace

std::optional<lumping::Failure> lumping::addTets(const Eigen::MatrixX3d& rest_positions, const std::vector<Tet>& tets,
                                                 double density, const char* density_name, Eigen::VectorXd& masses) {
  return addShares<4>(
      tets.size(), [&](std::size_t i) -> const std::array<int, 4>& { return tets[i].vertices; },
      [&](const std::array<int, 4>& v) { return signedVolume(rest_positions, v); }, density, density_name, "volume",
      masses);
}

std::optional<lumping::Failure> lumping::addTriangles(const Eigen::MatrixX3d& rest_positions,
                                                      const std::vector<std::array<int, 3>>& triangles,
                                                      double areal_density, const char* density_name,
                                                      Eigen::VectorXd& masses) {
  return addShares<3>(
      triangles.size(), [&](std::size_t i) -> const std::array<int, 3>& { return triangles[i]; },
      [&](const std::array<int, 3>& t) { return triangleArea(rest_positions, t); }, areal_density, density_name, "area",
      masses);
}

Eigen::VectorXd lumpMassesFromTets(const Eigen::MatrixX3d& rest_positions, const std::vector<Tet>& tets, double density,
                                   double min_mass) {
  for (size_t i = 0; i < tets.size(); ++i) checkElementIndices(tets[i].vertices, rest_positions.rows(), "tet", i);
  validation::checkDensity(density, "density");
  Eigen::VectorXd masses = Eigen::VectorXd::Zero(rest_positions.rows());
  if (const auto failure = lumping::addTets(rest_positions, tets, density, "density", masses)) {
    invalid("tet ", failure->element, ": ", failure->what);
  }
  return withMinimumMass(std::move(masses), min_mass);
}

std::vector<std::array<int, 3>> tetSurface(const std::vector<Tet>& tets) {
  // For a positive tet (0, 1, 2, 3) the outward faces are (0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3).
  static constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> seen;  // sorted corners -> count, wound face
  for (const Tet& t : tets) {
    for (const auto& f : kFaces) {
      const std::array<int, 3> face{t.vertices[f[0]], t.vertices[f[1]], t.vertices[f[2]]};
      std::array<int, 3> key = face;
      std::sort(key.begin(), key.end());
      auto& entry = seen[key];
      ++entry.first;
      entry.second = face;
    }
  }
  std::vector<std::array<int, 3>> surface;
  for (const auto& [key, entry] : seen)
    if (entry.first == 1) surface.push_back(entry.second);
  return surface;
}

Eigen::VectorXd lumpMassesFromTriangles(const Eigen::MatrixX3d& rest_positions,
                                        const std::vector<std::array<int, 3>>& triangles, double areal_density,
                                        double min_mass) {
  for (size_t i = 0; i < triangles.size(); ++i) checkElementIndices(triangles[i], rest_positions.rows(), "triangle", i);
  validation::checkDensity(areal_density, "areal_density");
  // A flat triangle lumps no mass: its corners would get min_mass, a made-up mass, and a cloth
  // builder given width 0 stepped particles of 1e-6 kg on zero-length springs.
  for (size_t i = 0; i < triangles.size(); ++i) {
    const std::array<int, 3>& t = triangles[i];
    validation::checkRestTriangle(rest_positions, t[0], t[1], t[2], validation::Owner{"triangle", i});
  }
  Eigen::VectorXd masses = Eigen::VectorXd::Zero(rest_positions.rows());
  if (const auto failure = lumping::addTriangles(rest_positions, triangles, areal_density, "areal_density", masses)) {
    invalid("triangle ", failure->element, ": ", failure->what);
  }
  return withMinimumMass(std::move(masses), min_mass);
}

namespace {

// One (edge, opposite vertex) incidence of a triangle mesh.
struct Incidence {
  int lo, hi, opposite;
  bool operator<(const Incidence& o) const { return std::tie(lo, hi, opposite) < std::tie(o.lo, o.hi, o.opposite); }
};

// Every incidence, sorted by edge: equal edges become adjacent, and the order does not depend on
// the triangle order.
std::vector<Incidence> edgeIncidences(const std::vector<std::array<int, 3>>& triangles) {
  std::vector<Incidence> incidences;
  incidences.reserve(3 * triangles.size());
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      if (a == b) continue;  // a degenerate triangle has no such edge
      incidences.push_back({std::min(a, b), std::max(a, b), c});
    }
  }
  std::sort(incidences.begin(), incidences.end());
  return incidences;
}

// Calls visit(first, count) for the incidences [first, first + count) of each edge.
template <typename Visit>
void forEachEdge(const std::vector<Incidence>& incidences, Visit visit) {
  for (size_t i = 0; i < incidences.size();) {
    size_t end = i;
    while (end < incidences.size() && incidences[end].lo == incidences[i].lo &&
           incidences[end].hi == incidences[i].hi) {
      ++end;
    }
    visit(&incidences[i], end - i);
    i = end;
  }
}

// Only a manifold interior edge (exactly two triangles, distinct opposite vertices) has a
// well-defined hinge.
bool isHinge(const Incidence* edge, size_t count) { return count == 2 && edge[0].opposite != edge[1].opposite; }

}  // namespace

std::vector<Spring> clothSpringsFromTriangles(const Eigen::MatrixX3d& rest_positions,
                                              const std::vector<std::array<int, 3>>& triangles,
                                              double stretch_stiffness, double bend_stiffness) {
  for (size_t i = 0; i < triangles.size(); ++i) checkElementIndices(triangles[i], rest_positions.rows(), "triangle", i);
  const std::vector<Incidence> incidences = edgeIncidences(triangles);
  const auto spring = [&](int a, int b, double k) {
    return Spring{a, b, (rest_positions.row(a) - rest_positions.row(b)).norm(), k};
  };
  std::vector<Spring> structural;
  std::vector<std::pair<int, int>> bending_pairs;
  forEachEdge(incidences, [&](const Incidence* edge, size_t count) {
    structural.push_back(spring(edge->lo, edge->hi, stretch_stiffness));
    if (isHinge(edge, count)) {
      const int p = edge[0].opposite, q = edge[1].opposite;
      bending_pairs.emplace_back(std::min(p, q), std::max(p, q));
    }
  });

  // A bending pair can coincide with an existing edge or with another hinge's pair on coarse or
  // irregular meshes; a second spring there would just double that stiffness.
  std::sort(bending_pairs.begin(), bending_pairs.end());
  bending_pairs.erase(std::unique(bending_pairs.begin(), bending_pairs.end()), bending_pairs.end());
  std::vector<Spring> springs = structural;
  for (const auto& [p, q] : bending_pairs) {
    const bool is_edge = std::binary_search(
        incidences.begin(), incidences.end(), Incidence{p, q, -1},
        [](const Incidence& x, const Incidence& y) { return std::tie(x.lo, x.hi) < std::tie(y.lo, y.hi); });
    if (!is_edge) springs.push_back(spring(p, q, bend_stiffness));
  }
  return springs;
}

void addTriangleClothElements(Scene& scene, double strain_stiffness, double strain_min, double strain_max,
                              double hinge_stiffness) {
  for (const TriangleStrain& t :
       triangleStrainsFromTriangles(scene.triangles, strain_stiffness, strain_min, strain_max)) {
    scene.triangle_strains.push_back(t);
  }
  for (const BendingHinge& h : bendingHingesFromTriangles(scene.triangles, hinge_stiffness))
    scene.bending_hinges.push_back(h);
}

std::vector<TriangleStrain> triangleStrainsFromTriangles(const std::vector<std::array<int, 3>>& triangles,
                                                         double stiffness, double strain_min, double strain_max) {
  std::vector<TriangleStrain> out;
  out.reserve(triangles.size());
  for (const auto& t : triangles) out.push_back(TriangleStrain{t, stiffness, strain_min, strain_max});
  return out;
}

std::vector<BendingHinge> bendingHingesFromTriangles(const std::vector<std::array<int, 3>>& triangles,
                                                     double stiffness) {
  std::vector<BendingHinge> hinges;
  forEachEdge(edgeIncidences(triangles), [&](const Incidence* edge, size_t count) {
    if (isHinge(edge, count))
      hinges.push_back(BendingHinge{{edge->lo, edge->hi, edge[0].opposite, edge[1].opposite}, stiffness});
  });
  return hinges;
}

}  // namespace stabint
