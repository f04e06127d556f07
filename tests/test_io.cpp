// Mesh loaders: OBJ cloth, TetGen and Medit solids. Files are written into a temporary
// directory by each test; errors must name the file and the right line.
#include <stabint/errors.hpp>
#include <stabint/io.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "temp_dir_test.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <unistd.h>

namespace stabint {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class MeshFiles : public testing::TempDirTest {
 protected:
};

// The FileFormatError `load` throws; a failed expectation when it throws nothing.
std::optional<FileFormatError> formatError(const std::function<void()>& load) {
  try {
    load();
  } catch (const FileFormatError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a FileFormatError";
  return std::nullopt;
}

// Checks file, line and a part of the message; the message itself must carry "file:line".
void expectError(const std::function<void()>& load, const std::string& file, int line, const std::string& part) {
  const auto e = formatError(load);
  if (!e) return;
  EXPECT_EQ(e->file(), file);
  EXPECT_EQ(e->line(), line) << e->what();
  const std::string where = line > 0 ? file + ":" + std::to_string(line) + ": " : file + ": ";
  EXPECT_THAT(e->what(), HasSubstr(where));
  EXPECT_THAT(e->what(), HasSubstr(part));
}

fs::path scenesDir() { return fs::path(STABINT_TEST_DATA_DIR).parent_path().parent_path() / "scenes"; }

// --- OBJ ------------------------------------------------------------------------------------------

const char* const kUnitSquareObj =
    "# unit square as one quad\n"
    "mtllib cloth.mtl\n"
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0   # comment after data\n"
    "v 0 1 0\n"
    "vt 0 0\n"
    "vn 0 0 1\n"
    "g square\n"
    "s off\n"
    "f 1/1/1 2/1/1 3//1 4\n";

TEST_F(MeshFiles, ObjQuadIsFannedIntoTwoTriangles) {
  const ClothMaterial material{0.2, 500.0, 5.0};
  const Scene s = loadObjCloth(write("square.obj", kUnitSquareObj), material);
  EXPECT_EQ(s.name, "square");
  ASSERT_EQ(s.numParticles(), 4);
  EXPECT_TRUE(s.positions.row(2).isApprox(Eigen::RowVector3d(1, 1, 0)));
  EXPECT_EQ(s.rest_positions, s.positions);
  EXPECT_TRUE(s.velocities.isZero());
  // Fan (1,2,3), (1,3,4): vertices 1 and 3 touch both triangles.
  const double sixth = 0.2 * 0.5 / 3.0;
  EXPECT_NEAR(s.masses[0], 2 * sixth, 1e-15);
  EXPECT_NEAR(s.masses[1], sixth, 1e-15);
  EXPECT_NEAR(s.masses[2], 2 * sixth, 1e-15);
  EXPECT_NEAR(s.masses[3], sixth, 1e-15);
  // Five edges and one hinge across the diagonal 1-3, joining 2 and 4.
  ASSERT_EQ(s.springs.size(), 6u);
  EXPECT_EQ(s.springs[5].a, 1);
  EXPECT_EQ(s.springs[5].b, 3);
  EXPECT_EQ(s.springs[5].stiffness, 5.0);
  EXPECT_EQ(s.springs[0].stiffness, 500.0);
  EXPECT_TRUE(s.pins.empty());
  EXPECT_TRUE(s.tets.empty());
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].damping, 0.0);
  EXPECT_EQ(s.bodies[0].particles.size(), 4u);
  EXPECT_TRUE(s.gravity.isApprox(Eigen::Vector3d(0, -9.81, 0)));
  EXPECT_NO_THROW(validateScene(s));
}

TEST_F(MeshFiles, ObjNegativeIndicesAndPolygons) {
  const Scene quad = loadObjCloth(write("neg.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n"));
  ASSERT_EQ(quad.springs.size(), 6u);
  EXPECT_NEAR(quad.masses.sum(), 0.1, 1e-15);
  // A pentagon: three triangles, seven edges, two hinges.
  const Scene penta = loadObjCloth(write("penta.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n"));
  EXPECT_EQ(penta.springs.size(), 7u + 2u);
  EXPECT_NEAR(penta.masses.sum(), 0.1 * 3.0, 1e-15);
}

TEST_F(MeshFiles, ObjErrorsNameFileLineAndProblem) {
  const std::string missing = (dir_ / "nope.obj").string();
  expectError([&] { loadObjCloth(missing); }, missing, 0, "cannot open file");

  std::string f = write("badnum.obj", "# header\nv 0 0 0\nv 0 x 0\n");
  expectError([&] { loadObjCloth(f); }, f, 3, "expected a number for vertex 2 coordinate y, got 'x'");

  f = write("nan.obj", "v 0 0 0\n\nv nan 0 0\n");
  expectError([&] { loadObjCloth(f); }, f, 3, "vertex 2 coordinate x is not finite ('nan')");

  f = write("short.obj", "v 0 0 0\nv 1 0\n");
  expectError([&] { loadObjCloth(f); }, f, 2, "vertex 2: expected 'v <x> <y> <z>'");
  // After x y z a weight, a colour or both, each a number; any other count is refused.
  f = write("extra.obj", "v 0 0 0\nv 1 0 0 1 0.5\n");
  expectError([&] { loadObjCloth(f); }, f, 2, "vertex 2: expected 'v <x> <y> <z>' with an optional <w>");
  f = write("colour.obj", "v 0 0 0 1 red 0\n");
  expectError([&] { loadObjCloth(f); }, f, 1, "expected a number for vertex 1 value 5, got 'red'");
  f = write("weighted.obj", "v 0 0 0 1\nv 1 0 0 0.2 0.3 0.4\nv 0 1 0 1 0.2 0.3 0.4\nf 1 2 3\n");
  EXPECT_EQ(loadObjCloth(f).numParticles(), 3);

  f = write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 7\n");
  expectError([&] { loadObjCloth(f); }, f, 5, "face 2: vertex index 7 out of range [1, 3]");

  f = write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  expectError([&] { loadObjCloth(f); }, f, 4, "face 1: vertex index 0 is invalid");

  f = write("back.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  expectError([&] { loadObjCloth(f); }, f, 4, "face 1: relative vertex index -4 points before the first vertex");

  f = write("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  expectError([&] { loadObjCloth(f); }, f, 3, "face 1: needs at least 3 vertices, got 2");

  f = write("twice.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1\n");
  expectError([&] { loadObjCloth(f); }, f, 4, "face 1: vertex 1 appears twice");

  f = write("idx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.5\n");
  expectError([&] { loadObjCloth(f); }, f, 4, "expected an integer for face 1 vertex index, got '3.5'");

  f = write("noface.obj", "v 0 0 0\nv 1 0 0\n");
  expectError([&] { loadObjCloth(f); }, f, 2, "no faces");
}

// --- TetGen ---------------------------------------------------------------------------------------

// Points 1..4 are the unit corner tet, 5 = (1,1,1) caps the face (2,3,4). Attributes and
// boundary markers present, to be ignored.
const char* const kPoints =
    "1 0 0 0  7.5 1\n"
    "2 1 0 0  7.5 1\n"
    "\n"
    "3 0 1 0  7.5 1   # trailing comment\n"
    "4 0 0 1  7.5 1\n"
    "5 1 1 1  7.5 0\n";
const std::string kNodesOneBased = std::string("# five points\n5 3 1 1\n") + kPoints;
// And 6 = (1,1,0), in the plane of (1,2,3), on line 9.
const std::string kNodesWithPlanarPoint = std::string("# six points\n6 3 1 1\n") + kPoints + "6 1 1 0  7.5 0\n";

std::string zeroBased(const std::string& one_based_nodes) {
  std::string out;
  std::istringstream in(one_based_nodes);
  int row = 0;
  for (std::string line; std::getline(in, line); ++row) {
    if (row >= 2 && !line.empty()) line[0] = static_cast<char>(line[0] - 1);
    out += line + "\n";
  }
  return out;
}

TEST_F(MeshFiles, TetGenOneBased) {
  write("two.node", kNodesOneBased);
  write("two.ele", "# tets\n2 4 0\n1 1 2 3 4\n2 5 2 4 3\n");
  const SolidMaterial material{300.0, 2e4};
  const Scene s = loadTetGen((dir_ / "two").string(), material);
  EXPECT_EQ(s.name, "two");
  ASSERT_EQ(s.numParticles(), 5);
  EXPECT_TRUE(s.positions.row(4).isApprox(Eigen::RowVector3d(1, 1, 1)));
  ASSERT_EQ(s.tets.size(), 2u);
  EXPECT_EQ(s.tets[0].vertices, (std::array<int, 4>{0, 1, 2, 3}));
  EXPECT_EQ(s.tets[1].vertices, (std::array<int, 4>{4, 1, 3, 2}));
  EXPECT_EQ(s.tets[1].stiffness, 2e4);
  EXPECT_NEAR(s.masses.sum(), 300.0 * (1.0 / 6 + 1.0 / 3), 1e-12);
  EXPECT_NEAR(s.masses[0], 300.0 / 24, 1e-12);
  EXPECT_TRUE(s.velocities.isZero());
  EXPECT_EQ(s.bodies.size(), 1u);
  EXPECT_NO_THROW(validateScene(s));
}

TEST_F(MeshFiles, TetGenZeroBasedAndExtensionInPath) {
  write("z.node", zeroBased(kNodesOneBased));
  const std::string ele = write("z.ele", "2 4 1\n0 0 1 2 3 9.0\n1 4 1 3 2 9.0\n");
  const Scene a = loadTetGen((dir_ / "z").string());
  const Scene b = loadTetGen(ele);
  ASSERT_EQ(a.tets.size(), 2u);
  EXPECT_EQ(a.tets[1].vertices, (std::array<int, 4>{4, 1, 3, 2}));
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.masses, b.masses);
}

TEST_F(MeshFiles, TetGenMeshWideNegativeOrientationIsReoriented) {
  write("neg.node", kNodesOneBased);
  write("neg.ele", "2 4 0\n1 1 3 2 4\n2 5 4 2 3\n");
  const Scene s = loadTetGen((dir_ / "neg").string());
  for (const Tet& t : s.tets) EXPECT_GT(signedVolume(s.rest_positions, t.vertices), 0.0);
  EXPECT_NEAR(s.masses.sum(), 1000.0 * 0.5, 1e-9);
  EXPECT_NO_THROW(validateScene(s));
}

TEST_F(MeshFiles, TetGenErrors) {
  const std::string node6 = write("m.node", kNodesWithPlanarPoint);
  std::string ele = write("m.ele", "# mixed\n2 4 0\n1 1 2 3 4\n2 5 4 2 3\n");
  const std::string base = (dir_ / "m").string();
  expectError([&] { loadTetGen(base); }, ele, 4, "tet 2: mixed orientation");

  ele = write("m.ele", "2 4 0\n1 1 2 3 4\n\n7 1 2 3 6\n");
  expectError([&] { loadTetGen(base); }, ele, 4,
              "tet 7: zero rest volume 0 for its longest edge L = 1.41421 (degenerate: at most 1e-12 L^3)");

  // A point in no tet would have no mass; it used to get a made-up one (1e-6 kg).
  write("m.ele", "1 4 0\n1 1 2 3 4\n");
  expectError([&] { loadTetGen(base); }, node6, 8, "point 5 is in no tetrahedron, so it would have no mass");

  ele = write("m.ele", "2 4 0\n1 1 2 3 4\n2 5 2 4 9\n");
  expectError([&] { loadTetGen(base); }, ele, 3, "tet 2: vertex index 9 out of range [1, 7)");

  ele = write("m.ele", "2 4 0\n1 1 2 3 4\n2 0 2 4 3\n");
  expectError([&] { loadTetGen(base); }, ele, 3, "tet 2: vertex index 0 out of range [1, 7)");

  ele = write("m.ele", "3 4 0\n1 1 2 3 4\n2 5 2 4 3\n");
  expectError([&] { loadTetGen(base); }, ele, 3, "unexpected end of file, expected tetrahedron 2 of 3");

  ele = write("m.ele", "2 4 0\n1 1 2 3\n");
  expectError([&] { loadTetGen(base); }, ele, 2,
              "tetrahedron 0: expected 5 fields (<index>, 4 node numbers, 0 attributes), got 4");
  // A line has the fields its header announces, no more: a trailing token, or an attribute the
  // header does not count, would be read as data of another column.
  ele = write("m.ele", "1 4 0\n1 1 2 3 4 5\n");
  expectError([&] { loadTetGen(base); }, ele, 2,
              "tetrahedron 0: expected 5 fields (<index>, 4 node numbers, 0 attributes), got 6");
  ele = write("m.ele", "1 4 1\n1 1 2 3 4\n");
  expectError([&] { loadTetGen(base); }, ele, 2,
              "tetrahedron 0: expected 6 fields (<index>, 4 node numbers, 1 attributes), got 5");
  ele = write("m.ele", "1 4 1\n1 1 2 3 4 heavy\n");
  expectError([&] { loadTetGen(base); }, ele, 2, "tet 1 attribute 0");
  ele = write("m.ele", "1 4 0 0\n1 1 2 3 4\n");
  expectError([&] { loadTetGen(base); }, ele, 1,
              "the .ele header is '<#tetrahedra> <nodes per tet> [<#attributes>]', got 4 fields");

  ele = write("m.ele", "2 8 0\n");
  expectError([&] { loadTetGen(base); }, ele, 1, "nodes per tetrahedron 8 must be 4 or 10");

  const std::string node = write("n.node", "# points\n\n3 3 0 0\n1 0 0 0\n2 1 0 0\n");
  write("n.ele", "0 4 0\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 5, "unexpected end of file, expected point 2 of 3");

  write("n.node", "2 2 0 0\n1 0 0\n2 1 0\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 1, "dimension 2 is not supported");

  write("n.node", "two 3 0 0\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 1,
              "expected an integer for number of points, got 'two'");

  write("n.node", "2 3 0 0\n1 0 0 0\n3 1 0 0\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 3, "point numbered 3, expected 2");

  write("n.node", "2 3 0 0\n1 0 0 0\n2 1 inf 0\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 3, "point 2 coordinate y is not finite");

  write("n.node", "2 3 0 0\n1 0 0 0\n2 1 0 0 7.5\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 3,
              "point 1: expected 4 fields (<index> <x> <y> <z>, 0 attributes, 0 boundary markers), got 5");
  write("n.node", "2 3 1 1\n1 0 0 0 7.5 1\n2 1 0 0 7.5\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 3,
              "point 1: expected 6 fields (<index> <x> <y> <z>, 1 attributes, 1 boundary markers), got 5");
  write("n.node", "2 3 0 2\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 1, "number of boundary markers 2 must be at most 1");
  write("n.node", "2 3 0 1\n1 0 0 0 1\n2 1 0 0 b\n");
  expectError([&] { loadTetGen((dir_ / "n").string()); }, node, 3, "point 2 marker");

  const std::string missing_base = (dir_ / "absent").string();
  expectError([&] { loadTetGen(missing_base); }, missing_base + ".node", 0, "cannot open file");
  write("only.node", kNodesOneBased);
  expectError([&] { loadTetGen((dir_ / "only").string()); }, (dir_ / "only.ele").string(), 0, "cannot open file");
}

// --- Medit ----------------------------------------------------------------------------------------

TEST_F(MeshFiles, MeditWithSkippedSectionsAndFreeLayout) {
  const std::string path = write("two.mesh",
                                 "MeshVersionFormatted 2\n"
                                 "# keyword and count on separate lines, as some writers do\n"
                                 "Dimension\n3\n"
                                 "Vertices 5\n"
                                 "0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n1 1 1 2\n"
                                 "Triangles\n1\n1 2 3 4\n"
                                 "Tetrahedra\n2\n"
                                 "1 2 3 4 0\n"
                                 "5 2 4 3 0\n"
                                 "Corners 2 1 2\n"
                                 "End\n");
  const Scene s = loadMedit(path, SolidMaterial{10.0, 7.0});
  EXPECT_EQ(s.name, "two");
  ASSERT_EQ(s.numParticles(), 5);
  ASSERT_EQ(s.tets.size(), 2u);
  EXPECT_EQ(s.tets[1].vertices, (std::array<int, 4>{4, 1, 3, 2}));
  EXPECT_EQ(s.tets[0].stiffness, 7.0);
  EXPECT_NEAR(s.masses.sum(), 10.0 * 0.5, 1e-12);
  EXPECT_NO_THROW(validateScene(s));
}

TEST_F(MeshFiles, MeditNegativeOrientationAndErrors) {
  const std::string head =
      "MeshVersionFormatted 1\nDimension 3\nVertices\n5\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n1 1 1 0\n";
  // Lines 1-9 are the head; the tetrahedra start at line 12.
  std::string path = write("neg.mesh", head + "Tetrahedra\n2\n1 3 2 4 0\n5 4 2 3 0\nEnd\n");
  const Scene s = loadMedit(path);
  for (const Tet& t : s.tets) EXPECT_GT(signedVolume(s.rest_positions, t.vertices), 0.0);

  path = write("mixed.mesh", head + "Tetrahedra\n2\n1 3 2 4 0\n5 2 4 3 0\nEnd\n");
  expectError([&] { loadMedit(path); }, path, 12, "tet 1: mixed orientation");

  path = write("range.mesh", head + "Tetrahedra\n2\n1 2 3 4 0\n5 2 4 6 0\nEnd\n");
  expectError([&] { loadMedit(path); }, path, 13, "tet 2: vertex index 6 out of range [1, 6)");

  path = write("short.mesh", head + "Tetrahedra\n3\n1 2 3 4 0\n5 2 4 3 0\n");
  expectError([&] { loadMedit(path); }, path, 13, "unexpected end of file, expected tet 3 of 3");

  // A record without its reference: the error is at the record's line, not at the keyword that
  // was read in its place.
  path = write("noref.mesh", head + "Tetrahedra\n2\n1 3 2 4 0\n5 4 2 3\n\nEnd\n");
  expectError([&] { loadMedit(path); }, path, 13,
              "tet 2: no reference after its numbers (found the keyword 'End' on line 15)");
  path = write("novref.mesh", "Dimension 3\nVertices 2\n0 0 0 0\n1 0 0\nTetrahedra 0\n");
  expectError([&] { loadMedit(path); }, path, 4,
              "vertex 2: no reference after its numbers (found the keyword 'Tetrahedra' on line 5)");

  path = write("notets.mesh", head + "End\n");
  expectError([&] { loadMedit(path); }, path, 10, "no Tetrahedra section");

  path = write("dim.mesh", "MeshVersionFormatted 1\nDimension 2\n");
  expectError([&] { loadMedit(path); }, path, 2, "dimension 2 is not supported");

  path = write("coord.mesh", "Dimension 3\nVertices 2\n0 0 0 0\n1 zero 0 0\n");
  expectError([&] { loadMedit(path); }, path, 4, "expected a number for vertex 2 coordinate y, got 'zero'");

  path = write("order.mesh", "Dimension 3\nTetrahedra 0\n");
  expectError([&] { loadMedit(path); }, path, 2, "Tetrahedra section before the Vertices section");

  const std::string missing = (dir_ / "missing.mesh").string();
  expectError([&] { loadMedit(missing); }, missing, 0, "cannot open file");
}

// --- example meshes shipped in scenes/ ------------------------------------------------------------

TEST(ExampleScenes, ClothSquareObjLoads) {
  const Scene s = loadObjCloth((scenesDir() / "cloth_square.obj").string());
  EXPECT_EQ(s.numParticles(), 121);
  // 10 x 10 quads, each fanned along one diagonal: 110 + 110 + 100 edges, then the hinges.
  EXPECT_GT(s.springs.size(), 320u);
  EXPECT_NEAR(s.masses.sum(), 0.1, 1e-12);
  EXPECT_NEAR(s.positions.col(1).maxCoeff(), 1.0, 1e-12);
  EXPECT_NO_THROW(validateScene(s));
}

TEST(ExampleScenes, BarLoadsFromTetGenAndMeditAlike) {
  const Scene tetgen = loadTetGen((scenesDir() / "bar").string());
  const Scene medit = loadMedit((scenesDir() / "bar.mesh").string());
  EXPECT_EQ(tetgen.numParticles(), 20);
  EXPECT_EQ(tetgen.tets.size(), 24u);
  EXPECT_NEAR(tetgen.masses.sum(), 1000.0 * 1.0 * 0.25 * 0.25, 1e-9);
  EXPECT_EQ(tetgen.positions, medit.positions);
  ASSERT_EQ(tetgen.tets.size(), medit.tets.size());
  for (size_t i = 0; i < tetgen.tets.size(); ++i) EXPECT_EQ(tetgen.tets[i].vertices, medit.tets[i].vertices);
  EXPECT_NO_THROW(validateScene(tetgen));
}

}  // namespace
}  // namespace stabint
