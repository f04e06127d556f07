#include "driver/element_changes.hpp"

#include "elements/element_type.hpp"
#include "scene/forcing.hpp"
#include "scene/scene_data.hpp"
#include "common/validation.hpp"

#include <stabint/errors.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

namespace stabint {
namespace {

bool samePins(const std::vector<Pin>& a, const std::vector<Pin>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const Pin& p, const Pin& q) {
    return p.vertex == q.vertex && p.stiffness == q.stiffness && p.target.position == q.target.position &&
           p.target.velocity == q.target.velocity && p.target.amplitude == q.target.amplitude &&
           p.target.frequency == q.target.frequency;
  });
}

}  // namespace

ElementChanges::ElementChanges(SceneData& scene, Forcing& forcing, GlobalSystem& system, Backend& backend,
                               InputScope scope)
    : scene_(scene), forcing_(forcing), system_(system), backend_(backend), scope_(std::move(scope)) {}

int ElementChanges::block(ElementKind kind) const {
  try {
    return scene_.blockIndex(elementType(kind));
  } catch (const InvalidInputError& e) {
    throw InvalidInputError(scope_.where() + e.what());
  }
}

void ElementChanges::checkIndex(int block, int index, const char* call) const {
  const ElementBlock& b = scene_.blocks()[static_cast<std::size_t>(block)];
  const int count = scope_.elements(scene_, block).count;
  if (index < 0 || index >= count)
    throw InvalidInputError(scope_.where(call) + b.type->name() + " " + std::to_string(index) +
                            " out of range (the scene has " + std::to_string(count) + ")");
}

bool ElementChanges::enabled(ElementKind kind, int index) const {
  const int block = this->block(kind);
  checkIndex(block, index, "elementEnabled");
  return scene_.elementEnabled(block, scope_.elements(scene_, block).first + index);
}

// Element e's term (w - w_old) A^T A into `change`, unless its weight is the same.
void ElementChanges::addTerm(GlobalSystem::WeightChange& change, int block, int e, double w_old) const {
  const double w_new = scene_.elementWeight(block, e);
  if (w_new == w_old) return;
  const ElementBlock& b = scene_.blocks()[static_cast<std::size_t>(block)];
  const ElementShape shape = b.type->shape();
  const std::size_t stride = shape.shared_coefficients ? 0 : std::size_t(shape.rows * shape.vertices);
  change.addElement(&b.vertices[std::size_t(shape.vertices) * std::size_t(e)], shape.vertices,
                    b.coefficients.data() + stride * std::size_t(e), shape.rows, w_new - w_old);
}

void ElementChanges::change(ElementKind kind, std::vector<int> indices, const double* stiffness, bool enabled) {
  const char* call = stiffness ? "setElementStiffness" : "setElementEnabled";
  const int block = this->block(kind);
  const ElementBlock& b = scene_.blocks()[static_cast<std::size_t>(block)];
  for (int e : indices) checkIndex(block, e, call);
  // An index listed twice is changed once (its term would otherwise enter L twice).
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  if (stiffness && !b.type->hasStiffness())
    throw InvalidInputError(scope_.where(call) + "a " + b.type->name() + " has no stiffness");
  if (stiffness && (!std::isfinite(*stiffness) || !(*stiffness >= 0.0) || !(*stiffness <= validation::kMaxMagnitude)))
    throw InvalidInputError(scope_.where(call) + b.type->name() + " stiffness " + validation::cat(*stiffness) +
                            " must be finite, >= 0 and at most " + validation::cat(validation::kMaxMagnitude));
  // The scope's indices as the scene's.
  const int first = scope_.elements(scene_, block).first;
  for (int& e : indices) e += first;
  std::vector<double> w_old, k_old;
  std::vector<bool> on_old;
  for (int e : indices) {
    w_old.push_back(scene_.elementWeight(block, e));
    k_old.push_back(b.type->stiffness(scene_.scene(), e));
    on_old.push_back(scene_.elementEnabled(block, e));
  }
  if (stiffness) {
    for (int e : indices) scene_.setElementStiffness(block, e, *stiffness);
    // The weight is k times a rest volume, area or inverse area: it must stay finite too. A
    // refusal puts the old stiffnesses back (their params are recomputed bit for bit).
    for (std::size_t i = 0; i < indices.size(); ++i) {
      if (std::isfinite(scene_.elementWeight(block, indices[i]))) continue;
      const int bad = indices[i] - first;
      for (std::size_t j = indices.size(); j-- > 0;) scene_.setElementStiffness(block, indices[j], k_old[j]);
      throw InvalidInputError(scope_.where(call) + b.type->name() + " " + std::to_string(bad) + ": stiffness " +
                              std::to_string(*stiffness) + " gives a weight that is not finite");
    }
  } else {
    for (int e : indices) scene_.setElementEnabled(block, e, enabled);
  }
  GlobalSystem::WeightChange weights;
  for (std::size_t i = 0; i < indices.size(); ++i) addTerm(weights, block, indices[i], w_old[i]);
  // L and the factors as they are now, put back bit for bit unless the change succeeds.
  GlobalSystem::Transaction transaction(system_);
  try {
    system_.apply(weights, scene_);
  } catch (const Error&) {
    // The new system does not factor (a stiffness too large for the masses, as the constructor
    // refuses it): the old stiffnesses and flags go back, and the transaction L and the factors.
    for (std::size_t i = indices.size(); i-- > 0;) {
      scene_.setElementStiffness(block, indices[i], k_old[i]);
      scene_.setElementEnabled(block, indices[i], on_old[i]);
    }
    throw;
  }
  transaction.commit();
}

void ElementChanges::changePins(const std::vector<Pin>& pins, int inserted) {
  std::map<int, double> delta;
  for (const Pin& p : scene_.scene().pins) delta[p.vertex] -= p.stiffness;
  for (const Pin& p : pins) delta[p.vertex] += p.stiffness;
  // setPins keeps ramps and flags by index: the pins after an inserted one take theirs along.
  const int old_count = static_cast<int>(scene_.scene().pins.size());
  const bool shifts = inserted >= 0 && inserted < old_count;
  const int pin_block = scene_.blockIndex(pinElementType());
  Forcing::State forcing;
  std::vector<bool> flags;
  if (shifts) {
    forcing = forcing_.state();
    forcing.pins.insert(forcing.pins.begin() + inserted, Forcing::Ramp{});
    for (int i = 0; i < old_count; ++i) flags.push_back(scene_.elementEnabled(pin_block, i));
    flags.insert(flags.begin() + inserted, true);  // a grabbed pin is enabled
  }
  const std::vector<Pin> before = scene_.scene().pins;
  scene_.setPins(pins);
  forcing_.pinsChanged(before);
  if (shifts) {
    forcing_.setState(forcing);
    for (int i = inserted; i < static_cast<int>(pins.size()); ++i)
      if (scene_.elementEnabled(pin_block, i) != flags[static_cast<std::size_t>(i)])
        scene_.setElementEnabled(pin_block, i, flags[static_cast<std::size_t>(i)]);
  }
  backend_.elementsChanged();
  GlobalSystem::WeightChange weights;
  for (const auto& [vertex, k] : delta)
    if (k != 0.0) weights.addDiagonal(vertex, k);
  system_.apply(weights, scene_);
}

void ElementChanges::restore(const ElementState& state, int contact_block,
                             const std::vector<std::uint8_t>* contact_flags) {
  if (!samePins(state.pins, scene_.scene().pins)) changePins(state.pins);
  GlobalSystem::WeightChange weights;
  for (std::size_t b = 0; b < scene_.blocks().size(); ++b) {
    const ElementBlock& block = scene_.blocks()[b];
    const int bi = static_cast<int>(b);
    for (int e = 0; e < block.count; ++e) {
      const double k = state.stiffness[b][static_cast<std::size_t>(e)];
      const bool on = (contact_flags && bi == contact_block ? *contact_flags : state.enabled[b])[std::size_t(e)] != 0;
      const bool k_differs = block.type->hasStiffness() && block.type->stiffness(scene_.scene(), e) != k;
      if (!k_differs && scene_.elementEnabled(bi, e) == on) continue;
      const double w_old = scene_.elementWeight(bi, e);
      if (k_differs) scene_.setElementStiffness(bi, e, k);
      if (scene_.elementEnabled(bi, e) != on) scene_.setElementEnabled(bi, e, on);
      if (!contact_flags) addTerm(weights, bi, e, w_old);
    }
  }
  if (!contact_flags) system_.apply(weights, scene_);
}

}  // namespace stabint
