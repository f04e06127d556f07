// A scene file's "mesh" entries: an OBJ cloth, a TetGen or a Medit solid with its material, read
// through the mesh loaders (stabint/io.hpp) and reported inside the scene file's context.
#include "io/json/json_internal.hpp"

#include "common/text_reader.hpp"

#include <stabint/errors.hpp>
#include <stabint/io.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <set>
#include <string>

namespace stabint::io {

namespace fs = std::filesystem;

namespace {

std::string lowerExtension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

Scene meshFromField(const Field& mesh, const fs::path& dir) {
  mesh.requireObject();
  const Field file_field = mesh.member("file");
  const fs::path relative = file_field.string();
  const fs::path path = relative.is_absolute() ? relative : dir / relative;

  std::string type;
  if (auto t = mesh.find("type")) {
    type = t->string();
    if (type != "obj" && type != "tetgen" && type != "medit") {
      t->fail("unknown mesh type '" + shown(type) + "' (expected obj, tetgen or medit)");
    }
  } else {
    const std::string ext = lowerExtension(path);
    if (ext == ".obj")
      type = "obj";
    else if (ext == ".mesh")
      type = "medit";
    else if (ext == ".node" || ext == ".ele")
      type = "tetgen";
    else
      file_field.fail("cannot tell the mesh type from '" + shown(relative.string()) +
                      "'; add \"type\": obj, tetgen or medit");
  }

  const std::set<std::string> common = {"file", "type", "translate", "damping", "name"};
  Scene out;
  try {
    if (type == "obj") {
      std::set<std::string> keys = common;
      keys.insert({"areal_density", "model", "stretch_stiffness", "bend_stiffness", "strain_stiffness", "strain_min",
                   "strain_max", "hinge_stiffness"});
      mesh.allowOnly(keys);
      ClothMaterial m;
      if (auto f = mesh.find("areal_density")) m.areal_density = f->positive();
      if (auto f = mesh.find("model")) m.model = clothModel(*f);
      if (auto f = mesh.find("stretch_stiffness")) m.stretch_stiffness = f->nonNegative();
      if (auto f = mesh.find("bend_stiffness")) m.bend_stiffness = f->nonNegative();
      if (auto f = mesh.find("strain_stiffness")) m.strain_stiffness = f->nonNegative();
      if (auto f = mesh.find("strain_min")) m.strain_min = f->nonNegative();
      if (auto f = mesh.find("strain_max")) m.strain_max = f->nonNegative();
      if (auto f = mesh.find("hinge_stiffness")) m.hinge_stiffness = f->nonNegative();
      out = loadObjCloth(path.string(), m);
    } else {
      std::set<std::string> keys = common;
      keys.insert({"density", "stiffness"});
      mesh.allowOnly(keys);
      SolidMaterial m;
      if (auto f = mesh.find("density")) m.density = f->positive();
      if (auto f = mesh.find("stiffness")) m.stiffness = f->nonNegative();
      if (type == "medit") {
        out = loadMedit(path.string(), m);
      } else {
        const std::string ext = lowerExtension(path);
        fs::path base = path;
        if (ext == ".node" || ext == ".ele") base.replace_extension();
        out = loadTetGen(base.string(), m);
      }
    }
  } catch (const FileFormatError& e) {
    // The mesh file's own error (file and line) inside the scene file's context.
    file_field.fail(e.what());
  }
  if (auto f = mesh.find("damping")) {
    const double d = f->number();
    if (d < 0.0 || d > 1.0) f->fail("must be in [0, 1], got " + Field::text(d));
    for (Body& b : out.bodies) b.damping = d;
  }
  if (auto f = mesh.find("name")) {
    out.name = f->string();
    for (Body& b : out.bodies) b.name = out.name;
  }
  return out;
}

}  // namespace stabint::io
