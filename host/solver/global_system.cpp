#include "solver/global_system.hpp"

#include "cpu/elements.hpp"
#include "scene/scene_data.hpp"

#include <stabint/errors.hpp>

#include <string>
#include <vector>

namespace stabint {

GlobalSystem::GlobalSystem(const SceneData& scene) : masses_(scene.masses()) {
  const int n = scene.numParticles();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(4 * scene.springs().size() + 16 * scene.tets().size() + scene.pins().size());
  for (const Spring& s : scene.springs()) {
    // A = e_a - e_b
    entries.emplace_back(s.a, s.a, s.stiffness);
    entries.emplace_back(s.b, s.b, s.stiffness);
    entries.emplace_back(s.a, s.b, -s.stiffness);
    entries.emplace_back(s.b, s.a, -s.stiffness);
  }
  for (const TetRest& tet : scene.tets()) {
    // Block w G G^T over the tet's four vertices.
    const Eigen::Matrix<double, 4, 3> g = elements::tetGradientOperator(tet.dm_inverse);
    const Eigen::Matrix4d block = tet.weight * g * g.transpose();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) entries.emplace_back(tet.vertices[i], tet.vertices[j], block(i, j));
  }
  for (const Pin& pin : scene.pins()) entries.emplace_back(pin.vertex, pin.vertex, pin.stiffness);
  laplacian_.resize(n, n);
  laplacian_.setFromTriplets(entries.begin(), entries.end());
}

void GlobalSystem::solve(double c, const Eigen::MatrixX3d& rhs, Eigen::MatrixX3d& x) {
  auto it = factors_.find(c);
  if (it == factors_.end()) {
    // A particle touched by no element has no diagonal entry in L, so add c M as a matrix.
    Eigen::SparseMatrix<double> mass(laplacian_.rows(), laplacian_.cols());
    mass.reserve(Eigen::VectorXi::Ones(laplacian_.cols()));
    for (Eigen::Index j = 0; j < masses_.size(); ++j) mass.insert(j, j) = c * masses_[j];
    const Eigen::SparseMatrix<double> k = laplacian_ + mass;
    auto factor = std::make_unique<Factor>();
    factor->compute(k);
    if (factor->info() != Eigen::Success)
      throw Error("global system: CHOLMOD factorization of cM + L failed for c = " + std::to_string(c));
    it = factors_.emplace(c, std::move(factor)).first;
  }
  x = it->second->solve(rhs);
}

}  // namespace stabint
