#pragma once
// Mass lumping and the checks of what it derives: one implementation for the public
// lumpMassesFromTets/Triangles, the mesh loaders and JSON densities. A failure is returned, not
// thrown, so that each caller names the element its own way (an index, a file and line, a JSON
// path). A density that makes a mass infinite was returned as an infinite mass (issue 12 item 11).
#include <stabint/scene.hpp>

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace stabint::lumping {

/// The first element whose mass share is not finite, is a positive amount that underflows to 0,
/// or makes one of its vertices' masses overflow, and what happened ("mass share density 1e+300
/// x volume 1e+10 / 4 is not finite").
struct Failure {
  std::size_t element;
  std::string what;
};

/// Adds density |V| / 4 of each tet to each of its vertices' entries of `masses` (sized, indices
/// valid, density checked with validation::checkDensity). `density_name` is the field named in
/// a failure ("density").
std::optional<Failure> addTets(const Eigen::MatrixX3d& rest_positions, const std::vector<Tet>& tets, double density,
                               const char* density_name, Eigen::VectorXd& masses);

/// Adds areal_density A / 3 of each triangle to each of its vertices' entries, as addTets.
std::optional<Failure> addTriangles(const Eigen::MatrixX3d& rest_positions,
                                    const std::vector<std::array<int, 3>>& triangles, double areal_density,
                                    const char* density_name, Eigen::VectorXd& masses);

}  // namespace stabint::lumping
