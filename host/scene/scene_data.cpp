// SceneData: validation once, then the element blocks and the gather lists both backends read
// every iteration.
#include "scene/scene_data.hpp"

#include <algorithm>

namespace stabint {

namespace {

// Counting sort of (vertex, contribution) pairs by vertex. Contributions are visited in
// ascending order, so each vertex's list comes out sorted without a separate sort.
ContributionCsr buildCsr(int n, const std::vector<ElementBlock>& blocks) {
  ContributionCsr csr;
  std::vector<int> target;
  for (const ElementBlock& block : blocks) target.insert(target.end(), block.vertices.begin(), block.vertices.end());
  csr.numContributions = static_cast<int>(target.size());
  csr.offsets.assign(n + 1, 0);
  for (int v : target) ++csr.offsets[v + 1];
  for (int j = 0; j < n; ++j) csr.offsets[j + 1] += csr.offsets[j];
  csr.contributions.resize(csr.numContributions);
  std::vector<int> fill(csr.offsets.begin(), csr.offsets.end() - 1);
  for (int c = 0; c < csr.numContributions; ++c) csr.contributions[fill[target[c]]++] = c;
  return csr;
}

}  // namespace

SceneData::SceneData(const Scene& scene) {
  // Validate before copying anything: a throw leaves no half-built object behind.
  validateScene(scene);
  scene_ = scene;
  n_ = scene.numParticles();
  int base = 0;
  for (const ElementType* type : elementTypes()) {
    blocks_.push_back(type->build(scene_));
    blocks_.back().contribution_base = base;
    base += static_cast<int>(blocks_.back().vertices.size());
  }
  csr_ = buildCsr(n_, blocks_);
  moving_pins_ = std::any_of(scene_.pins.begin(), scene_.pins.end(),
                             [](const Pin& p) { return p.target.moving(); });
  time_dependent_fields_ = std::any_of(scene_.force_fields.begin(), scene_.force_fields.end(),
                                       [](const ForceField& f) { return f.timeDependent(); });
  time_dependent_forcing_ = moving_pins_ || time_dependent_fields_;
}

void SceneData::externalForces(double t, Eigen::MatrixX3d& out) const {
  out = scene_.masses * scene_.gravity.transpose();
  for (const ForceField& field : scene_.force_fields) {
    const Eigen::RowVector3d f = field.at(t).transpose();
    if (field.particles.empty()) {
      out.rowwise() += f;
    } else {
      for (int j : field.particles) out.row(j) += f;
    }
  }
}

void SceneData::pinTargets(double t, Eigen::MatrixX3d& out) const {
  out.resize(static_cast<Eigen::Index>(scene_.pins.size()), 3);
  for (size_t i = 0; i < scene_.pins.size(); ++i) out.row(i) = scene_.pins[i].target.at(t).transpose();
}

}  // namespace stabint
