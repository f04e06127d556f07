#pragma once
/// @file
/// Built-in scenes with parameters: the test and benchmark scenes of docs/method.md section 9.
#include <stabint/scene.hpp>

namespace stabint {

/// Most particles a built-in scene may have (a 2048 x 2048 cloth). Larger sizes (the product
/// of the grid sizes, computed in 64 bits) are an InvalidInputError naming the parameters and
/// this maximum, before anything is allocated.
constexpr int kMaxBuiltinParticles = 1 << 22;

/// One particle on a zero-rest-length spring (a pin) to the origin, no gravity:
/// omega^2 = stiffness / mass. Starts at (amplitude, 0, 0) at rest.
struct LinearOscillatorParams {
  double mass = 1.0;       ///< kg
  double stiffness = 1.0;  ///< N/m, of the pin
  double amplitude = 1.0;  ///< m, the initial displacement along x
};
/// Builds the linear oscillator scene and validates it (validateScene): bad parameters throw InvalidInputError.
Scene makeLinearOscillator(const LinearOscillatorParams& p = {});

/// A chain of `particles` equal masses joined by springs, its first particle pinned at the
/// origin, laid out horizontally along +x at rest (released horizontally), gravity along -y.
struct ChainPendulumParams {
  int particles = 10;          ///< number of particles, the pinned first one included
  double total_mass = 0.1;     ///< kg
  double length = 1.0;         ///< m
  double stiffness = 1e4;      ///< N/m, per spring
  double pin_stiffness = 1e6;  ///< N/m, the pin holding the first particle
  double gravity = 9.81;       ///< m/s^2, along -y
};
/// Builds the chain pendulum scene and validates it (validateScene): bad parameters throw InvalidInputError.
Scene makeChainPendulum(const ChainPendulumParams& p = {});

/// A rectangular cloth of `nx` by `ny` particles in the x-y plane (hanging under gravity along
/// -y), triangulated into Scene::triangles (two triangles per cell), with the elements of
/// `model` (springs with the stretch/shear/bend stiffnesses, or triangle strain and bending
/// hinges with the strain and hinge parameters); masses lumped from the areal density. The particles listed in `pinned`
/// (row-major index j*nx + i) are pinned in place; by default the two top corners.
struct ClothGridParams {
  int nx = 20;                             ///< particles along x
  int ny = 20;                             ///< particles along y
  double width = 1.0;                      ///< m, along x
  double height = 1.0;                     ///< m, along y
  double areal_density = 0.1;              ///< kg/m^2
  double stretch_stiffness = 1e3;          ///< N/m, springs along grid edges (model Springs)
  double shear_stiffness = 1e2;            ///< N/m, springs along cell diagonals (model Springs)
  double bend_stiffness = 1e1;             ///< N/m, springs across two cells (model Springs)
  double pin_stiffness = 1e5;              ///< N/m, each pin
  std::vector<int> pinned;                 ///< empty: the two top corners
  double damping = 0.0;                    ///< one body, momentum-preserving damping factor
  ClothModel model = ClothModel::Springs;  ///< springs, or triangle strain and bending hinges
  double strain_stiffness = 1e3;           ///< triangle strain k, N/m (model Triangles)
  double strain_min = 1.0;                 ///< triangle strain limits (model Triangles)
  double strain_max = 1.0;                 ///< triangle strain limits (model Triangles)
  double hinge_stiffness = 1e-3;           ///< bending hinge k, J (model Triangles)
};
/// Builds the cloth grid scene and validates it (validateScene): bad parameters throw InvalidInputError.
Scene makeClothGrid(const ClothGridParams& p = {});

/// The triangles of makeClothGrid's `nx` by `ny` grid: cell (i, j) is split along the diagonal
/// from (i + 1, j) to (i, j + 1), consistently wound.
std::vector<std::array<int, 3>> clothGridTriangles(int nx, int ny);

/// A box of `nx` by `ny` by `nz` cells along x (length) by y by z, each cell split into six
/// tets; the particles at x = 0 are pinned; gravity along -y. Masses lumped from the density.
struct TetBarParams {
  int nx = 8;                  ///< cells along x
  int ny = 2;                  ///< cells along y
  int nz = 2;                  ///< cells along z
  double length = 1.0;         ///< m, along x
  double width = 0.25;         ///< m, along y and z
  double density = 1000.0;     ///< kg/m^3
  double stiffness = 1e5;      ///< tet strain stiffness (Pa)
  double pin_stiffness = 1e7;  ///< N/m, each pin at x = 0
  double damping = 0.0;        ///< one body, momentum-preserving damping factor
};
/// Builds the tet bar scene and validates it (validateScene): bad parameters throw InvalidInputError.
Scene makeTetBar(const TetBarParams& p = {});

}  // namespace stabint
