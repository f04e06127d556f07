#pragma once
// A running scene as the element types read it (RunningScene): its elements and their enabled
// flags from the SceneData, the pin targets and collider positions from the Forcing. Two
// references, so a backend or the solver keeps one beside the two it reads.
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"

namespace stabint {

class SceneView final : public RunningScene {
 public:
  SceneView(const SceneData& data, const Forcing& forcing) : data_(&data), forcing_(&forcing) {}

  const Scene& scene() const override { return data_->scene(); }
  int blockIndex(const ElementType& type) const override { return data_->blockIndex(type); }
  bool elementEnabled(int block, int element) const override { return data_->elementEnabled(block, element); }
  double elementWeight(int block, int element) const override { return data_->elementWeight(block, element); }
  const std::vector<double>& blockParams(int block) const override {
    return data_->blocks()[static_cast<std::size_t>(block)].params;
  }
  bool hasMovingPins() const override { return forcing_->hasMovingPins(); }
  Eigen::Vector3d pinTarget(int pin, double t) const override { return forcing_->pinTarget(pin, t); }
  bool hasMovingColliders() const override { return forcing_->hasMovingColliders(); }
  Eigen::Vector3d colliderPosition(int collider, double t) const override {
    return forcing_->colliderPosition(collider, t);
  }

 private:
  const SceneData* data_;
  const Forcing* forcing_;
};

}  // namespace stabint
