// The built-in scenes (oscillator, chain, cloth, tetbar): their builder parameters, read from a
// scene file's "builtin" entry or from builtinScene's JSON, and listed for usage texts.
#include "io/json/json_internal.hpp"

#include "common/text_reader.hpp"

#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/io.hpp>

#include <set>
#include <string>
#include <vector>

namespace stabint::io {

namespace {

// One list of parameter names per builder, used both to read them and to list them.
template <typename Visit>
void visitParams(Visit&& v, LinearOscillatorParams& p) {
  v("mass", p.mass);
  v("stiffness", p.stiffness);
  v("amplitude", p.amplitude);
}
template <typename Visit>
void visitParams(Visit&& v, ChainPendulumParams& p) {
  v("particles", p.particles);
  v("total_mass", p.total_mass);
  v("length", p.length);
  v("stiffness", p.stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("gravity", p.gravity);
}
template <typename Visit>
void visitParams(Visit&& v, ClothGridParams& p) {
  v("nx", p.nx);
  v("ny", p.ny);
  v("width", p.width);
  v("height", p.height);
  v("areal_density", p.areal_density);
  v("stretch_stiffness", p.stretch_stiffness);
  v("shear_stiffness", p.shear_stiffness);
  v("bend_stiffness", p.bend_stiffness);
  v("model", p.model);
  v("strain_stiffness", p.strain_stiffness);
  v("strain_min", p.strain_min);
  v("strain_max", p.strain_max);
  v("hinge_stiffness", p.hinge_stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("pinned", p.pinned);
  v("damping", p.damping);
}
template <typename Visit>
void visitParams(Visit&& v, TetBarParams& p) {
  v("nx", p.nx);
  v("ny", p.ny);
  v("nz", p.nz);
  v("length", p.length);
  v("width", p.width);
  v("density", p.density);
  v("stiffness", p.stiffness);
  v("pin_stiffness", p.pin_stiffness);
  v("damping", p.damping);
}

}  // namespace

// A name as clothModelName prints it ("springs", "triangles").
ClothModel clothModel(const Field& f) {
  const std::string name = f.string();
  if (const std::optional<ClothModel> model = valueNamed(name, clothModelName, kClothModelCount)) return *model;
  f.fail("unknown cloth model '" + shown(name) + "' (expected " + enumNames(clothModelName, kClothModelCount) + ")");
}

namespace {

struct ParamReader {
  const Field& params;
  std::set<std::string>& known;
  void operator()(const char* key, int& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = f->integer();
  }
  void operator()(const char* key, double& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = f->number();
  }
  void operator()(const char* key, ClothModel& out) const {
    known.insert(key);
    if (auto f = params.find(key)) out = clothModel(*f);
  }
  void operator()(const char* key, std::vector<int>& out) const {
    known.insert(key);
    if (auto f = params.find(key)) {
      out.resize(f->size());
      for (size_t i = 0; i < out.size(); ++i) out[i] = (*f)[i].integer();  // range: the builder checks
    }
  }
};

struct ParamNames {
  std::vector<std::string>& names;
  template <typename T>
  void operator()(const char* key, T&) const {
    names.emplace_back(key);
  }
};

// Reads the builder parameters from `params` (an object; `extra` keys belong to the caller).
template <typename Params, typename Make>
Scene buildWith(const Field& params, const std::set<std::string>& extra, Params& p, Make make) {
  std::set<std::string> known = extra;
  visitParams(ParamReader{params, known}, p);
  params.allowOnly(known);
  try {
    return make(p);
  } catch (const InvalidInputError& e) {
    params.fail(e.what());
  }
}

}  // namespace

Scene builtinFromField(const std::string& name, const Field& params, const std::set<std::string>& extra,
                       const Field& name_field) {
  Scene out;
  if (name == "oscillator") {
    LinearOscillatorParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeLinearOscillator(q); });
  } else if (name == "chain") {
    ChainPendulumParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeChainPendulum(q); });
  } else if (name == "cloth") {
    ClothGridParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeClothGrid(q); });
  } else if (name == "tetbar") {
    TetBarParams p;
    out = buildWith(params, extra, p, [](const auto& q) { return makeTetBar(q); });
  } else {
    name_field.fail("unknown built-in scene '" + shown(name) + "' (expected oscillator, chain, cloth or tetbar)");
  }
  return out;
}

}  // namespace stabint::io

namespace stabint {

using io::Field;
using io::json;

Scene builtinScene(const std::string& name, const std::string& params_json, const std::string& label) {
  const json params = io::parseJson(params_json.empty() ? "{}" : params_json, label);
  const json name_value = name;
  const Field root(params, "params", label);
  root.requireObject();
  return io::builtinFromField(name, root, {}, Field(name_value, "name", label));
}

std::vector<std::string> builtinSceneNames() { return {"oscillator", "chain", "cloth", "tetbar"}; }

std::vector<std::string> builtinSceneParameters(const std::string& name) {
  using namespace io;
  std::vector<std::string> names;
  const ParamNames collect{names};
  if (name == "oscillator") {
    LinearOscillatorParams p;
    visitParams(collect, p);
  } else if (name == "chain") {
    ChainPendulumParams p;
    visitParams(collect, p);
  } else if (name == "cloth") {
    ClothGridParams p;
    visitParams(collect, p);
  } else if (name == "tetbar") {
    TetBarParams p;
    visitParams(collect, p);
  }
  return names;
}

}  // namespace stabint
