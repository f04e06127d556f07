#include "solver/global_system.hpp"

#include "scene/scene_data.hpp"

#include <stabint/errors.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace stabint {

GlobalSystem::GlobalSystem(const SceneData& scene) : masses_(scene.masses()) {
  const int n = scene.numParticles();
  std::vector<Eigen::Triplet<double>> entries;
  std::size_t count = 0;
  for (const ElementBlock& block : scene.blocks()) {
    const int k = block.type->shape().vertices;
    count += std::size_t(block.count) * std::size_t(k * k);
  }
  entries.reserve(count);
  for (const ElementBlock& block : scene.blocks()) {
    // Block w A^T A over the element's vertex tuple: entry (i, j) = w sum_r A(r, i) A(r, j).
    const ElementShape shape = block.type->shape();
    const int K = shape.vertices, R = shape.rows;
    const int stride = shape.shared_coefficients ? 0 : R * K;
    for (int e = 0; e < block.count; ++e) {
      const int* v = &block.vertices[std::size_t(K) * e];
      const double* a = block.coefficients.data() + std::size_t(stride) * e;
      const double w = block.params[std::size_t(shape.params) * e];
      for (int i = 0; i < K; ++i) {
        for (int j = 0; j < K; ++j) {
          double sum = 0.0;
          for (int r = 0; r < R; ++r) sum += a[K * r + i] * a[K * r + j];
          entries.emplace_back(v[i], v[j], w * sum);
        }
      }
    }
  }
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
