#pragma once
// The bodies of a scene: the sets of particles its elements connect. The blend's corrections keep
// and restore the rigid motion of each body apart (docs/method.md, "The blend"): a scene's bodies
// move apart in the solve, and a bar turning above a cloth says nothing of how the cloth moves.
#include <stabint/scene.hpp>

#include <vector>

namespace stabint {

/// The particles the scene's springs, tets, triangle strains and bending hinges connect, as built
/// (an element disabled later still connects): each body's particles ascending, the bodies in the
/// order of their first particle. A particle no element touches is a body of its own.
std::vector<std::vector<int>> connectedBodies(const Scene& scene);

/// The tet bodies, which self-contact answers as bodies (docs/method.md, "Self-contact"): the
/// particles the scene's tets connect, in connectedBodies' order. A particle in no tet is in none.
std::vector<std::vector<int>> tetBodies(const Scene& scene);

}  // namespace stabint
