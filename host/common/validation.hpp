#pragma once
// The checks validateScene and the element types share, each throwing InvalidInputError with a
// message that names the element or field ("spring 12: stiffness -1 must be >= 0").
#include <stabint/errors.hpp>
#include <stabint/scene.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <ostream>
#include <sstream>
#include <string>

namespace stabint::validation {

/// Concatenates anything streamable; doubles print with 6 significant digits, which is enough to
/// recognise the offending value in a message.
template <typename... Args>
std::string cat(const Args&... args) {
  std::ostringstream s;
  (s << ... << args);
  return s.str();
}

template <typename... Args>
[[noreturn]] void invalid(const Args&... args) {
  throw InvalidInputError(cat(args...));
}

inline std::string vec(const Eigen::Vector3d& v) { return cat("(", v.x(), ", ", v.y(), ", ", v.z(), ")"); }

/// Names an element in messages ("spring 12", "body 'cloth'"). Streamed only when a check
/// fails, so validating a large scene builds no strings.
struct Owner {
  const char* kind;
  std::size_t index;
  const std::string* label = nullptr;  // bodies are known to users by name, when they have one
};

inline std::ostream& operator<<(std::ostream& s, const Owner& o) {
  if (o.label && !o.label->empty()) return s << o.kind << " '" << *o.label << "'";
  return s << o.kind << " " << o.index;
}

/// `field` is a member name; `subscript` >= 0 makes it a list entry, e.g. "particles[3]".
inline void checkIndex(int index, int n, const Owner& owner, const char* field, long subscript = -1) {
  if (index < 0 || index >= n) {
    if (subscript >= 0) invalid(owner, ": index ", field, "[", subscript, "] = ", index, " out of range [0, ", n, ")");
    invalid(owner, ": index ", field, " = ", index, " out of range [0, ", n, ")");
  }
}

/// NaN fails every comparison, so `!(k >= 0)` rejects it along with negatives.

/// Largest magnitude of a quantity that the simulation squares or multiplies by a time or a
/// stiffness (coordinates, speeds, gravity, rest lengths, pin and force targets, frequencies), so
/// that squares and their sums stay finite. Finite inputs beyond it (a rest length of 1e200, a
/// frequency of 1e308) overflowed in the first step and were reported as a blow-up.
constexpr double kMaxMagnitude = 1e150;

/// An element's or a pin's stiffness: >= 0 and at most kMaxMagnitude, the one rule every path
/// keeps (the scene, per-frame input, a checkpoint, which holds no larger real), so that every
/// simulator that runs saves a checkpoint it can load again.
inline void checkStiffness(double k, const Owner& owner) {
  if (!(k >= 0.0) || !std::isfinite(k)) invalid(owner, ": stiffness ", k, " must be >= 0");
  if (!(k <= kMaxMagnitude))
    invalid(owner, ": stiffness ", k, " exceeds ", kMaxMagnitude, " (every stiffness's bound)");
}

/// Finite and at most kMaxMagnitude in each component.
inline void checkFinite(const Eigen::Vector3d& v, const Owner& owner, const char* field) {
  if (!v.allFinite()) invalid(owner, ": ", field, " ", vec(v), " is not finite");
  if (!(v.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
    invalid(owner, ": ", field, " ", vec(v), " exceeds ", kMaxMagnitude, " in magnitude");
  }
}

inline void checkFinite(double x, const Owner& owner, const char* field) {
  if (!std::isfinite(x)) invalid(owner, ": ", field, " ", x, " is not finite");
  if (!(std::abs(x) <= kMaxMagnitude)) invalid(owner, ": ", field, " ", x, " exceeds ", kMaxMagnitude, " in magnitude");
}

/// The same bound on a device that computes in float: its squares (1e30) times a stiffness or a
/// mass of up to 1e8 stay within float's 3.4e38. Beyond it a per-frame value (setPinTarget at
/// 1e150, setVelocities at 1e100) overflowed the device and every later step was refused.
constexpr double kMaxMagnitudeFloat = 1e15;

/// Per-frame input (positions, velocities, external forces of a running simulation): `expected`
/// rows, each finite and at most `limit` (kMaxMagnitude, or kMaxMagnitudeFloat on a float
/// device) in magnitude. `what` prefixes the message ("setState: scene 2: positions").
inline void checkInputRows(const Eigen::MatrixX3d& m, long expected, const std::string& what,
                           double limit = kMaxMagnitude) {
  if (m.rows() != expected)
    throw InvalidInputError(cat(what, ": ", m.rows(), " rows, expected one per particle (", expected, ")"));
  for (Eigen::Index j = 0; j < m.rows(); ++j) {
    const Eigen::Vector3d row = m.row(j).transpose();
    if (!row.allFinite()) throw InvalidInputError(cat(what, ": row ", j, " is not finite"));
    if (!(row.cwiseAbs().maxCoeff() <= limit))
      throw InvalidInputError(cat(what, ": row ", j, " ", vec(row), " exceeds ", limit, " in magnitude",
                                  limit < kMaxMagnitude ? " (the limit of a float device)" : ""));
  }
}

/// A per-frame vector (a pin's target): finite and at most `limit` in magnitude.
inline void checkInputVector(const Eigen::Vector3d& v, const std::string& what, double limit = kMaxMagnitude) {
  if (!v.allFinite()) throw InvalidInputError(cat(what, " is not finite"));
  if (!(v.cwiseAbs().maxCoeff() <= limit))
    throw InvalidInputError(cat(what, " ", vec(v), " exceeds ", limit, " in magnitude",
                                limit < kMaxMagnitude ? " (the limit of a float device)" : ""));
}

/// Each of `count` vertices `vertices[k]` (field "vertices[k]") in range and no particle twice.
template <typename Vertices>
void checkVertexList(const Vertices& vertices, int n, const Owner& owner) {
  const long count = static_cast<long>(vertices.size());
  for (long k = 0; k < count; ++k) checkIndex(vertices[k], n, owner, "vertices", k);
  for (long a = 0; a < count; ++a) {
    for (long b = a + 1; b < count; ++b) {
      if (vertices[a] == vertices[b]) {
        invalid(owner, ": particle ", vertices[a], " appears twice (vertices[", a, "] and vertices[", b, "])");
      }
    }
  }
}

// --- rest shapes ------------------------------------------------------------------------------
// One test of a rest tet or triangle for every place that reads one (validation of tets,
// triangle strain and bending hinges, the mesh loaders, JSON tets, OBJ faces), so that a shape
// the loaders refuse is refused through the API too, with the same words.

/// "Zero" relative to the element's own size: |V| <= kFlatness L^3 (tet) or A <= kFlatness L^2
/// (triangle), L its longest edge. Round-off on a flat element does not then pass as a sliver with
/// a random sign, and the test does not depend on units.
constexpr double kFlatness = 1e-12;

/// A rest tet's or triangle's measure and what is wrong with it, if anything.
struct RestShape {
  enum Kind { Fine, Flat, Overflow } kind;
  double measure;        // signed volume (tet) or area (triangle)
  double longest;        // longest edge
  const char* measured;  // "volume" or "area"
  int power;             // of L in the flatness test: 3 or 2
  bool fine() const { return kind == Fine; }
};

namespace detail {
template <std::size_t K>
double longestEdge(const Eigen::MatrixX3d& x, const std::array<int, K>& v) {
  double longest = 0.0;
  for (std::size_t a = 0; a < K; ++a) {
    for (std::size_t b = a + 1; b < K; ++b) longest = std::max(longest, (x.row(v[a]) - x.row(v[b])).norm());
  }
  return longest;
}
// measure / L^power > kFlatness, divided step by step: L^3 overflows long before V does. A
// zero L gives NaN, which is flat.
inline RestShape classify(double measure, double longest, const char* measured, int power) {
  if (!std::isfinite(measure)) return {RestShape::Overflow, measure, longest, measured, power};
  double relative = std::abs(measure);
  for (int k = 0; k < power; ++k) relative /= longest;
  return {relative > kFlatness ? RestShape::Fine : RestShape::Flat, measure, longest, measured, power};
}
}  // namespace detail

/// The rest tet `v` of `x`: Overflow when its volume is not finite although the coordinates are
/// (edges beyond about 1e102), Flat when it is zero relative to its size, else Fine with its
/// signed volume (negative: inverted).
inline RestShape restTet(const Eigen::MatrixX3d& x, const std::array<int, 4>& v) {
  return detail::classify(signedVolume(x, v), detail::longestEdge(x, v), "volume", 3);
}

/// The rest triangle `v` of `x`, as restTet with its (unsigned) area.
inline RestShape restTriangle(const Eigen::MatrixX3d& x, const std::array<int, 3>& v) {
  const Eigen::Vector3d e1 = (x.row(v[1]) - x.row(v[0])).transpose();
  const Eigen::Vector3d e2 = (x.row(v[2]) - x.row(v[0])).transpose();
  return detail::classify(0.5 * e1.cross(e2).norm(), detail::longestEdge(x, v), "area", 2);
}

/// What is wrong with a rest shape that is not fine, for a message after its name ("tet 3: ...").
inline std::string restShapeProblem(const RestShape& r) {
  if (r.kind == RestShape::Overflow) return cat("rest ", r.measured, " overflows (longest edge ", r.longest, ")");
  return cat("zero rest ", r.measured, " ", r.measure, " for its longest edge L = ", r.longest,
             " (degenerate: at most ", kFlatness, " L^", r.power, ")");
}

/// The rest tet is neither flat nor overflowing, and positive.
inline void checkRestTet(const Eigen::MatrixX3d& x, const std::array<int, 4>& v, const Owner& owner) {
  const RestShape r = restTet(x, v);
  if (!r.fine()) invalid(owner, ": ", restShapeProblem(r));
  if (r.measure < 0.0)
    invalid(owner, ": negative rest volume ", r.measure, " (inverted: list two vertices in the other order)");
}

/// The rest triangle (a, b, c) of `x` is neither flat nor overflowing.
inline void checkRestTriangle(const Eigen::MatrixX3d& x, int a, int b, int c, const Owner& owner) {
  const RestShape r = restTriangle(x, {a, b, c});
  if (r.kind == RestShape::Flat)
    invalid(owner, ": degenerate rest triangle (", a, ", ", b, ", ", c, "), area ", r.measure);
  if (!r.fine()) invalid(owner, ": rest triangle (", a, ", ", b, ", ", c, "): ", restShapeProblem(r));
}

/// A density that lumps masses: positive and finite (zero would leave every particle without
/// mass). `name` is the field, e.g. "density" or "areal_density".
inline void checkDensity(double density, const char* name) {
  if (!(density > 0.0) || !std::isfinite(density)) invalid(name, " ", density, " must be > 0 and finite");
}

}  // namespace stabint::validation
