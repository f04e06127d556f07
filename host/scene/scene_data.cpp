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
  buildBlocks();
}

void SceneData::buildBlocks() {
  for (const ElementType* type : elementTypes()) blocks_.push_back(type->build(scene_));
  enabled_.resize(blocks_.size());
  weights_.resize(blocks_.size());
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    ElementBlock& block = blocks_[b];
    weights_[b] = block.type->weightsFromBlocks(scene_, blocks_);
    const std::size_t p = static_cast<std::size_t>(block.type->shape().params);
    for (std::size_t e = 0; e < weights_[b].size(); ++e) block.params[p * e] = weights_[b][e];
  }
  numberContributions();
}

void SceneData::writeElementParams(std::size_t block, int element) {
  ElementBlock& b = blocks_[block];
  const std::size_t at = static_cast<std::size_t>(b.type->shape().params) * static_cast<std::size_t>(element);
  b.type->elementParams(scene_, element, &b.params[at]);
  if (!weights_[block].empty()) b.params[at] = weights_[block][static_cast<std::size_t>(element)];
}

double SceneData::enabledWeight(int block, int element) const {
  return weights_[static_cast<std::size_t>(block)][static_cast<std::size_t>(element)];
}

int SceneData::blockIndex(const ElementType& type) const {
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    if (blocks_[b].type == &type) return static_cast<int>(b);
  return -1;  // not reached: every type of elementTypes() has a block
}

void SceneData::applyEnabled(std::size_t block) {
  ElementBlock& b = blocks_[block];
  const std::vector<std::uint8_t>& flags = enabled_[block];
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  for (std::size_t e = 0; e < flags.size(); ++e)
    if (!flags[e]) b.params[p * e] = 0.0;
}

void SceneData::setElementStiffness(int block, int element, double stiffness) {
  ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
  b.type->setStiffness(scene_, element, stiffness);
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  writeElementParams(static_cast<std::size_t>(block), element);
  if (!elementEnabled(block, element)) b.params[p * static_cast<std::size_t>(element)] = 0.0;
  paramsChanged(b, element);
}

void SceneData::paramsChanged(ElementBlock& block, int element) {
  // [project rule] The log is trimmed by half when it reaches this length: amortised O(1) per
  // change, and a copy that missed more changes than that refreshes the whole block.
  constexpr std::size_t kMaxLog = 512;
  ++block.params_revision;
  if (block.changed_params.size() >= kMaxLog)
    block.changed_params.erase(block.changed_params.begin(),
                               block.changed_params.begin() + std::ptrdiff_t(kMaxLog / 2));
  block.changed_params.push_back(element);
}

void SceneData::setElementEnabled(int block, int element, bool enabled) {
  ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
  std::vector<std::uint8_t>& flags = enabled_[static_cast<std::size_t>(block)];
  if (flags.empty()) flags.assign(static_cast<std::size_t>(b.count), 1);
  flags[static_cast<std::size_t>(element)] = enabled ? 1 : 0;
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  if (enabled) {
    writeElementParams(static_cast<std::size_t>(block), element);
  } else {
    b.params[p * static_cast<std::size_t>(element)] = 0.0;
  }
  paramsChanged(b, element);
}

void SceneData::setElementParams(int block, int element, int first, const double* values, int count) {
  ElementBlock& b = blocks_[static_cast<std::size_t>(block)];
  const std::size_t p = static_cast<std::size_t>(b.type->shape().params);
  std::copy(values, values + count, b.params.begin() + std::ptrdiff_t(p * std::size_t(element) + std::size_t(first)));
  paramsChanged(b, element);
}

ElementState SceneData::elementState() const {
  ElementState state;
  state.pins = scene_.pins;
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    const ElementBlock& block = blocks_[b];
    state.stiffness.emplace_back();
    state.enabled.emplace_back();
    for (int e = 0; e < block.count; ++e) {
      state.stiffness.back().push_back(block.type->stiffness(scene_, e));
      state.enabled.back().push_back(elementEnabled(static_cast<int>(b), e) ? 1 : 0);
    }
  }
  return state;
}

void SceneData::numberContributions() {
  int base = 0;
  for (ElementBlock& block : blocks_) {
    block.contribution_base = base;
    base += static_cast<int>(block.vertices.size());
  }
  csr_ = buildCsr(n_, blocks_);
}

void SceneData::setPins(const std::vector<Pin>& pins) {
  Scene candidate;
  candidate.positions = scene_.positions;  // sizes for the index checks
  candidate.pins = pins;
  pinElementType().validate(candidate);
  scene_.pins = pins;
  // Only the pin block is rebuilt (in place: backends keep pointers to the blocks); the others
  // keep their data and, pins being last in the table, their contribution numbers.
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    ElementBlock& block = blocks_[b];
    if (block.type != &pinElementType()) continue;
    const int revision = block.revision;
    block = pinElementType().build(scene_);
    block.revision = revision + 1;
    // Grabbed pins are enabled; the others keep their flags.
    if (!enabled_[b].empty()) enabled_[b].resize(pins.size(), 1);
    applyEnabled(b);
  }
  numberContributions();
}

}  // namespace stabint
