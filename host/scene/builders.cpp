// Built-in scenes (docs/method.md section 9). Every builder ends with validateScene, so a bad
// parameter (negative stiffness, zero mass, out-of-range pin) fails here with the scene's own
// message instead of later inside a solver.
#include <stabint/builders.hpp>
#include <stabint/errors.hpp>

#include "common/out_of_memory.hpp"

#include <algorithm>
#include <array>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace stabint {

namespace {

void requireAtLeast(int value, int minimum, const char* name) {
  if (value < minimum) {
    throw InvalidInputError(std::string(name) + " = " + std::to_string(value) +
                            " must be >= " + std::to_string(minimum));
  }
}

// The particle count of a grid of `sizes` (each >= 1), refused past kMaxBuiltinParticles. The
// product is formed in 64 bits and stops at the limit: in int it wrapped (65536 x 65537 came out
// as 65536 and the loops wrote past the allocation), and a huge honest count was std::bad_alloc.
int gridParticles(std::initializer_list<long long> sizes, const char* names) {
  std::string product;
  for (const long long n : sizes) product += (product.empty() ? "" : " x ") + std::to_string(n);
  long long count = 1;
  for (const long long n : sizes) {
    count *= n;  // both factors are at most 2^31: no overflow before the check below
    if (count > kMaxBuiltinParticles) {
      throw InvalidInputError(std::string(names) + " = " + product + " particles exceeds the maximum of " +
                              std::to_string(kMaxBuiltinParticles) + " for a built-in scene");
    }
  }
  return static_cast<int>(count);
}

// Positions double as the rest shape; every built-in scene starts at rest in its rest shape.
void setParticles(Scene& s, Eigen::MatrixX3d positions, Eigen::VectorXd masses) {
  s.velocities = Eigen::MatrixX3d::Zero(positions.rows(), 3);
  s.rest_positions = positions;
  s.positions = std::move(positions);
  s.masses = std::move(masses);
}

Body wholeBody(const Scene& s, double damping) {
  Body body{s.name, std::vector<int>(s.numParticles()), damping};
  for (int j = 0; j < s.numParticles(); ++j) body.particles[j] = j;
  return body;
}

Pin pinInPlace(const Scene& s, int vertex, double stiffness) {
  Pin pin;
  pin.vertex = vertex;
  pin.stiffness = stiffness;
  // Out-of-range vertices are left for validateScene to report; do not read past the matrix.
  if (vertex >= 0 && vertex < s.numParticles()) pin.target.position = s.rest_positions.row(vertex).transpose();
  return pin;
}

Spring springBetween(const Scene& s, int a, int b, double stiffness) {
  return Spring{a, b, (s.rest_positions.row(a) - s.rest_positions.row(b)).norm(), stiffness};
}

Scene finish(Scene s) {
  validateScene(s);
  return s;
}

}  // namespace

Scene makeLinearOscillator(const LinearOscillatorParams& p) {
  Scene s;
  s.name = "oscillator";
  setParticles(s, Eigen::RowVector3d(p.amplitude, 0.0, 0.0), Eigen::VectorXd::Constant(1, p.mass));
  s.gravity.setZero();
  Pin pin;
  pin.vertex = 0;
  pin.stiffness = p.stiffness;  // target stays at the origin
  s.pins.push_back(pin);
  s.bodies.push_back(wholeBody(s, 0.0));
  return finish(std::move(s));
}

static Scene makeChainPendulumUnguarded(const ChainPendulumParams& p) {
  requireAtLeast(p.particles, 2, "chain particles");
  gridParticles({p.particles}, "chain particles");
  Scene s;
  s.name = "chain";
  const double spacing = p.length / (p.particles - 1);
  Eigen::MatrixX3d x = Eigen::MatrixX3d::Zero(p.particles, 3);
  for (int i = 0; i < p.particles; ++i) x(i, 0) = i * spacing;
  setParticles(s, std::move(x), Eigen::VectorXd::Constant(p.particles, p.total_mass / p.particles));
  for (int i = 0; i + 1 < p.particles; ++i) s.springs.push_back(Spring{i, i + 1, spacing, p.stiffness});
  s.pins.push_back(pinInPlace(s, 0, p.pin_stiffness));
  s.gravity = Eigen::Vector3d(0.0, -p.gravity, 0.0);
  s.bodies.push_back(wholeBody(s, 0.0));
  return finish(std::move(s));
}

std::vector<std::array<int, 3>> clothGridTriangles(int nx, int ny) {
  if (nx > 0 && ny > 0) gridParticles({nx, ny}, "cloth nx x ny");
  const auto id = [nx](int i, int j) { return j * nx + i; };
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(2 * std::max(nx - 1, 0) * std::max(ny - 1, 0));
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j)});
      triangles.push_back({id(i + 1, j), id(i, j + 1), id(i + 1, j + 1)});
    }
  }
  return triangles;
}

// Particle (i, j) is index j*nx + i at (i dx, height - j dy, 0): row j = 0 is the top edge at
// y = height, so the default pins hang the cloth from its top corners.
static Scene makeClothGridUnguarded(const ClothGridParams& p) {
  requireAtLeast(p.nx, 2, "cloth nx");
  requireAtLeast(p.ny, 2, "cloth ny");
  Scene s;
  s.name = "cloth";
  const int nx = p.nx, ny = p.ny;
  const int count = gridParticles({nx, ny}, "cloth nx x ny");
  const auto id = [nx](int i, int j) { return j * nx + i; };
  const double dx = p.width / (nx - 1), dy = p.height / (ny - 1);
  Eigen::MatrixX3d x(count, 3);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) x.row(id(i, j)) << i * dx, p.height - j * dy, 0.0;
  }
  s.triangles = clothGridTriangles(nx, ny);
  Eigen::VectorXd masses = lumpMassesFromTriangles(x, s.triangles, p.areal_density);
  setParticles(s, std::move(x), std::move(masses));

  if (p.model == ClothModel::Triangles) {
    addTriangleClothElements(s, p.strain_stiffness, p.strain_min, p.strain_max, p.hinge_stiffness);
  } else {
    // Grouped by kind (structural, shear, bending), each in row-major order.
    const auto add = [&](int a, int b, double k) { s.springs.push_back(springBetween(s, a, b, k)); };
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) add(id(i, j), id(i + 1, j), p.stretch_stiffness);
    }
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i < nx; ++i) add(id(i, j), id(i, j + 1), p.stretch_stiffness);
    }
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        add(id(i, j), id(i + 1, j + 1), p.shear_stiffness);
        add(id(i + 1, j), id(i, j + 1), p.shear_stiffness);
      }
    }
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i + 2 < nx; ++i) add(id(i, j), id(i + 2, j), p.bend_stiffness);
    }
    for (int j = 0; j + 2 < ny; ++j) {
      for (int i = 0; i < nx; ++i) add(id(i, j), id(i, j + 2), p.bend_stiffness);
    }
  }

  const std::vector<int> pinned = p.pinned.empty() ? std::vector<int>{id(0, 0), id(nx - 1, 0)} : p.pinned;
  for (int v : pinned) s.pins.push_back(pinInPlace(s, v, p.pin_stiffness));
  s.bodies.push_back(wholeBody(s, p.damping));
  return finish(std::move(s));
}

// Kuhn (Freudenthal) split: each cube becomes the six tets along the monotone paths from its
// corner (0,0,0) to (1,1,1), one per axis permutation. All cubes use the same main diagonal,
// so the split of every shared face agrees between the two cubes on either side.
static Scene makeTetBarUnguarded(const TetBarParams& p) {
  requireAtLeast(p.nx, 1, "tet bar nx");
  requireAtLeast(p.ny, 1, "tet bar ny");
  requireAtLeast(p.nz, 1, "tet bar nz");
  Scene s;
  s.name = "tetbar";
  const int count = gridParticles({p.nx + 1LL, p.ny + 1LL, p.nz + 1LL}, "tet bar (nx + 1) x (ny + 1) x (nz + 1)");
  const int px = p.nx + 1, py = p.ny + 1, pz = p.nz + 1;
  const auto id = [px, py](int i, int j, int k) { return i + px * (j + py * k); };
  const double dx = p.length / p.nx, dy = p.width / p.ny, dz = p.width / p.nz;
  Eigen::MatrixX3d x(count, 3);
  for (int k = 0; k < pz; ++k) {
    for (int j = 0; j < py; ++j) {
      for (int i = 0; i < px; ++i) x.row(id(i, j, k)) << i * dx, j * dy, k * dz;
    }
  }

  static const std::array<std::array<int, 3>, 6> kAxisOrders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < p.nz; ++k) {
    for (int j = 0; j < p.ny; ++j) {
      for (int i = 0; i < p.nx; ++i) {
        for (const auto& order : kAxisOrders) {
          std::array<int, 3> corner{i, j, k};
          Tet tet;
          tet.stiffness = p.stiffness;
          tet.vertices[0] = id(corner[0], corner[1], corner[2]);
          for (int step = 0; step < 3; ++step) {
            ++corner[order[step]];
            tet.vertices[step + 1] = id(corner[0], corner[1], corner[2]);
          }
          // Odd permutations come out left-handed; a swap makes every rest volume positive.
          if (signedVolume(x, tet.vertices) < 0.0) std::swap(tet.vertices[1], tet.vertices[2]);
          s.tets.push_back(tet);
        }
      }
    }
  }
  Eigen::VectorXd masses = lumpMassesFromTets(x, s.tets, p.density);
  setParticles(s, std::move(x), std::move(masses));
  for (int k = 0; k < pz; ++k) {
    for (int j = 0; j < py; ++j) s.pins.push_back(pinInPlace(s, id(0, j, k), p.pin_stiffness));
  }
  s.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  s.bodies.push_back(wholeBody(s, p.damping));
  return finish(std::move(s));
}

// The public builders: a size that passes the limits but not the machine's memory is an
// OutOfMemoryError naming the builder.
Scene makeChainPendulum(const ChainPendulumParams& p) {
  return reportingOutOfMemory("makeChainPendulum", [&] { return makeChainPendulumUnguarded(p); });
}
Scene makeClothGrid(const ClothGridParams& p) {
  return reportingOutOfMemory("makeClothGrid", [&] { return makeClothGridUnguarded(p); });
}
Scene makeTetBar(const TetBarParams& p) {
  return reportingOutOfMemory("makeTetBar", [&] { return makeTetBarUnguarded(p); });
}

}  // namespace stabint
