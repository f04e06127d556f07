// SceneData: validation once, then the per-element rest data and the gather lists both backends
// read every iteration.
#include "scene/scene_data.hpp"

#include <Eigen/Dense>

#include <algorithm>

namespace stabint {

namespace {

std::vector<TetRest> precomputeTets(const Scene& scene) {
  std::vector<TetRest> out;
  out.reserve(scene.tets.size());
  for (const Tet& tet : scene.tets) {
    const auto& x = scene.rest_positions;
    const auto& v = tet.vertices;
    Eigen::Matrix3d dm;
    dm.col(0) = (x.row(v[1]) - x.row(v[0])).transpose();
    dm.col(1) = (x.row(v[2]) - x.row(v[0])).transpose();
    dm.col(2) = (x.row(v[3]) - x.row(v[0])).transpose();
    // validateScene has guaranteed det(Dm) > 0, so the inverse exists.
    out.push_back(TetRest{v, dm.inverse(), tet.stiffness * dm.determinant() / 6.0});
  }
  return out;
}

// Counting sort of (vertex, contribution) pairs by vertex. Contributions are visited in
// ascending order, so each vertex's list comes out sorted without a separate sort.
ContributionCsr buildCsr(const Scene& scene) {
  const int n = scene.numParticles();
  ContributionCsr csr;
  csr.springBase = 0;
  csr.tetBase = 2 * static_cast<int>(scene.springs.size());
  csr.pinBase = csr.tetBase + 4 * static_cast<int>(scene.tets.size());
  csr.numContributions = csr.pinBase + static_cast<int>(scene.pins.size());

  std::vector<int> target(csr.numContributions);
  for (size_t i = 0; i < scene.springs.size(); ++i) {
    target[csr.springBase + 2 * i] = scene.springs[i].a;
    target[csr.springBase + 2 * i + 1] = scene.springs[i].b;
  }
  for (size_t i = 0; i < scene.tets.size(); ++i) {
    for (int k = 0; k < 4; ++k) target[csr.tetBase + 4 * i + k] = scene.tets[i].vertices[k];
  }
  for (size_t i = 0; i < scene.pins.size(); ++i) target[csr.pinBase + i] = scene.pins[i].vertex;

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
  tets_ = precomputeTets(scene_);
  csr_ = buildCsr(scene_);
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
