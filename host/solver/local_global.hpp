#pragma once
// Local/global iterations for one implicit solve (docs/method.md, "One implicit solve"):
//   x* = argmin_x c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t).
// Each iteration projects every element at the current x (local, on the backend) and solves
// K_c x = rhs (global): with the prefactored K_c on the host, or by CG (GlobalSolve::
// ConjugateGradient) on the host or, for OpenCL, on the device. The loop is shared by all backends;
// each acceleration is its own class over the solve's shared context (solver/accelerations.hpp).
#include "solver/accelerations.hpp"
#include "solver/solve_context.hpp"

#include <cstddef>
#include <utility>
#include <vector>

namespace stabint {

class Forcing;
class SceneData;

class LocalGlobalSolver {
 public:
  /// `scratch_slot` is a backend slot the solver may overwrite.
  LocalGlobalSolver(Backend& backend, GlobalSystem& system, int scratch_slot);
  ~LocalGlobalSolver();

  /// Runs iterations from the positions in slot `x` (the warm start) and leaves the result there.
  /// Returns the number of iterations (global solves) done. When `objective_history` is given,
  /// it receives the objective at the start and after every iteration. The objective never
  /// rises from one iteration to the next, with or without acceleration, and with either global
  /// solve: CG warm-started from the current iterate lowers the global step's quadratic at every
  /// CG iteration, so even an inexact global step lowers it (in exact arithmetic; to round-off
  /// of the device's precision on OpenCL; docs/method.md, "Global solve").
  int solve(double c, int y, int x, double t, const IterationControl& control,
            std::vector<double>* objective_history = nullptr);

  /// c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t)
  double objective(double c, int y, int x, double t) { return context_.objective(c, y, x, t); }

  /// The potential at time t of the positions the last solve left in slot x, per segment (one for
  /// a single scene), when its last local step was at them (L-BFGS and Newton-CG, and plain
  /// solves that track their objective on one scene): equal bit for bit to Backend::potential(x,
  /// t) (a batch's: Backend::potentials), so a step takes it instead of an energy pass over the
  /// same positions. Empty otherwise.
  const std::vector<PotentialEnergy>& potentialsOfResult() const { return context_.resultPotentials(); }

  /// The iterations segment `s` took in the last solve: the solve's count, but with a stop by
  /// accuracy (any solver's tolerance, L-BFGS's gradient_tolerance) or Newton-CG's own CG counts,
  /// where each segment stops on its own, as its scene alone would, and stays there while the
  /// others go on.
  int segmentIterations(std::size_t s) const { return context_.stops.iterations()[s]; }

  /// Accelerated iterates rejected (objective rose) since construction.
  int rejectedAccelerations() const { return extrapolated_.rejected(); }

  /// The scenes of a batch (block-diagonal K_c): L-BFGS keeps its dot products, step lengths
  /// and history per segment, Chebyshev and Anderson their rule, objective and safeguard,
  /// Newton-CG its CG and line search, so each scene takes the steps it takes alone. Without segments
  /// the whole system is one. `energy_scales` (one per segment) replace IterationControl::
  /// energy_scale in each segment's round-off allowance.
  void setSegments(const std::vector<SceneSegment>& segments, const std::vector<double>& energy_scales) {
    context_.setSegments(segments, energy_scales);
  }

  /// The segments the next solve solves, one flag per segment (a batch's scenes that step, or
  /// that need the blend's partner); empty: all of them. A segment not flagged keeps its rows of
  /// slot x (the warm start), takes no iteration (segmentIterations 0) and has no potential in
  /// potentialsOfResult (NaN); on the CPU reference its element passes and its trees of the
  /// factor's solve are not run, and its history work on the host is not done either way.
  /// The flags hold for the next solve only (a caller that sets none gets every segment solved).
  void setSolving(std::vector<char> segments) { next_solving_ = std::move(segments); }
  /// The segments whose L-BFGS initial Hessian may take their rigid motions in the next solve
  /// (with IterationControl::rigid_modes), one flag per segment; empty: all of them. Like
  /// setSolving, for the next solve only.
  void setRigidModes(std::vector<char> segments) { next_rigid_ = std::move(segments); }

  /// The scene whose springs Newton-CG takes its Hessians from (Acceleration::Newton) and whose
  /// one-particle elements and external forces the rigid motions read, with its forcing (both
  /// must outlive the solver); without one Newton-CG's Hessian is K_c and no solve takes the
  /// rigid motions.
  void setScene(const SceneData& scene, const Forcing& forcing) { context_.setScene(scene, forcing); }
  /// The contact set's changes within L-BFGS's solves (SolveContext::ContactChange); the other
  /// accelerations keep the step's set through their solves.
  void setContactChange(SolveContext::ContactChange change) { context_.setContactChange(std::move(change)); }

 private:
  SolveContext context_;
  PlainIterations plain_;
  ExtrapolatedIterations extrapolated_;
  LbfgsIterations lbfgs_;
  NewtonIterations newton_;
  std::vector<char> next_solving_;  // setSolving, for the next solve
  std::vector<char> next_rigid_;    // setRigidModes, for the next solve
};

}  // namespace stabint
