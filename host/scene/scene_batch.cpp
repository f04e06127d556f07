#include "scene/scene_batch.hpp"

#include "elements/element_type.hpp"

#include <stabint/errors.hpp>

#include <cstddef>
#include <string>
#include <utility>

namespace stabint {
namespace {

// Part p's particles into rows [offset, offset + p's count) of s's matrices, which already have
// them; its elements, fields, bodies and triangles appended with their particles shifted by offset.
void placeScene(Scene& s, const Scene& p, int offset) {
  const int n = p.numParticles();
  s.positions.middleRows(offset, n) = p.positions;
  s.rest_positions.middleRows(offset, n) = p.rest_positions;
  s.velocities.middleRows(offset, n) = p.velocities;
  s.masses.segment(offset, n) = p.masses;
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

// s's per-particle matrices resized to `particles` rows, keeping the rows they have.
void resizeParticles(Scene& s, int particles) {
  s.positions.conservativeResize(particles, Eigen::NoChange);
  s.rest_positions.conservativeResize(particles, Eigen::NoChange);
  s.velocities.conservativeResize(particles, Eigen::NoChange);
  s.masses.conservativeResize(particles);
}

}  // namespace

void appendScene(Scene& s, const Scene& p) {
  const int offset = s.numParticles();
  resizeParticles(s, offset + p.numParticles());
  placeScene(s, p, offset);
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
  // The particles' matrices are sized once: appending scene by scene would copy them each time,
  // quadratic in the number of scenes.
  int particles = 0;
  for (const Scene& s : scenes) particles += s.numParticles();
  batch.scene.positions.resize(particles, 3);
  batch.scene.rest_positions.resize(particles, 3);
  batch.scene.velocities.resize(particles, 3);
  batch.scene.masses.resize(particles);
  int offset = 0;
  for (const Scene& s : scenes) {
    SceneSegment segment;
    segment.first_particle = offset;
    segment.num_particles = s.numParticles();
    segment.first_collider = static_cast<int>(batch.scene.colliders.size());
    segment.num_colliders = static_cast<int>(s.colliders.size());
    for (const ElementType* type : elementTypes()) {
      segment.first_element.push_back(type->count(batch.scene));
      segment.num_elements.push_back(type->count(s));
    }
    placeScene(batch.scene, s, offset);
    offset += s.numParticles();
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

SceneBatch withSupportColliders(const std::vector<Scene>& scenes, const std::vector<char>& supported, bool one) {
  std::vector<Scene> with = scenes;
  for (std::size_t i = 0; i < with.size(); ++i) {
    if (!supported[i]) continue;
    Scene& s = with[i];
    Collider support;
    support.shape = ColliderShape::Plane;
    support.normal = Eigen::Vector3d::UnitY();
    support.center = Eigen::Vector3d(0.0, -1e30, 0.0);
    s.colliders.push_back(support);
  }
  SceneBatch batch = one ? batchOfOne(with.front()) : concatenateScenes(with);
  for (std::size_t i = 0; i < batch.segments.size(); ++i) {
    if (!supported[i]) continue;
    SceneSegment& seg = batch.segments[i];
    --seg.num_colliders;
    seg.support_collider = seg.first_collider + seg.num_colliders;
  }
  return batch;
}

}  // namespace stabint
