// Hostile input (issue 12): every malformed file, path, size or option is a named stabint::Error
// of the documented type — never a crash, a hang, a std::bad_alloc or an unexplained error — and
// leaves the caller's data as it was. One test per class of defect; each failed before its fix.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>
#include <stabint/io.hpp>
#include <stabint/simulator.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "temp_dir_test.hpp"

#include <climits>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace stabint {
namespace {

using ::testing::HasSubstr;

class Hostile : public testing::TempDirTest {};

// The FileFormatError `load` throws, checked for file, line and a part of the message. Anything
// else escaping (std::bad_alloc, a JSON library exception) fails the test.
void expectFileError(const std::function<void()>& load, const std::string& file, int line, const std::string& part) {
  try {
    load();
    ADD_FAILURE() << "expected a FileFormatError from " << file;
  } catch (const FileFormatError& e) {
    EXPECT_EQ(e.file(), file) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(part));
  }
}

// Every loader a path can reach, so that one bad path is tried on all of them.
void expectAllLoadersRefuse(const std::string& path, const std::string& part) {
  expectFileError([&] { loadSceneFile(path); }, path, 0, part);
  expectFileError([&] { loadObjCloth(path); }, path, 0, part);
  expectFileError([&] { loadMedit(path); }, path, 0, part);
  expectFileError([&] { loadTetGen(path + ".node"); }, path + ".node", 0, part);
}

// --- paths that are not text files ---------------------------------------------------------------

// Opening a FIFO for reading used to wait for a writer forever.
TEST_F(Hostile, FifoIsRefusedWithoutBlocking) {
  const std::string fifo = (dir_ / "mesh").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((fifo + ".node").c_str(), 0600), 0);
  expectAllLoadersRefuse(fifo, "not a regular file");
}

// /dev/zero never ends and has no newline: memory grew without bound.
TEST_F(Hostile, DeviceIsRefused) {
  expectFileError([] { loadObjCloth("/dev/zero"); }, "/dev/zero", 0, "not a regular file");
  expectFileError([] { loadMedit("/dev/zero"); }, "/dev/zero", 0, "not a regular file");
  expectFileError([] { loadSceneFile("/dev/zero"); }, "/dev/zero", 0, "not a regular file");
}

// A directory read as an empty file ("no vertices").
TEST_F(Hostile, DirectoryIsRefused) {
  const std::string dir = (dir_ / "mesh").string();
  std::filesystem::create_directories(dir + ".node");
  std::filesystem::create_directories(dir);
  expectAllLoadersRefuse(dir, "is a directory");
}

// A regular file without newlines was read whole into one line; now a line has a limit.
TEST_F(Hostile, LineWithoutEndIsRefusedAtTheLimit) {
  const std::string path = write("long.obj", "v 0 0 0\nv " + std::string(5u << 20, '1'));
  expectFileError([&] { loadObjCloth(path); }, path, 2, "line longer than 4 MiB");
}

// --- header counts -------------------------------------------------------------------------------

// Counts were reserved before anything was read: std::bad_alloc escaped (no file, no line), or
// gigabytes were taken. Now room is reserved only as far as the file can hold records, and the
// short file fails where its records end.
TEST_F(Hostile, HugeHeaderCountsFailAtEndOfFile) {
  const std::string count = std::to_string(INT_MAX);
  const std::string base = (dir_ / "big").string();
  write("big.node", count + " 3 0 0\n0 0 0 0\n");
  expectFileError([&] { loadTetGen(base); }, base + ".node", 2, "unexpected end of file, expected point 1 of " + count);

  write("tet.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
  write("tet.ele", count + " 4 0\n0 0 1 2 3\n");
  const std::string tet = (dir_ / "tet").string();
  expectFileError([&] { loadTetGen(tet); }, tet + ".ele", 2,
                  "unexpected end of file, expected tetrahedron 1 of " + count);

  const std::string mesh = write("big.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n" + count + "\n0 0 0 0\n");
  expectFileError([&] { loadMedit(mesh); }, mesh, 5, "unexpected end of file, expected vertex 2 of " + count);
  const std::string tets =
      write("tets.mesh", "Vertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\nTetrahedra\n" + count + "\n1 2 3 4 0\n");
  expectFileError([&] { loadMedit(tets); }, tets, 9, "unexpected end of file, expected tet 2 of " + count);
}

// --- sizes of built-in scenes ------------------------------------------------------------------

// The InvalidInputError `build` throws, checked for a part of the message.
void expectInvalid(const std::function<void()>& build, const std::string& part) {
  try {
    build();
    ADD_FAILURE() << "expected an InvalidInputError (" << part << ")";
  } catch (const InvalidInputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(part));
  }
}

// nx * ny in int wrapped (65536 x 65537 came out as 65536) and the loops wrote past the
// allocation; sizes that did not wrap took gigabytes or escaped as std::bad_alloc. Now the count
// is formed in 64 bits and refused past a stated maximum, before anything is allocated.
// Memory exhaustion (issue 20, item 6): a 2048 x 2048 cloth (the largest built-in size) under a
// 1 GiB address-space limit needs more than the limit. In a child process (the limit must not
// reach the test runner): makeClothGrid throws OutOfMemoryError naming the builder, not
// std::bad_alloc; the child's exit code says which. AddressSanitizer reserves terabytes of
// address space, so under it the check is skipped.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define STABINT_TEST_UNDER_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define STABINT_TEST_UNDER_ASAN 1
#endif
TEST(OutOfMemory, ABuilderPastTheMemoryIsAStabintError) {
#ifdef STABINT_TEST_UNDER_ASAN
  GTEST_SKIP() << "AddressSanitizer's shadow memory needs an unlimited address space";
#else
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const rlimit limit{rlim_t(1) << 30, rlim_t(1) << 30};
    if (::setrlimit(RLIMIT_AS, &limit) != 0) ::_exit(3);
    ClothGridParams p;
    p.nx = p.ny = 2048;
    try {
      makeClothGrid(p);
      ::_exit(4);  // built within the limit: the test's premise is wrong
    } catch (const OutOfMemoryError& e) {
      ::_exit(std::string(e.what()).find("makeClothGrid") != std::string::npos ? 0 : 5);
    } catch (...) {
      ::_exit(6);
    }
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: no limit, 4: built, 5: message without the builder, 6: another exception";
#endif
}

TEST_F(Hostile, HugeBuiltinSizesAreRefusedWithTheMaximum) {
  const std::string maximum = "exceeds the maximum of " + std::to_string(kMaxBuiltinParticles);
  ClothGridParams cloth;
  cloth.nx = 65536;
  cloth.ny = 65537;
  expectInvalid([&] { makeClothGrid(cloth); }, "cloth nx x ny = 65536 x 65537 particles " + maximum);
  cloth.nx = cloth.ny = 8000;
  expectInvalid([&] { makeClothGrid(cloth); }, maximum);
  expectInvalid([] { clothGridTriangles(65536, 65537); }, maximum);
  ChainPendulumParams chain;
  chain.particles = 2000000000;
  expectInvalid([&] { makeChainPendulum(chain); }, "chain particles = 2000000000 particles " + maximum);
  TetBarParams bar;
  bar.nx = INT_MAX;  // nx + 1 overflowed as well
  expectInvalid([&] { makeTetBar(bar); }, maximum);
  bar.nx = bar.ny = bar.nz = 2047;  // 2048^3 = 2^33 wrapped to 0
  expectInvalid([&] { makeTetBar(bar); }, "(nx + 1) x (ny + 1) x (nz + 1) = 2048 x 2048 x 2048 particles " + maximum);

  // The way a scene file or stabint-run --param reaches them: the builder's message, in the file's.
  expectFileError([] { builtinScene("cloth", R"({"nx": 65536, "ny": 65537})", "scene.json"); }, "scene.json", 0,
                  maximum);
  chain.particles = kMaxBuiltinParticles + 1;  // the bound is exact
  expectInvalid([&] { makeChainPendulum(chain); }, maximum);
}

// --- time ----------------------------------------------------------------------------------------

// The duplicate-corner check compared every pair of corners of a face: a 200,000-gon took 15 s.
// Now it sorts; a repeat anywhere in a big polygon is still found and named with both corners.
TEST_F(Hostile, BigPolygonDuplicateCornerIsNamed) {
  constexpr int kCorners = 200000;
  std::string vertices, face = "f";
  for (int i = 0; i < kCorners; ++i) {
    const double a = 6.283185307179586 * i / kCorners;
    // All digits: std::to_string's six decimals put the first corners on one line (a flat fan
    // triangle, refused since zero-area faces are).
    char v[64];
    std::snprintf(v, sizeof v, "v %.17g %.17g 0\n", std::cos(a), std::sin(a));
    vertices += v;
  }
  for (int i = 1; i <= kCorners; ++i) face += " " + std::to_string(i == 150000 ? 7 : i);
  const std::string path = write("gon.obj", vertices + face + "\n");
  expectFileError([&] { loadObjCloth(path); }, path, kCorners + 1,
                  "face 1: vertex 7 appears twice (corners 7 and 150000)");
  face.clear();
  for (int i = 1; i <= kCorners; ++i) face += " " + std::to_string(i);
  EXPECT_EQ(loadObjCloth(write("gon2.obj", vertices + "f" + face + "\n")).numParticles(), kCorners);
}

// --- JSON scene files ----------------------------------------------------------------------------

// A vector nested 70,000 levels deep overflowed the stack while its error message dumped it.
TEST_F(Hostile, DeepJsonIsRefusedWithItsLine) {
  const std::string deep = std::string(70000, '[') + "1" + std::string(70000, ']');
  const std::string path =
      write("deep.json", "{\"builtin\": {\"name\": \"oscillator\"},\n\"gravity\": " + deep + "}\n");
  expectFileError([&] { loadSceneFile(path); }, path, 2, "JSON nested deeper than 64 levels");
  expectFileError([&] { builtinScene("chain", "{\"pinned\": " + deep + "}", "params"); }, "params", 1, "nested deeper");

  // Within the limit the message shows the start of the value only.
  const std::string nested = std::string(60, '[') + "1" + std::string(60, ']');
  const std::string ok = write("nested.json", "{\"builtin\": {\"name\": \"oscillator\"}, \"gravity\": " + nested + "}");
  expectFileError([&] { loadSceneFile(ok); }, ok, 0, "gravity: expected an array of 3 numbers [x, y, z], got [[[[");
  try {
    loadSceneFile(ok);
  } catch (const FileFormatError& e) {
    EXPECT_LT(std::string(e.what()).size(), 200u + ok.size()) << e.what();
  }

  // Brackets inside strings are no nesting.
  const std::string name = std::string(100, '[') + "\\\"{";
  const std::string quoted =
      write("quoted.json", "{\"builtin\": {\"name\": \"oscillator\"}, \"name\": \"" + name + "\"}");
  EXPECT_EQ(loadSceneFile(quoted).name, std::string(100, '[') + "\"{");
}

// --- finite inputs that overflow ------------------------------------------------------------------

// Each of these passed validation and then failed the first step as "the simulation blew up".
TEST_F(Hostile, FiniteInputsThatOverflowAreRefusedByName) {
  const Scene chain = makeChainPendulum();  // 10 particles 1/9 m apart, 9 springs, pin 0
  const auto refused = [&](const std::function<void(Scene&)>& change, const std::string& part) {
    Scene s = chain;
    change(s);
    expectInvalid([&] { validateScene(s); }, part);
    expectInvalid([&] { Simulator sim(s, SimulatorOptions{}); }, part);
  };
  refused([](Scene& s) { s.masses[3] = 1e308, s.velocities.row(3) << 1e10, 0, 0; },
          "particle 3: kinetic energy 0.5 m |v|^2 of masses[3] = 1e+308 at speed 1e+10 overflows");
  refused([](Scene& s) { s.springs[2].rest_length = 1e200; },
          "spring 2: rest length 1e+200 exceeds 1e+150 in magnitude");
  refused([](Scene& s) { s.pins[0].target.frequency = 1e308; },
          "pin 0: target frequency 1e+308 exceeds 1e+150 in magnitude");
  refused([](Scene& s) { s.gravity.y() = -1e308; }, "gravity (0, -1e+308, 0) exceeds 1e+150 in magnitude");
  refused([](Scene& s) { s.positions(4, 0) = 1e200; }, "positions row 4 (1e+200, 0, 0) exceeds 1e+150 in magnitude");
  refused([](Scene& s) { s.masses.setConstant(1e307), s.gravity.y() = -1e3; },
          "gravity (0, -1000, 0): the work it can do, total mass 1e+308 x |g| x scene size 1 overflows");
  refused([](Scene& s) { s.springs[1].stiffness = 1e300; }, "spring 1: stiffness 1e+300 exceeds 1e+150");
  refused([](Scene& s) { s.pins[0].stiffness = 1e308; }, "pin 0: stiffness 1e+308 exceeds 1e+150");
  refused(
      [](Scene& s) { s.springs[1].stiffness = 1e150, s.springs[1].rest_length = 1e100; },
      "spring 1: energy k L^2 of stiffness 1e+150 over the larger of rest length and scene size L = 1e+100 overflows");
  refused([](Scene& s) { s.pins[0].stiffness = 1e150, s.pins[0].target.position.x() = -1e100; },
          "pin 0: energy k L^2 of stiffness 1e+150 over the scene size L = 1e+100 overflows");

  // Values at the bound are accepted.
  Scene s = chain;
  s.springs[2].rest_length = 1e150;
  s.springs[2].stiffness = 1.0;
  EXPECT_NO_THROW(validateScene(s));
}

// --- what loaders derive ----------------------------------------------------------------------------

// A volume or mass that overflows although every number in the file is finite: an overflowing
// volume was called "zero volume", and a density times a volume came back as an infinite mass.
// Each is now named at its element's line with what overflowed.
TEST_F(Hostile, DerivedVolumesAndMassesThatOverflowAreNamedWithTheirLine) {
  // The corner tet scaled by s: volume s^3 / 6. s = 1e103 overflows, s = 4000 is 1.07e10.
  const auto tetgen = [&](const std::string& name, const std::string& s) {
    write(name + ".node", "4 3 0 0\n1 0 0 0\n2 " + s + " 0 0\n3 0 " + s + " 0\n4 0 0 " + s + "\n");
    write(name + ".ele", "# one tet\n1 4 0\n1 1 2 3 4\n");
    return (dir_ / name).string();
  };
  const std::string huge = tetgen("huge", "1e103");
  expectFileError([&] { loadTetGen(huge); }, huge + ".ele", 3,
                  "tet 1: rest volume overflows (longest edge 1.41421e+103)");
  const std::string big = tetgen("big", "4000");
  expectFileError(
      [&] {
        loadTetGen(big, SolidMaterial{1e300, 1e5});
      },
      big + ".ele", 3, "tet 1: mass share density 1e+300 x volume 1.06667e+10 / 4 is not finite");
  // The same through a scene file's mesh entry: the mesh's own file and line, inside the field.
  const std::string scene = write("big.json", R"({"mesh": {"file": "big.node", "density": 1e300}})");
  expectFileError(
      [&] { loadSceneFile(scene); }, scene, 0,
      "mesh.file: " + big + ".ele:3: tet 1: mass share density 1e+300 x volume 1.06667e+10 / 4 is not finite");
  const std::string medit = write("big.mesh",
                                  "Vertices 4\n0 0 0 0\n4000 0 0 0\n0 4000 0 0\n0 0 4000 0\n"
                                  "Tetrahedra 1\n1 2 3 4 0\n");
  expectFileError([&] { loadMedit(medit, SolidMaterial{1e300, 1e5}); }, medit, 7, "tet 1: mass share density 1e+300");

  // OBJ: an area that overflows, a mass that does, and a coordinate past validation's bound
  // (refused where its line is known rather than at construction).
  std::string obj = write("huge.obj", "v 0 0 0\nv 1e150 0 0\nv 0 1e150 0\nf 1 2 3\n");
  expectFileError([&] { loadObjCloth(obj); }, obj, 4, "face 1: rest area overflows (longest edge 1.41421e+150)");
  obj = write("big.obj", "v 0 0 0\nv 1e10 0 0\nv 0 1e10 0\nf 1 2 3\n");
  ClothMaterial heavy;
  heavy.areal_density = 1e300;
  expectFileError([&] { loadObjCloth(obj, heavy); }, obj, 4,
                  "face 1: mass share areal_density 1e+300 x area 5e+19 / 3 is not finite");
  obj = write("far.obj", "v 0 0 0\nv 1e151 0 0\nv 0 1 0\nf 1 2 3\n");
  expectFileError([&] { loadObjCloth(obj); }, obj, 2, "vertex 2 coordinate x 1e151 exceeds 1e+150 in magnitude");

  // JSON densities name the tet or triangle by its path (this was "masses[0] = inf" before).
  const std::string json =
      write("dense.json", R"({"particles": {"positions": [[0,0,0],[4000,0,0],[0,4000,0],[0,0,4000]],
                                                   "density": 1e300}, "tets": [{"vertices": [0, 1, 2, 3], "stiffness": 1}]})");
  expectFileError([&] { loadSceneFile(json); }, json, 0,
                  "tets[0]: mass share density 1e+300 x volume 1.06667e+10 / 4 is not finite");

  // Through the API: finite shares whose sum at a shared vertex overflows.
  Eigen::MatrixX3d x(5, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1;
  x *= 1000.0;
  const std::vector<Tet> tets{Tet{{0, 1, 2, 3}, 1.0}, Tet{{0, 2, 1, 4}, 1.0}};  // volumes 1e9 / 6 each
  expectInvalid([&] { lumpMassesFromTets(x, tets, 2.4e300); },                  // a share of 1e308 each
                "tet 1: the lumped mass of particle 0 overflows when its share 1e+308 is added to 1e+308");

  // Validation, on coordinates at its bound of 1e150: a tet's volume of 1e450 / 6 passed as
  // positive (and blew up the first step), a triangle's area was called degenerate.
  Scene s;
  s.rest_positions = x.topRows(4) * 1e147;
  s.positions = s.rest_positions;
  s.velocities = Eigen::MatrixX3d::Zero(4, 3);
  s.masses = Eigen::VectorXd::Ones(4);
  s.tets.push_back(Tet{{0, 1, 2, 3}, 1.0});
  expectInvalid([&] { validateScene(s); }, "tet 0: rest volume overflows (longest edge 1.41421e+150)");
  s.tets.clear();
  s.triangle_strains.push_back(TriangleStrain{{0, 1, 2}, 1.0, 1.0, 1.0});
  expectInvalid([&] { validateScene(s); },
                "triangle strain 0: rest triangle (0, 1, 2): rest area overflows (longest edge 1.41421e+150)");
}

// --- silent acceptances ---------------------------------------------------------------------------

// The JSON library keeps the last of two equal keys: a scene ran with a value its reader may not
// have seen, although every key is promised to be checked.
TEST_F(Hostile, DuplicateJsonKeysAreRefusedWithTheirLine) {
  std::string path = write("dup.json",
                           "{\"builtin\": {\"name\": \"oscillator\", \"mass\": 1,\n"
                           "                         \"mass\": 2}}");
  expectFileError([&] { loadSceneFile(path); }, path, 2, "duplicate key 'mass' (first on line 1)");
  path = write("escaped.json",
               "{\"gravity\": [0, 0, 0],\n\n\"grav\\u0069ty\": [0, 1, 0], \"builtin\": {\"name\": \"chain\"}}");
  expectFileError([&] { loadSceneFile(path); }, path, 3, "duplicate key 'gravity' (first on line 1)");
  // Equal keys in different objects, and keys that equal a string value, are fine.
  path = write("fine.json", R"({"builtin": [{"name": "oscillator", "translate": [0, 0, 0]}, {"name": "oscillator"}],
                              "name": "name", "bodies": [{"name": "a"}]})");
  EXPECT_EQ(loadSceneFile(path).name, "name");
  expectFileError([&] { builtinScene("cloth", R"({"nx": 3, "nx": 40})", "params"); }, "params", 1,
                  "duplicate key 'nx' (first on line 1)");
}

// The JSON library stops at a NUL byte and reports success: the text after it was ignored, and
// the duplicate-key scan read it as JSON (a libFuzzer finding: an empty-stack back()).
TEST_F(Hostile, JsonWithNulByteIsRefusedWithItsLine) {
  const std::string path = write("nul.json", std::string("{\"builtin\": {\"name\": \"chain\"}}\n\0\"me\", ]\n}\n", 42));
  expectFileError([&] { loadSceneFile(path); }, path, 2, "NUL byte at offset 31");
  // The fuzzer's input: a string, a NUL, then unbalanced brackets.
  const std::string found =
      write("found.json", std::string("\"vertex\"\0\"me\", \v\0\"mesh\": {ut.json\", ]\n}\n", 40));
  expectFileError([&] { loadSceneFile(found); }, found, 1, "NUL byte at offset 8");
}

// Zero-area faces, vertices in no face or tet, and a zero density each silently got the 1e-6 kg
// mass floor: a scene the file did not describe.
TEST_F(Hostile, ZeroAreaFacesUnusedVerticesAndZeroDensityAreRefused) {
  std::string obj = write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n");
  expectFileError([&] { loadObjCloth(obj); }, obj, 6,
                  "face 2: zero rest area 0 for its longest edge L = 2 (degenerate: at most 1e-12 L^2)");
  obj = write("quad.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3 4\n");
  expectFileError([&] { loadObjCloth(obj); }, obj, 5, "face 1 (the fan triangle of corners 1, 2, 3): zero rest area 0");
  obj = write("stray.obj", "v 0 0 0\nv 1 0 0\n# a stray vertex\nv 5 5 5\nv 0 1 0\nf 1 2 4\n");
  expectFileError([&] { loadObjCloth(obj); }, obj, 4,
                  "vertex 3 is in no face, so it would have no mass; remove it from the file");
  const std::string mesh =
      write("stray.mesh", "Vertices 5\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n9 9 9 0\nTetrahedra 1\n1 2 3 4 0\n");
  expectFileError([&] { loadMedit(mesh); }, mesh, 6, "vertex 5 is in no tetrahedron, so it would have no mass");

  obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ClothMaterial weightless;
  weightless.areal_density = 0.0;
  expectInvalid([&] { loadObjCloth(obj, weightless); }, "ClothMaterial areal_density 0 must be > 0 and finite");
  expectInvalid([&] { loadMedit(mesh, SolidMaterial{0.0, 1e5}); }, "SolidMaterial density 0 must be > 0 and finite");
  ClothGridParams cloth;
  cloth.areal_density = 0.0;
  expectInvalid([&] { makeClothGrid(cloth); }, "areal_density 0 must be > 0 and finite");
  TetBarParams bar;
  bar.density = -1.0;
  expectInvalid([&] { makeTetBar(bar); }, "density -1 must be > 0 and finite");
}

// A sliver tet (volume 1e-13 of its size) passed the API's and JSON's `volume > 0` although the
// mesh loaders refused it with a relative test; all now use the relative test.
TEST_F(Hostile, SliverTetsAreRefusedEverywhereByTheSameTest) {
  const auto oneTet = [](double apex) {
    Scene s;
    s.rest_positions.resize(4, 3);
    s.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, apex;
    s.positions = s.rest_positions;
    s.velocities = Eigen::MatrixX3d::Zero(4, 3);
    s.masses = Eigen::VectorXd::Ones(4);
    s.tets.push_back(Tet{{0, 1, 2, 3}, 1e3});
    return s;
  };
  // Volume 1e-13 / 6 against the longest edge sqrt(2): 1.2e-14 L^3, below 1e-12 L^3.
  const std::string sliver =
      "zero rest volume 1.66667e-14 for its longest edge L = 1.41421 (degenerate: at most 1e-12 L^3)";
  expectInvalid([&] { validateScene(oneTet(1e-13)); }, "tet 0: " + sliver);
  expectInvalid([&] { Simulator sim(oneTet(1e-13), SimulatorOptions{}); }, "tet 0: " + sliver);
  const std::string json =
      write("sliver.json", R"({"particles": {"positions": [[0,0,0],[1,0,0],[0,1,0],[0,0,1e-13]], "masses": 1},
                                                    "tets": [{"vertices": [0, 1, 2, 3], "stiffness": 1}]})");
  expectFileError([&] { loadSceneFile(json); }, json, 0, "tets[0].vertices: " + sliver);
  write("sliver.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1e-13\n");
  write("sliver.ele", "1 4 0\n1 1 2 3 4\n");
  expectFileError([&] { loadTetGen((dir_ / "sliver").string()); }, (dir_ / "sliver.ele").string(), 2,
                  "tet 1: " + sliver);
  // The test is relative: a small tet of good shape is a tet.
  Scene small = oneTet(1e-5);
  small.rest_positions.topRows(3) *= 1e-5;
  small.positions = small.rest_positions;
  EXPECT_NO_THROW(validateScene(small));
}

// --- the implicit system ---------------------------------------------------------------------------

// Masses too small for the stiffnesses: CHOLMOD printed on stdout (inside `--csv -` output) and
// the first step() failed with the base Error naming an internal constant. Now the construction
// refuses the scene, naming masses and stiffness, and nothing is printed.
// One rule for every stiffness, whatever path it comes in by (issue 46): a scene's element or pin
// stiffness is at most 1e150, the bound of per-frame input and of every real a checkpoint holds.
// A single tet of 1e200 or 1e308 built, stepped and saved a checkpoint that no simulator could load
// again; it is refused at construction, and every stiffness a simulator accepts saves a
// checkpoint a fresh simulator of the scene restores.
TEST_F(Hostile, EveryAcceptedStiffnessRoundTripsThroughACheckpoint) {
  for (double k : {1.0, 1e100, 1e150, 1e200, 1e308}) {
    TetBarParams one;
    one.nx = one.ny = one.nz = 1;
    Scene s = makeTetBar(one);
    for (Tet& t : s.tets) t.stiffness = k;
    s.pins.back().stiffness = std::min(k, 1e150);
    try {
      Simulator sim(s, SimulatorOptions{});
      sim.step();
      const Checkpoint saved = sim.checkpoint();
      Simulator fresh(s, SimulatorOptions{});
      EXPECT_NO_THROW(fresh.restore(Checkpoint::fromBytes(saved.bytes()))) << "stiffness " << k;
      EXPECT_LE(k, 1e150) << "accepted beyond the bound";
    } catch (const InvalidInputError& e) {
      // Refused: beyond the bound, or a system that does not factor (at 1e100-1e150 the mass is
      // lost in the stiffness: not numerically positive definite).
      const std::string what = e.what();
      EXPECT_TRUE(what.find("exceeds 1e+150") != std::string::npos ||
                  what.find("positive definite") != std::string::npos)
          << what;
      if (k > 1e150) {
        EXPECT_NE(what.find("stiffness"), std::string::npos) << what;
      }
    }
  }
}

TEST_F(Hostile, SingularImplicitSystemIsRefusedAtConstructionSilently) {
  ChainPendulumParams p;
  p.particles = 2;
  p.total_mass = 1e-300;
  p.stiffness = 0x1p498;  // about 8.2e149, a power of 4 within 1e150: its Cholesky factor rounds to exactly 0
  const Scene scene = makeChainPendulum(p);
  SimulatorOptions o;
  for (const Integrator integrator :
       {Integrator::BackwardEuler, Integrator::ImplicitMidpoint, Integrator::BDF2, Integrator::EnergyBlend}) {
    o.integrator = integrator;
    ::testing::internal::CaptureStdout();
    expectInvalid([&] { Simulator sim(scene, o); },
                  "is not numerically positive definite: c times the smallest mass, ");
    EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  }
  o.integrator = Integrator::SymplecticEuler;  // explicit: no system to factor
  EXPECT_NO_THROW(Simulator(scene, o));
}

// Positive definiteness by an explicit test, not CHOLMOD's flag alone (issue 46). CHOLMOD refuses
// a pivot <= 0 or NaN as it factors, but an infinite one passes: at time_step 1e-152, c = 1/h^2 is
// 1e304 (4e304 for the midpoint), and c times a particle's 1e5 kg overflows to infinity on every
// diagonal entry. CHOLMOD reported success with infinite pivots; the factor is now tested (every
// pivot finite and positive, every entry finite) and the construction refuses the scene, naming
// c, the largest mass and the stiffness, with nothing printed. A mass 1e10 times lighter builds.
TEST_F(Hostile, AFactorWithInfinitePivotsIsRefusedByTheExplicitTest) {
  ChainPendulumParams p;
  p.particles = 3;
  p.total_mass = 3e5;
  SimulatorOptions o;
  o.time_step = 1e-152;
  for (const Integrator integrator :
       {Integrator::BackwardEuler, Integrator::ImplicitMidpoint, Integrator::BDF2, Integrator::EnergyBlend}) {
    o.integrator = integrator;
    ::testing::internal::CaptureStdout();
    expectInvalid([&] { Simulator sim(makeChainPendulum(p), o); },
                  "is not numerically positive definite: its Cholesky factor has a pivot or an entry that is not "
                  "finite: c times the largest mass, inf, ");
    EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  }
  p.total_mass = 3e-5;
  o.integrator = Integrator::EnergyBlend;
  EXPECT_NO_THROW(Simulator(makeChainPendulum(p), o));
}

// --- saving --------------------------------------------------------------------------------------

// A name that is not UTF-8 (one the OBJ loader itself made from a Latin-1 file name) made
// saveSceneFile throw the JSON library's exception. Loaders now make names UTF-8, and saving
// refuses other bytes naming the field.
TEST_F(Hostile, NamesThatAreNotUtf8AreMadeTextOrRefused) {
  const Scene cloth = loadObjCloth(write("caf\xe9.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(cloth.name, "caf\xef\xbf\xbd");  // U+FFFD
  const std::string saved = (dir_ / "cloth.json").string();
  saveSceneFile(cloth, saved);
  EXPECT_EQ(loadSceneFile(saved).name, cloth.name);

  Scene s = makeLinearOscillator();
  s.name = "caf\xe9";
  expectInvalid([&] { saveSceneFile(s, saved); }, "scene name 'caf\\xe9' is not valid UTF-8 (byte 4)");
  s.name = "ok";
  s.bodies[0].name = "a\xed\xa0\x80";  // a UTF-16 surrogate, which UTF-8 may not hold
  expectInvalid([&] { saveSceneFile(s, saved); }, "body 0 name 'a\\xed\\xa0\\x80' is not valid UTF-8 (byte 2)");
  s.bodies[0].name = "\xe2\x82\xac \xf0\x9f\x98\x80";  // well-formed: saved as it is
  saveSceneFile(s, saved);
  EXPECT_EQ(loadSceneFile(saved).bodies[0].name, s.bodies[0].name);
}

// --- what error messages show of a file ------------------------------------------------------------

bool printableAscii(const std::string& s) {
  for (const unsigned char c : s) {
    if (c < 0x20 || c >= 0x7f) return false;
  }
  return true;
}

// Binary bytes, control characters and NUL were echoed raw into the message.
TEST_F(Hostile, MessagesShowFileBytesEscaped) {
  const std::string obj = write("bin.obj", std::string("v 0 \x01\x1b[2J\0\xff 0\n", 15));
  try {
    loadObjCloth(obj);
    ADD_FAILURE() << "expected a FileFormatError";
  } catch (const FileFormatError& e) {
    EXPECT_TRUE(printableAscii(e.what())) << e.what();
    EXPECT_THAT(e.what(), HasSubstr("got '\\x01\\x1b[2J\\x00\\xff'"));
  }
  const std::string mesh = write("bin.mesh", "Vertices 0\n" + std::string(200, '\x07') + "\n");
  try {
    loadMedit(mesh);
    ADD_FAILURE() << "expected a FileFormatError";
  } catch (const FileFormatError& e) {
    EXPECT_TRUE(printableAscii(e.what())) << e.what();
    EXPECT_THAT(e.what(), HasSubstr("\\x07\\x07..."));  // and cut short
    EXPECT_LT(std::string(e.what()).size(), 400u);
  }
}

// Names from a scene file (a key, a built-in name, the bytes a malformed file stopped at) were
// echoed raw into the message.
TEST_F(Hostile, JsonMessagesShowFileBytesEscaped) {
  const auto expectEscaped = [](const std::string& path, const std::string& part) {
    try {
      loadSceneFile(path);
      ADD_FAILURE() << "expected a FileFormatError";
    } catch (const FileFormatError& e) {
      EXPECT_TRUE(printableAscii(e.what())) << e.what();
      EXPECT_THAT(e.what(), HasSubstr(part));
    }
  };
  expectEscaped(write("key.json", R"({"builtin": {"name": "oscillator"}, "\u001b[2J\u00ff": 1})"),
                "unknown field '\\x1b[2J\\xc3\\xbf'");
  expectEscaped(write("name.json", R"({"builtin": {"name": "\u0007cloth"}})"), "unknown built-in scene '\\x07cloth'");
  expectEscaped(write("bad.json", "{\"gravity\": \x01\xff}"), "malformed JSON");
}

}  // namespace
}  // namespace stabint
