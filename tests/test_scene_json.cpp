// JSON scene files: every field of the Scene model, the conveniences (builtin, mesh, pin_where,
// where, density lumping), exact round trips through saveSceneFile, and every error path with the
// file and field path it must name.

#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/io.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "temp_dir_test.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <unistd.h>

namespace stabint {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// The repository's scenes/ folder, next to tests/.
const std::string kScenesDir = (fs::path(__FILE__).parent_path().parent_path() / "scenes").string();

class SceneJson : public testing::TempDirTest {
 protected:
  // Loads `text` as a scene file; the error it must raise is "<file>: <message>" with line 0
  // unless a line is given.
  void expectError(const std::string& text, const std::string& message, int line = 0) const {
    const std::string path = write("scene.json", text);
    try {
      loadSceneFile(path);
      ADD_FAILURE() << "expected a FileFormatError containing: " << message;
    } catch (const FileFormatError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_THAT(e.what(), HasSubstr(message));
      const std::string prefix = path + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": ";
      EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
    }
  }
};

// Two-particle scene text with `extra` members appended to the top-level object.
std::string twoParticles(const std::string& extra = "") {
  return R"({"particles": {"positions": [[0,0,0],[1,0,0]], "masses": [1, 2]})" + extra + "}";
}

void expectSameScene(const Scene& a, const Scene& b) {
  // Exact: bitwise equal doubles (so -0.0 and 0.0 differ).
  const auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  const auto sameMatrix = [&](const auto& x, const auto& y) {
    if (x.rows() != y.rows() || x.cols() != y.cols()) return false;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      if (!same(x.data()[i], y.data()[i])) return false;
    }
    return true;
  };
  EXPECT_EQ(a.name, b.name);
  EXPECT_TRUE(sameMatrix(a.positions, b.positions));
  EXPECT_TRUE(sameMatrix(a.rest_positions, b.rest_positions));
  EXPECT_TRUE(sameMatrix(a.velocities, b.velocities));
  EXPECT_TRUE(sameMatrix(a.masses, b.masses));
  EXPECT_TRUE(sameMatrix(a.gravity, b.gravity));
  ASSERT_EQ(a.springs.size(), b.springs.size());
  for (size_t i = 0; i < a.springs.size(); ++i) {
    EXPECT_EQ(a.springs[i].a, b.springs[i].a);
    EXPECT_EQ(a.springs[i].b, b.springs[i].b);
    EXPECT_TRUE(same(a.springs[i].rest_length, b.springs[i].rest_length)) << "spring " << i;
    EXPECT_TRUE(same(a.springs[i].stiffness, b.springs[i].stiffness)) << "spring " << i;
  }
  ASSERT_EQ(a.tets.size(), b.tets.size());
  for (size_t i = 0; i < a.tets.size(); ++i) {
    EXPECT_EQ(a.tets[i].vertices, b.tets[i].vertices);
    EXPECT_TRUE(same(a.tets[i].stiffness, b.tets[i].stiffness));
  }
  ASSERT_EQ(a.pins.size(), b.pins.size());
  for (size_t i = 0; i < a.pins.size(); ++i) {
    EXPECT_EQ(a.pins[i].vertex, b.pins[i].vertex);
    EXPECT_TRUE(same(a.pins[i].stiffness, b.pins[i].stiffness));
    EXPECT_TRUE(sameMatrix(a.pins[i].target.position, b.pins[i].target.position));
    EXPECT_TRUE(sameMatrix(a.pins[i].target.velocity, b.pins[i].target.velocity));
    EXPECT_TRUE(sameMatrix(a.pins[i].target.amplitude, b.pins[i].target.amplitude));
    EXPECT_TRUE(same(a.pins[i].target.frequency, b.pins[i].target.frequency));
  }
  ASSERT_EQ(a.force_fields.size(), b.force_fields.size());
  for (size_t i = 0; i < a.force_fields.size(); ++i) {
    EXPECT_EQ(a.force_fields[i].particles, b.force_fields[i].particles);
    EXPECT_TRUE(sameMatrix(a.force_fields[i].force, b.force_fields[i].force));
    EXPECT_TRUE(sameMatrix(a.force_fields[i].rate, b.force_fields[i].rate));
    EXPECT_TRUE(sameMatrix(a.force_fields[i].amplitude, b.force_fields[i].amplitude));
    EXPECT_TRUE(same(a.force_fields[i].frequency, b.force_fields[i].frequency));
  }
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_EQ(a.bodies[i].name, b.bodies[i].name);
    EXPECT_EQ(a.bodies[i].particles, b.bodies[i].particles);
    EXPECT_TRUE(same(a.bodies[i].damping, b.bodies[i].damping));
  }
  ASSERT_EQ(a.triangle_strains.size(), b.triangle_strains.size());
  for (size_t i = 0; i < a.triangle_strains.size(); ++i) {
    EXPECT_EQ(a.triangle_strains[i].vertices, b.triangle_strains[i].vertices);
    EXPECT_TRUE(same(a.triangle_strains[i].stiffness, b.triangle_strains[i].stiffness));
    EXPECT_TRUE(same(a.triangle_strains[i].strain_min, b.triangle_strains[i].strain_min));
    EXPECT_TRUE(same(a.triangle_strains[i].strain_max, b.triangle_strains[i].strain_max));
  }
  ASSERT_EQ(a.bending_hinges.size(), b.bending_hinges.size());
  for (size_t i = 0; i < a.bending_hinges.size(); ++i) {
    EXPECT_EQ(a.bending_hinges[i].vertices, b.bending_hinges[i].vertices);
    EXPECT_TRUE(same(a.bending_hinges[i].stiffness, b.bending_hinges[i].stiffness));
  }
  EXPECT_EQ(a.triangles, b.triangles);
}

// --- the explicit form ---------------------------------------------------------------------------

TEST_F(SceneJson, ExplicitFormReadsEveryField) {
  const Scene s = loadSceneFile(write("all.json", R"({
    "format": "stabint-scene", "version": 1, "name": "all",
    "_comment": "keys starting with _ are ignored",
    "gravity": [0, 0, -1],
    "particles": {
      "positions": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]],
      "rest_positions": [[0,0,0],[1,0,0],[0,1,0],[0,0,2]],
      "velocities": [[0,0,0],[0,0,0],[0,0,0],[1,2,3]],
      "masses": [1, 2, 3, 4]
    },
    "springs": [{"a": 0, "b": 1, "stiffness": 10}, {"a": 2, "b": 3, "stiffness": 5, "rest_length": 0.5}],
    "tets": [{"vertices": [0, 1, 2, 3], "stiffness": 100}],
    "pins": [{"vertex": 0, "stiffness": 1e4},
             {"vertex": 3, "stiffness": 2, "target": {"position": [9,9,9], "velocity": [1,0,0], "amplitude": [0,1,0], "frequency": 2}}],
    "force_fields": [{"force": [1,0,0]}, {"particles": [1, 2], "rate": [0,1,0], "amplitude": [0,0,1], "frequency": 3}],
    "bodies": [{"name": "all", "damping": 0.25}, {"particles": [3]}]
  })"));
  EXPECT_EQ(s.name, "all");
  EXPECT_EQ(s.gravity, Eigen::Vector3d(0, 0, -1));
  ASSERT_EQ(s.numParticles(), 4);
  EXPECT_EQ(s.rest_positions(3, 2), 2.0);
  EXPECT_EQ(s.velocities.row(3), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(s.masses, Eigen::Vector4d(1, 2, 3, 4));
  ASSERT_EQ(s.springs.size(), 2u);
  EXPECT_DOUBLE_EQ(s.springs[0].rest_length, 1.0);  // default: distance in the rest shape
  EXPECT_DOUBLE_EQ(s.springs[1].rest_length, 0.5);
  EXPECT_DOUBLE_EQ(s.springs[1].stiffness, 5.0);
  ASSERT_EQ(s.tets.size(), 1u);
  EXPECT_EQ(s.tets[0].stiffness, 100.0);
  ASSERT_EQ(s.pins.size(), 2u);
  EXPECT_EQ(s.pins[0].target.position, Eigen::Vector3d::Zero());  // default: the rest position
  EXPECT_FALSE(s.pins[0].target.moving());
  EXPECT_EQ(s.pins[1].target.position, Eigen::Vector3d(9, 9, 9));
  EXPECT_EQ(s.pins[1].target.velocity, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(s.pins[1].target.amplitude, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(s.pins[1].target.frequency, 2.0);
  ASSERT_EQ(s.force_fields.size(), 2u);
  EXPECT_TRUE(s.force_fields[0].particles.empty());  // all particles
  EXPECT_EQ(s.force_fields[1].particles, (std::vector<int>{1, 2}));
  EXPECT_EQ(s.force_fields[1].rate, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(s.force_fields[1].frequency, 3.0);
  ASSERT_EQ(s.bodies.size(), 2u);
  EXPECT_EQ(s.bodies[0].particles, (std::vector<int>{0, 1, 2, 3}));  // default: all
  EXPECT_EQ(s.bodies[0].damping, 0.25);
  EXPECT_EQ(s.bodies[1].particles, (std::vector<int>{3}));
  EXPECT_EQ(s.bodies[1].damping, 0.0);
}

TEST_F(SceneJson, DefaultsFromTheMinimalForm) {
  const Scene s = loadSceneFile(write("minimal.json", R"({"particles": {"positions": [[1,2,3]], "masses": 0.5}})"));
  EXPECT_EQ(s.name, "minimal");  // the file stem
  EXPECT_EQ(s.gravity, Eigen::Vector3d(0, -9.81, 0));
  EXPECT_EQ(s.rest_positions, s.positions);
  EXPECT_EQ(s.velocities, Eigen::MatrixX3d::Zero(1, 3));
  EXPECT_EQ(s.masses[0], 0.5);
  EXPECT_TRUE(s.bodies.empty());
}

TEST_F(SceneJson, MassesLumpedFromDensities) {
  // One tet with volume 1/6 and one triangle of area 1/2 sharing three particles.
  const Scene s = loadSceneFile(write("lumped.json", R"({
    "particles": {"positions": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "density": 600, "areal_density": 30},
    "tets": [{"vertices": [0, 1, 2, 3], "stiffness": 1}],
    "triangles": [[0, 1, 2]]
  })"));
  const double tet = 600.0 / 6.0 / 4.0, tri = 30.0 * 0.5 / 3.0;
  EXPECT_DOUBLE_EQ(s.masses[0], tet + tri);
  EXPECT_DOUBLE_EQ(s.masses[2], tet + tri);
  EXPECT_DOUBLE_EQ(s.masses[3], tet);
  ASSERT_EQ(s.triangles.size(), 1u);
}

// --- conveniences ----------------------------------------------------------------------------------

TEST_F(SceneJson, BuiltinMatchesTheBuilder) {
  const Scene s = loadSceneFile(
      write("b.json", R"({"builtin": {"name": "cloth", "nx": 5, "ny": 4, "damping": 0.1, "pinned": [0]}})"));
  ClothGridParams p;
  p.nx = 5;
  p.ny = 4;
  p.damping = 0.1;
  p.pinned = {0};
  expectSameScene(s, makeClothGrid(p));
  EXPECT_EQ(s.triangles.size(), 2u * 4 * 3);

  const Scene chain = loadSceneFile(write("c.json", R"({"builtin": {"name": "chain", "particles": 4, "gravity": 1}})"));
  ChainPendulumParams cp;
  cp.particles = 4;
  cp.gravity = 1;
  expectSameScene(chain, makeChainPendulum(cp));
  expectSameScene(loadSceneFile(write("o.json", R"({"builtin": {"name": "oscillator", "mass": 2}})")),
                  makeLinearOscillator({2.0, 1.0, 1.0}));
  EXPECT_EQ(loadSceneFile(write("t.json", R"({"builtin": {"name": "tetbar", "nx": 2, "ny": 1, "nz": 1}})")).tets.size(),
            12u);
}

TEST_F(SceneJson, PartsAreConcatenatedAndExplicitIndicesAreGlobal) {
  const Scene s = loadSceneFile(write("parts.json", R"({
    "builtin": [{"name": "oscillator"}, {"name": "chain", "particles": 3, "translate": [0, 5, 0]}],
    "particles": {"positions": [[7,7,7]], "masses": [1]},
    "springs": [{"a": 3, "b": 1, "stiffness": 1}]
  })"));
  ASSERT_EQ(s.numParticles(), 5);
  EXPECT_EQ(s.name, "parts");                                  // several parts: the file stem
  EXPECT_EQ(s.gravity, Eigen::Vector3d::Zero());               // the first builtin's gravity
  EXPECT_EQ(s.positions.row(1), Eigen::RowVector3d(0, 5, 0));  // chain translated
  EXPECT_EQ(s.pins[1].vertex, 1);                              // the chain's pin, shifted
  EXPECT_EQ(s.pins[1].target.position, Eigen::Vector3d(0, 5, 0));
  EXPECT_EQ(s.springs[0].a, 1);  // the chain's own springs, shifted
  EXPECT_EQ(s.springs.back().a, 3);
  ASSERT_EQ(s.bodies.size(), 2u);
  EXPECT_EQ(s.bodies[1].particles, (std::vector<int>{1, 2, 3}));
}

TEST_F(SceneJson, MeshesRelativeToTheSceneFile) {
  fs::create_directories(dir_ / "meshes");
  write("meshes/quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  write("meshes/one.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
  write("meshes/one.ele", "1 4 0\n0 0 1 2 3\n");
  const std::string path = write("m.json", R"({
    "mesh": [{"file": "meshes/quad.obj", "areal_density": 3, "stretch_stiffness": 7, "damping": 0.5, "name": "sheet"},
             {"file": "meshes/one.node", "density": 60, "stiffness": 9, "translate": [0, 0, 5]}],
    "pins": [{"pin_where": {"axis": "y", "min": 0.5, "max": 2}, "stiffness": 3}]
  })");
  const Scene s = loadSceneFile(path);
  ASSERT_EQ(s.numParticles(), 8);
  EXPECT_DOUBLE_EQ(s.masses[0], 2 * 3.0 * 0.5 / 3.0);  // the quad fans into 1-2-3 and 1-3-4
  EXPECT_DOUBLE_EQ(s.masses[1], 3.0 * 0.5 / 3.0);
  EXPECT_EQ(s.springs[0].stiffness, 7.0);
  EXPECT_EQ(s.bodies[0].name, "sheet");
  EXPECT_EQ(s.bodies[0].damping, 0.5);
  EXPECT_EQ(s.tets.size(), 1u);
  EXPECT_EQ(s.tets[0].stiffness, 9.0);
  EXPECT_DOUBLE_EQ(s.masses[4], 60.0 / 6.0 / 4.0);
  EXPECT_EQ(s.positions(7, 2), 6.0);
  EXPECT_EQ(s.triangles.size(), 2u);
  // pin_where picks rest y in [0.5, 2]: quad vertices 2 and 3, tet vertex 6 (0, 1, 5).
  ASSERT_EQ(s.pins.size(), 3u);
  EXPECT_EQ(s.pins[0].vertex, 2);
  EXPECT_EQ(s.pins[1].vertex, 3);
  EXPECT_EQ(s.pins[2].vertex, 6);
  EXPECT_EQ(s.pins[2].target.position, Eigen::Vector3d(0, 1, 5));
}

TEST_F(SceneJson, WhereSelectsByBoxForForceFieldsAndBodies) {
  const Scene s = loadSceneFile(write("w.json", twoParticles(R"(,
    "pins": [{"pin_where": {"min": [0.5, -1, -1], "max": [2, 1, 1]}, "stiffness": 1, "target": {"velocity": [0, 1, 0]}}],
    "force_fields": [{"where": {"axis": "x", "max": 0.5}, "force": [0, 0, 1]}],
    "bodies": [{"where": {"axis": "x", "min": 0}, "damping": 0.1}])")));
  ASSERT_EQ(s.pins.size(), 1u);
  EXPECT_EQ(s.pins[0].vertex, 1);
  EXPECT_EQ(s.pins[0].target.position, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(s.pins[0].target.velocity, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(s.force_fields[0].particles, std::vector<int>{0});
  EXPECT_EQ(s.bodies[0].particles, (std::vector<int>{0, 1}));
}

TEST_F(SceneJson, ExampleScenesLoad) {
  for (const char* name : {"chain", "cloth_handle", "tetbar", "cloth_wind", "cloth_stiff_drag"}) {
    SCOPED_TRACE(name);
    const Scene s = loadSceneFile(kScenesDir + "/" + name + ".json");
    EXPECT_GT(s.numParticles(), 0);
    EXPECT_FALSE(s.pins.empty());
  }
  ChainPendulumParams p;
  p.particles = 6;
  const Scene reference = makeChainPendulum(p);
  const Scene chain = loadSceneFile(kScenesDir + "/chain.json");
  ASSERT_EQ(chain.numParticles(), 6);
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(chain.masses[j], reference.masses[j], 1e-15);
  EXPECT_EQ(loadSceneFile(kScenesDir + "/tetbar.json").pins.size(), 4u);
  EXPECT_EQ(loadSceneFile(kScenesDir + "/cloth_handle.json").pins.size(), 2u);
  // Two fixed top corners and the hand at the bottom-right corner (1, 0, 0), moving.
  const Scene drag = loadSceneFile(kScenesDir + "/cloth_stiff_drag.json");
  ASSERT_EQ(drag.pins.size(), 3u);
  EXPECT_EQ(drag.positions.row(drag.pins[2].vertex), Eigen::RowVector3d(1, 0, 0));
  EXPECT_TRUE(drag.pins[2].target.moving());
  EXPECT_FALSE(drag.pins[0].target.moving());
  EXPECT_EQ(drag.triangle_strains.size(), 200u);  // 10 x 10 cells of cloth_square.obj, two each
}

TEST_F(SceneJson, DocumentedExampleLoads) {
  // The complete example of docs/scene-format.md, next to a copy of the mesh it names.
  std::ifstream doc(fs::path(kScenesDir).parent_path() / "docs" / "scene-format.md");
  ASSERT_TRUE(doc) << "docs/scene-format.md";
  std::string line, json;
  bool inside = false;
  while (std::getline(doc, line)) {
    if (line == "```json") {
      inside = true;
    } else if (inside && line == "```") {
      break;
    } else if (inside) {
      json += line + "\n";
    }
  }
  ASSERT_FALSE(json.empty());
  fs::copy_file(kScenesDir + "/bar.mesh", dir_ / "bar.mesh");
  const Scene s = loadSceneFile(write("showcase.json", json));
  EXPECT_EQ(s.name, "showcase");
  ASSERT_EQ(s.numParticles(), 144 + 20 + 3);
  EXPECT_EQ(s.bodies.size(), 3u);
  EXPECT_EQ(s.bodies[2].particles, (std::vector<int>{164, 165, 166}));
  EXPECT_NEAR(s.springs.back().rest_length, 0.25, 0.0);
}

// --- round trip ------------------------------------------------------------------------------------

TEST_F(SceneJson, SaveLoadRoundTripsBuiltinsExactly) {
  ClothGridParams cloth;
  cloth.nx = 7;
  cloth.ny = 5;
  cloth.damping = 0.3;
  TetBarParams bar;
  bar.nx = 3;
  for (const Scene& s : {makeClothGrid(cloth), makeTetBar(bar), makeChainPendulum(), makeLinearOscillator()}) {
    SCOPED_TRACE(s.name);
    const std::string path = (dir_ / (s.name + ".json")).string();
    saveSceneFile(s, path);
    expectSameScene(loadSceneFile(path), s);
  }
}

// Triangle strain (with strain limits) and bending hinges through their generic JSON form.
TEST_F(SceneJson, SaveLoadRoundTripsTriangleElementsExactly) {
  ClothGridParams cloth;
  cloth.nx = 6;
  cloth.ny = 4;
  cloth.model = ClothModel::Triangles;
  cloth.strain_min = 0.95;
  cloth.strain_max = 1.0 / 3.0 + 1.0;
  cloth.hinge_stiffness = 0.1 / 3.0;
  Scene s = makeClothGrid(cloth);
  s.rest_positions(7, 2) = 0.01;  // a curved rest shape: hinges with rest curvature
  ASSERT_FALSE(s.triangle_strains.empty());
  ASSERT_FALSE(s.bending_hinges.empty());
  const std::string path = (dir_ / "triangles.json").string();
  saveSceneFile(s, path);
  expectSameScene(loadSceneFile(path), s);
}

TEST_F(SceneJson, TriangleElementsInTheExplicitForm) {
  const Scene s = loadSceneFile(write("tri.json", R"({
    "particles": {"positions": [[0,0,0],[1,0,0],[0,1,0],[1,1,0.1]], "masses": 1},
    "triangle_strains": [{"vertices": [0, 1, 2], "stiffness": 50},
                         {"vertices": [1, 3, 2], "stiffness": 60, "strain_min": 0.9, "strain_max": 1.2}],
    "bending_hinges": [{"vertices": [1, 2, 0, 3], "stiffness": 0.5}]
  })"));
  ASSERT_EQ(s.triangle_strains.size(), 2u);
  EXPECT_EQ(s.triangle_strains[0].vertices, (std::array<int, 3>{0, 1, 2}));
  EXPECT_EQ(s.triangle_strains[0].strain_min, 1.0);  // defaults
  EXPECT_EQ(s.triangle_strains[0].strain_max, 1.0);
  EXPECT_EQ(s.triangle_strains[1].stiffness, 60.0);
  EXPECT_EQ(s.triangle_strains[1].strain_min, 0.9);
  EXPECT_EQ(s.triangle_strains[1].strain_max, 1.2);
  ASSERT_EQ(s.bending_hinges.size(), 1u);
  EXPECT_EQ(s.bending_hinges[0].vertices, (std::array<int, 4>{1, 2, 0, 3}));
  EXPECT_EQ(s.bending_hinges[0].stiffness, 0.5);
}

TEST_F(SceneJson, TriangleElementErrorsNameTheField) {
  const std::string particles = R"("particles": {"positions": [[0,0,0],[1,0,0],[0,1,0],[2,0,0]], "masses": 1})";
  expectError("{" + particles + R"(, "triangle_strains": [{"vertices": [0, 1], "stiffness": 1}]})",
              "triangle_strains[0].vertices: expected 3 particle indices, got 2");
  expectError("{" + particles + R"(, "triangle_strains": [{"vertices": [0, 1, 2]}]})",
              "triangle_strains[0]: missing field 'stiffness'");
  expectError("{" + particles + R"(, "triangle_strains": [{"vertices": [0, 1, 9], "stiffness": 1}]})",
              "triangle_strains[0].vertices[2]: particle index 9 out of range [0, 4)");
  expectError("{" + particles + R"(, "bending_hinges": [{"vertices": [0, 1, 2, 3], "stifness": 1}]})",
              "bending_hinges[0]: unknown field 'stifness'");
  // Rest-state errors come from validation, which names the element.
  expectError("{" + particles + R"(, "triangle_strains": [{"vertices": [0, 1, 3], "stiffness": 1}]})",
              "top level: triangle strain 0: degenerate rest triangle (0, 1, 3), area 0");
}

TEST_F(SceneJson, TriangleClothFromBuiltinAndMesh) {
  const Scene grid = loadSceneFile(write("tc.json", R"({"builtin": {"name": "cloth", "nx": 4, "ny": 3,
    "model": "triangles", "strain_stiffness": 200, "strain_max": 1.1, "hinge_stiffness": 0.02}})"));
  ClothGridParams p;
  p.nx = 4;
  p.ny = 3;
  p.model = ClothModel::Triangles;
  p.strain_stiffness = 200;
  p.strain_max = 1.1;
  p.hinge_stiffness = 0.02;
  expectSameScene(grid, makeClothGrid(p));
  EXPECT_TRUE(grid.springs.empty());
  EXPECT_EQ(grid.triangle_strains.size(), 12u);
  expectError(R"({"builtin": {"name": "cloth", "model": "beams"}})",
              "builtin.model: unknown cloth model 'beams' (expected springs or triangles)");

  write("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const Scene mesh = loadSceneFile(write("tm.json", R"({"mesh": {"file": "quad.obj", "model": "triangles",
    "strain_stiffness": 30, "strain_min": 0.5, "hinge_stiffness": 0.25}})"));
  EXPECT_TRUE(mesh.springs.empty());
  ASSERT_EQ(mesh.triangle_strains.size(), 2u);
  EXPECT_EQ(mesh.triangle_strains[1].stiffness, 30.0);
  EXPECT_EQ(mesh.triangle_strains[1].strain_min, 0.5);
  ASSERT_EQ(mesh.bending_hinges.size(), 1u);  // the quad's diagonal 1-3
  EXPECT_EQ(mesh.bending_hinges[0].vertices, (std::array<int, 4>{0, 2, 1, 3}));
  EXPECT_EQ(mesh.bending_hinges[0].stiffness, 0.25);
}

TEST_F(SceneJson, SaveLoadRoundTripsAwkwardNumbersExactly) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene s = makeChainPendulum();
  s.name = "odd \"name\" \\ with ünïcode";
  for (Eigen::Index i = 0; i < s.positions.size(); ++i) s.positions.data()[i] += u(rng) * 1e-3;
  s.velocities.setRandom();
  s.velocities(0, 0) = -0.0;
  s.velocities(1, 1) = 5e-324;  // denormal
  s.masses[2] = 1.0 / 3.0;
  s.masses[3] = 1e300;
  s.gravity = Eigen::Vector3d(-0.0, -9.81, 1e-17);
  s.springs[0].stiffness = 0.1 + 0.2;
  s.pins[0].target.velocity = Eigen::Vector3d(0.1, 0, 0);
  s.pins[0].target.amplitude = Eigen::Vector3d(0, 0.7, 0);
  s.pins[0].target.frequency = 1.0 / 7.0;
  Pin plain;
  plain.vertex = 4;
  plain.stiffness = 3;
  plain.target.frequency = -0.0;
  s.pins.push_back(plain);
  ForceField f;
  f.particles = {1, 3};
  f.force = Eigen::Vector3d(u(rng), u(rng), u(rng));
  f.frequency = 2.5;
  s.force_fields.push_back(f);
  s.force_fields.push_back(ForceField{});
  s.bodies.push_back(Body{"empty", {}, 1.0});
  const std::string path = (dir_ / "odd.json").string();
  saveSceneFile(s, path);
  expectSameScene(loadSceneFile(path), s);
}

TEST_F(SceneJson, SaveRejectsInvalidScenesAndUnwritablePaths) {
  Scene s = makeChainPendulum();
  s.masses[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(saveSceneFile(s, (dir_ / "nan.json").string()), InvalidInputError);
  const std::string bad = (dir_ / "no" / "such" / "dir.json").string();
  try {
    saveSceneFile(makeChainPendulum(), bad);
    ADD_FAILURE() << "expected a FileFormatError";
  } catch (const FileFormatError& e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_THAT(e.what(), HasSubstr("cannot open file for writing"));
  }
}

// --- errors: files and syntax ------------------------------------------------------------------------

TEST_F(SceneJson, MissingFile) {
  const std::string path = (dir_ / "absent.json").string();
  try {
    loadSceneFile(path);
    ADD_FAILURE();
  } catch (const FileFormatError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(std::string(e.what()), path + ": cannot open file: No such file or directory");
  }
}

TEST_F(SceneJson, MalformedJsonNamesTheLine) {
  expectError("{\n  \"particles\": {\n    \"positions\": [[0,0,0],]\n  }\n}\n",
              "malformed JSON (column 27): syntax error while parsing value - unexpected ']'", 3);
  expectError("", "malformed JSON", 1);
  expectError("{\"name\": \"x\"} trailing", "malformed JSON", 1);
}

TEST_F(SceneJson, TopLevelErrors) {
  expectError("[1, 2]", "top level: expected an object, got array");
  expectError("{}", "top level: no particles: give particles, builtin or mesh");
  expectError(twoParticles(R"(, "sprngs": [])"), "top level: unknown field 'sprngs' (expected one of: ");
  expectError(twoParticles(R"(, "format": "other")"), "format: expected \"stabint-scene\", got \"other\"");
  expectError(twoParticles(R"(, "version": 2)"), "version: unsupported version 2");
  expectError(twoParticles(R"(, "name": 5)"), "name: expected a string, got number");
  expectError(twoParticles(R"(, "gravity": [0, -9.81])"),
              "gravity: expected an array of 3 numbers [x, y, z], got [0,-9.81]");
  expectError(twoParticles(R"(, "gravity": [0, "down", 0])"), "gravity[1]: expected a number, got string");
  expectError(twoParticles(R"(, "gravity": [0, 1e999, 0])"), "number overflow parsing '1e999'", 1);
}

// A number too large for a double comes from the parser without a position; the number it quotes
// is found outside strings (a name holding the same text does not count) to give the line.
TEST_F(SceneJson, NumberOverflowNamesItsLine) {
  expectError("{\n  \"name\": \"-1e400\",\n  \"particles\": {\"positions\": [[0,0,0]],\n    \"masses\": -1e400}\n}\n",
              "malformed JSON (column 15): number overflow parsing '-1e400'", 4);
}

TEST_F(SceneJson, ParticleErrors) {
  expectError(R"({"particles": []})", "particles: expected an object, got array");
  expectError(R"({"particles": {"masses": [1]}})", "particles: missing field 'positions'");
  expectError(R"({"particles": {"positions": [[0,0,0]], "mass": 1}})", "particles: unknown field 'mass'");
  expectError(R"({"particles": {"positions": [[0,0,0]]}})", "particles: needs masses, or density");
  expectError(R"({"particles": {"positions": [[0,0,0]], "masses": [1, 2]}})",
              "particles.masses: has 2 entries, expected 1 (one per position)");
  expectError(R"({"particles": {"positions": [[0,0,0]], "masses": [0]}})", "particles.masses[0]: must be > 0, got 0");
  expectError(R"({"particles": {"positions": [[0,0,0]], "masses": -1}})", "particles.masses: must be > 0, got -1");
  expectError(R"({"particles": {"positions": [[0,0,0]], "masses": 1, "density": 2}})",
              "particles.masses: give either masses or density/areal_density, not both");
  expectError(R"({"particles": {"positions": [[0,0,0]], "density": 1}})",
              "particles: particle 0 gets no mass from density/areal_density");
  expectError(R"({"particles": {"positions": [[0,0,0]], "velocities": [], "masses": 1}})",
              "particles.velocities: has 0 rows, expected 1 (one per position)");
  expectError(R"({"particles": {"positions": [[0,0,0], [0,0]], "masses": 1}})",
              "particles.positions[1]: expected an array of 3 numbers");
  expectError(R"({"particles": {"positions": [[0,0,"z"]], "masses": 1}})",
              "particles.positions[0][2]: expected a number, got string");
  expectError(R"({"particles": {"positions": [[0,0,0]], "rest_positions": [[0,0,true]], "masses": 1}})",
              "particles.rest_positions[0][2]: expected a number, got boolean");
}

TEST_F(SceneJson, ElementErrors) {
  expectError(twoParticles(R"(, "springs": {"a": 0})"), "springs: expected an array, got object");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 1, "stiffness": "stiff"}])"),
              "springs[0].stiffness: expected a number, got string");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 1}])"), "springs[0]: missing field 'stiffness'");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 2, "stiffness": 1}])"),
              "springs[0].b: particle index 2 out of range [0, 2)");
  expectError(twoParticles(R"(, "springs": [{"a": 0.5, "b": 1, "stiffness": 1}])"),
              "springs[0].a: expected an integer, got 0.5");
  expectError(twoParticles(R"(, "springs": [{"a": 1, "b": 1, "stiffness": 1}])"),
              "springs[0].b: spring joins particle 1 to itself");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 1, "stiffness": -1}])"),
              "springs[0].stiffness: must be >= 0, got -1");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 1, "stiffness": 1, "rest_length": -2}])"),
              "springs[0].rest_length: must be >= 0, got -2");
  expectError(twoParticles(R"(, "springs": [{"a": 0, "b": 1, "stiffness": 1, "k": 2}])"),
              "springs[0]: unknown field 'k'");
  expectError(twoParticles(R"(, "springs": [{"a": 99999999999, "b": 1, "stiffness": 1}])"),
              "springs[0].a: integer out of range");
  expectError(twoParticles(R"(, "tets": [{"vertices": [0, 1, 0], "stiffness": 1}])"),
              "tets[0].vertices: expected 4 particle indices, got 3");
  expectError(R"({"particles": {"positions": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "masses": 1},
                  "tets": [{"vertices": [0, 2, 1, 3], "stiffness": 1}]})",
              "tets[0].vertices: rest volume -0.166667 is not positive");
  expectError(twoParticles(R"(, "triangles": [[0, 1]])"), "triangles[0]: expected 3 particle indices, got 2");
  expectError(twoParticles(R"(, "triangles": [[0, 1, 5]])"), "triangles[0][2]: particle index 5 out of range [0, 2)");
}

TEST_F(SceneJson, PinErrors) {
  expectError(twoParticles(R"(, "pins": [{"stiffness": 1}])"), "pins[0]: needs vertex or pin_where");
  expectError(twoParticles(R"(, "pins": [{"vertex": 0}])"), "pins[0]: missing field 'stiffness'");
  expectError(twoParticles(R"(, "pins": [{"vertex": 0, "pin_where": {"axis": "x", "max": 1}, "stiffness": 1}])"),
              "pins[0].pin_where: give either vertex or pin_where, not both");
  expectError(twoParticles(R"(, "pins": [{"vertex": 0, "stiffness": 1, "target": {"speed": [1,0,0]}}])"),
              "pins[0].target: unknown field 'speed'");
  expectError(twoParticles(R"(, "pins": [{"vertex": 0, "stiffness": 1, "target": {"frequency": "fast"}}])"),
              "pins[0].target.frequency: expected a number, got string");
  expectError(
      twoParticles(
          R"(, "pins": [{"pin_where": {"axis": "x", "max": 1}, "stiffness": 1, "target": {"position": [0,0,0]}}])"),
      "pins[0].target.position: not allowed with pin_where");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {"axis": "w", "max": 1}, "stiffness": 1}])"),
              "pins[0].pin_where.axis: expected \"x\", \"y\" or \"z\", got \"w\"");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {"axis": "x"}, "stiffness": 1}])"),
              "pins[0].pin_where: needs min, max or both");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {"axis": "x", "min": 5}, "stiffness": 1}])"),
              "pins[0].pin_where: selects no particle");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {}, "stiffness": 1}])"),
              "pins[0].pin_where: needs \"axis\" with min/max");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {"min": [0, 0]}, "stiffness": 1}])"),
              "pins[0].pin_where.min: expected an array of 3 numbers");
  expectError(twoParticles(R"(, "pins": [{"pin_where": {"axis": "x", "max": 1, "min": [0,0,0]}, "stiffness": 1}])"),
              "pins[0].pin_where.min: expected a number, got array");
}

TEST_F(SceneJson, ForceFieldAndBodyErrors) {
  expectError(twoParticles(R"(, "force_fields": [{"force": [1, 0]}])"),
              "force_fields[0].force: expected an array of 3 numbers");
  expectError(twoParticles(R"(, "force_fields": [{"particles": [0, 7]}])"),
              "force_fields[0].particles[1]: particle index 7 out of range [0, 2)");
  expectError(twoParticles(R"(, "force_fields": [{"particles": [0], "where": {"axis": "x", "max": 1}}])"),
              "force_fields[0].where: give either particles or where, not both");
  expectError(twoParticles(R"(, "bodies": [{"damping": 1.5}])"), "bodies[0].damping: must be in [0, 1], got 1.5");
  expectError(twoParticles(R"(, "bodies": [{"name": 3}])"), "bodies[0].name: expected a string, got number");
  expectError(twoParticles(R"(, "bodies": [{"particles": [0, 0]}])"), "top level: body 0: particle 0 listed twice");
}

TEST_F(SceneJson, BuiltinAndMeshErrors) {
  expectError(R"({"builtin": {"nx": 3}})", "builtin: missing field 'name'");
  expectError(R"({"builtin": {"name": "rope"}})", "builtin.name: unknown built-in scene 'rope'");
  expectError(R"({"builtin": {"name": "cloth", "nx": "many"}})", "builtin.nx: expected an integer, got string");
  expectError(R"({"builtin": {"name": "cloth", "nz": 3}})", "builtin: unknown field 'nz'");
  expectError(R"({"builtin": {"name": "cloth", "nx": 1}})", "builtin: cloth nx = 1 must be >= 2");
  expectError(R"({"builtin": [{"name": "chain"}, {"name": "chain", "stiffness": -1}]})",
              "builtin[1]: spring 0: stiffness -1 must be >= 0");
  expectError(R"({"mesh": {"type": "obj"}})", "mesh: missing field 'file'");
  expectError(R"({"mesh": {"file": "x.stl"}})", "mesh.file: cannot tell the mesh type from 'x.stl'");
  expectError(R"({"mesh": {"file": "x.stl", "type": "stl"}})", "mesh.type: unknown mesh type 'stl'");
  expectError(R"({"mesh": {"file": "absent.obj"}})",
              "mesh.file: " + (dir_ / "absent.obj").string() + ": cannot open file");
  write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  expectError(R"({"mesh": {"file": "bad.obj"}})",
              "mesh.file: " + (dir_ / "bad.obj").string() + ":3: face 1: vertex index 3 out of range");
  write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expectError(R"({"mesh": {"file": "ok.obj", "density": 3}})", "mesh: unknown field 'density'");
  expectError(R"({"mesh": [{"file": "ok.obj"}, {"file": "ok.obj", "damping": 2}]})",
              "mesh[1].damping: must be in [0, 1], got 2");
}

TEST_F(SceneJson, BuiltinSceneFromParameterText) {
  const Scene cloth = builtinScene("cloth", R"({"nx": 3, "ny": 3})", "cli");
  EXPECT_EQ(cloth.numParticles(), 9);
  EXPECT_EQ(cloth.triangles.size(), 8u);
  try {
    builtinScene("cloth", R"({"nx": "3"})", "builtin scene 'cloth'");
    ADD_FAILURE();
  } catch (const FileFormatError& e) {
    EXPECT_EQ(std::string(e.what()), "builtin scene 'cloth': params.nx: expected an integer, got string");
  }
  EXPECT_THROW(builtinScene("rope", "{}", "cli"), FileFormatError);
  EXPECT_EQ(builtinSceneParameters("tetbar").size(), 9u);
}

}  // namespace
}  // namespace stabint
