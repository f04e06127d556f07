#pragma once
// The checks validateScene and the element types share, each throwing InvalidInputError with a
// message that names the element or field ("spring 12: stiffness -1 must be >= 0").
#include <stabint/errors.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>

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
inline void checkStiffness(double k, const Owner& owner) {
  if (!(k >= 0.0) || !std::isfinite(k)) invalid(owner, ": stiffness ", k, " must be >= 0");
}

/// Largest magnitude of a quantity that the simulation squares or multiplies by a time or a
/// stiffness (coordinates, speeds, gravity, rest lengths, pin and force targets, frequencies), so
/// that squares and their sums stay finite. Finite inputs beyond it (a rest length of 1e200, a
/// frequency of 1e308) overflowed in the first step and were reported as a blow-up.
constexpr double kMaxMagnitude = 1e150;

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

/// The rest triangle (a, b, c) of `x` is not degenerate: its area is above 1e-12 times its
/// longest edge squared (round-off on collinear points does not pass as a sliver).
inline void checkRestTriangle(const Eigen::MatrixX3d& x, int a, int b, int c, const Owner& owner) {
  const Eigen::Vector3d e1 = (x.row(b) - x.row(a)).transpose();
  const Eigen::Vector3d e2 = (x.row(c) - x.row(a)).transpose();
  const double twice_area = e1.cross(e2).norm();
  const double longest = std::max({e1.squaredNorm(), e2.squaredNorm(), (e2 - e1).squaredNorm()});
  if (!(twice_area > 1e-12 * longest)) {
    invalid(owner, ": degenerate rest triangle (", a, ", ", b, ", ", c, "), area ", 0.5 * twice_area);
  }
}

}  // namespace stabint::validation
