#include "scene/scene_batch.hpp"

#include "elements/element_type.hpp"

#include <stabint/errors.hpp>

#include <cstddef>
#include <string>
#include <utility>

namespace stabint {
namespace {

template <typename Matrix>
void appendRows(Matrix& into, const Matrix& rows) {
  const Eigen::Index n = into.rows();
  into.conservativeResize(n + rows.rows(), Eigen::NoChange);
  into.bottomRows(rows.rows()) = rows;
}

}  // namespace

void appendScene(Scene& s, const Scene& p) {
  const int offset = s.numParticles();
  appendRows(s.positions, p.positions);
  appendRows(s.rest_positions, p.rest_positions);
  appendRows(s.velocities, p.velocities);
  s.masses.conservativeResize(offset + p.masses.size());
  s.masses.tail(p.masses.size()) = p.masses;
  for (const ElementType* type : elementTypes()) type->appendShifted(s, p, offset);
  for (ForceField f : p.force_fields) {
    // "All particles" of a part means the part's own particles once it has neighbours.
    if (f.particles.empty()) {
      for (int j = 0; j < p.numParticles(); ++j) f.particles.push_back(j);
    }
    for (int& j : f.particles) j += offset;
    s.force_fields.push_back(std::move(f));
  }
  for (Body b : p.bodies) {
    for (int& j : b.particles) j += offset;
    s.bodies.push_back(std::move(b));
  }
  for (auto t : p.triangles) {
    for (int& v : t) v += offset;
    s.triangles.push_back(t);
  }
}

SceneBatch concatenateScenes(const std::vector<Scene>& scenes) {
  if (scenes.empty()) throw InvalidInputError("scene batch: no scenes");
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string which = "scene " + std::to_string(i) + ": ";
    try {
      validateScene(scenes[i]);
    } catch (const InvalidInputError& e) {
      throw InvalidInputError(which + e.what());
    }
    if (scenes[i].gravity != scenes.front().gravity)
      throw InvalidInputError(which + "gravity differs from scene 0's; the scenes of a batch share one gravity");
  }
  SceneBatch batch;
  batch.scene.name = "batch of " + std::to_string(scenes.size()) + " scenes";
  batch.scene.gravity = scenes.front().gravity;
  batch.scene.positions.resize(0, 3);
  batch.scene.rest_positions.resize(0, 3);
  batch.scene.velocities.resize(0, 3);
  batch.scene.masses.resize(0);
  for (const Scene& s : scenes) {
    SceneSegment segment;
    segment.first_particle = batch.scene.numParticles();
    segment.num_particles = s.numParticles();
    segment.first_collider = static_cast<int>(batch.scene.colliders.size());
    segment.num_colliders = static_cast<int>(s.colliders.size());
    for (const ElementType* type : elementTypes()) {
      segment.first_element.push_back(type->count(batch.scene));
      segment.num_elements.push_back(type->count(s));
    }
    appendScene(batch.scene, s);
    batch.segments.push_back(std::move(segment));
  }
  return batch;
}

SceneBatch batchOfOne(const Scene& scene) {
  SceneSegment segment;
  segment.num_particles = scene.numParticles();
  segment.num_colliders = static_cast<int>(scene.colliders.size());
  for (const ElementType* type : elementTypes()) {
    segment.first_element.push_back(0);
    segment.num_elements.push_back(type->count(scene));
  }
  return SceneBatch{scene, {segment}};
}

}  // namespace stabint
