#pragma once
// The backend interface the integrator driver talks to: whole-array operations on a fixed set of
// `n by 3` state slots that live in the backend's memory (host arrays for the CPU reference,
// device buffers for OpenCL). The integrators (host/integrator/) are written once against
// this interface; the global sparse solve stays on the host (host/solver/), except with
// GlobalSolve::ConjugateGradient on a backend that solvesGlobalSystem() (OpenCL: on the device).
#include "scene/scene_batch.hpp"

#include <stabint/types.hpp>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <cstdint>
#include <string>
#include <vector>

namespace stabint {

class Forcing;
class SceneData;

/// Potential energy split by the way the blend books it: the internal energy of the elements
/// never depends on time, pins and external forces may.
struct PotentialEnergy {
  double internal = 0.0;  // every element type of EnergyTerm::Internal (all but pins)
  double pins = 0.0;      // pins and contact at time t (the elements whose params may move)
  double external = 0.0;  // -sum (m g + f(t)).x
  double elastic() const { return internal + pins; }
  double total() const { return internal + pins + external; }
};

class Backend {
 public:
  virtual ~Backend() = default;

  /// Copies between host and a slot (`n by 3`).
  virtual void write(int slot, const Eigen::MatrixX3d& host) = 0;
  virtual void read(int slot, Eigen::MatrixX3d& host) = 0;
  /// Two slots to the host; on a device backend with one wait instead of two.
  virtual void readBoth(int slot_a, Eigen::MatrixX3d& a, int slot_b, Eigen::MatrixX3d& b) {
    read(slot_a, a);
    read(slot_b, b);
  }
  /// Rounds host values to what a slot holds after write() (a device in float keeps floats).
  virtual void roundToStorage(Eigen::MatrixX3d& /*host*/) const {}
  /// Whether writeRows is available: the backend writes some rows of a slot alone and then holds
  /// them as roundToStorage gives them (exactly as given but on a float device). One scene's input
  /// then costs that scene's rows.
  virtual bool writesRows() const { return false; }
  /// Rows first.. of a slot from the host (only where writesRows()).
  virtual void writeRows(int /*slot*/, int /*first*/, const Eigen::MatrixX3d& /*rows*/) {
    throw Error(description() + " writes whole slots only");
  }
  virtual void copy(int dst, int src) = 0;
  /// dst = a * x + b * y. dst may be x or y.
  virtual void combine(int dst, double a, int x, double b, int y) = 0;
  /// sum_j m_j a_j . b_j
  virtual double massDot(int a, int b) = 0;
  /// E_int and U_ext of the positions in `x` at time t (an element pass + reduction).
  virtual PotentialEnergy potential(int x, double t) = 0;
  /// dst = M^-1 f(x, t), f = -grad E_int - grad U_ext.
  virtual void accelerations(int dst, int x, double t) = 0;
  /// Local step at positions `x` followed by the gather of the global right-hand side
  ///   rhs = c M y + sum_e w_e A_e^T p_e(x) + (m g + f(t)),
  /// returned on the host as `n by 3` (the only per-iteration transfer to the host). When
  /// `energy_at_x` is given it also receives potential(x, t), computed in the same element pass
  /// from the projections the local step has anyway.
  virtual void localStepRhs(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                            PotentialEnergy* energy_at_x = nullptr) = 0;
  /// The same element pass in its force form, gathered into the gradient of one implicit solve's
  /// objective c/2 ||x - y||_M^2 + E_int(x) + U_ext(x, t) at `x`:
  ///   g = c M (x - y) - (m g + f(t)) - sum_e w_e A_e^T (p_e(x) - A_e x),
  /// returned on the host (what L-BFGS and Newton-CG read per iteration instead of the
  /// right-hand side: it equals K_c x - rhs, without the cancellation of two large terms and
  /// without a product with K_c). `energy_at_x` as in localStepRhs.
  virtual void localStepGradient(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                                 PotentialEnergy* energy_at_x = nullptr) = 0;

  // ---- the global step on the backend (GlobalSolve::ConjugateGradient; docs/method.md) -------
  // A backend that keeps the global system in its own memory runs the whole local/global
  // iteration there: localStep leaves the right-hand side in place and solveGlobal runs a
  // Jacobi-preconditioned CG on it, so nothing crosses to the host per iteration. The CPU
  // reference has none (its host CG is GlobalSystem::solveConjugateGradient).

  /// Whether localStep / solveGlobal are available.
  virtual bool solvesGlobalSystem() const { return false; }
  /// Copies L = sum_e w_e A_e^T A_e (symmetric, `n by n`) into the backend; called again after
  /// every change of L (element changes, grabs).
  virtual void setGlobalMatrix(const Eigen::SparseMatrix<double>& /*laplacian*/) { noGlobalSolver(); }
  /// localStepRhs with the right-hand side kept in the backend for solveGlobal. Reads back only
  /// the energy, when `energy_at_x` is given.
  virtual void localStep(int /*x*/, int /*y*/, double /*c*/, double /*t*/, PotentialEnergy* /*energy_at_x*/) {
    noGlobalSolver();
  }
  /// `iterations` Jacobi-preconditioned CG iterations on (c M + L) x = rhs (the last localStep's),
  /// warm-started from slot `x`, which receives the result; with `tolerance` > 0 it stops once
  /// ||rhs - K x|| <= tolerance ||rhs|| in every column. Returns the CG iterations done.
  virtual int solveGlobal(double /*c*/, int /*x*/, int /*iterations*/, double /*tolerance*/) {
    noGlobalSolver();
    return 0;
  }
  // ---- per-scene results of a batch (docs/batch_design.md, "Backend operations") -------------
  // The backend's scene is a concatenation (concatenateScenes) whose segments were set once; each
  // call gives one value per segment, each summed as a backend of that scene alone sums it (bit
  // for bit on the CPU reference), so one scene's energy never depends on its neighbours'.

  /// Whether setSegments / massDots / potentials are available.
  virtual bool computesPerScene() const { return false; }
  /// The segments of the backend's scene (their element ranges index SceneData::blocks(), which
  /// are in elementTypes() order): those concatenateScenes gave with that scene; not checked.
  virtual void setSegments(const std::vector<SceneSegment>& /*segments*/) { notPerScene(); }
  /// out[s] = sum over segment s's particles of m_j a_j . b_j.
  virtual void massDots(int /*a*/, int /*b*/, std::vector<double>& /*out*/) { notPerScene(); }
  /// out[s] = potential of segment s's particles and elements in `x` at time t. With `which` (one
  /// flag per segment) a backend may skip the segments not flagged: their entries are then
  /// unspecified (the CPU reference leaves them as they were; the OpenCL backend does so where a
  /// few launches cover the flagged ones, else it computes every segment in one launch).
  virtual void potentials(int /*x*/, double /*t*/, std::vector<PotentialEnergy>& /*out*/,
                          const std::vector<char>* /*which*/ = nullptr) {
    notPerScene();
  }
  /// localStepGradient with every segment's potential at `x` (as potentials() gives them) instead
  /// of the whole scene's: a batch's L-BFGS line search. A backend that can sum per segment in
  /// the same element pass does one pass; the others run potentials() after it.
  ///
  /// With `running` (one flag per segment), a backend may skip the segments not flagged (a
  /// batch's scenes that take no part in the solve, or stopped in it): their entries of
  /// `per_scene` and their rows of the result are then unspecified. The CPU reference skips them;
  /// the OpenCL backend skips their work-groups where a few launches cover the others (else one
  /// launch for the batch).
  virtual void localStepGradientPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                                         std::vector<PotentialEnergy>& per_scene,
                                         const std::vector<char>* /*running*/ = nullptr) {
    localStepGradient(x, y, c, t, gradient, nullptr);
    potentials(x, t, per_scene);
  }
  /// localStepRhs with every segment's potential at `x` (as potentials() gives them): a batch's
  /// Chebyshev and Anderson solves and plain iterations' tolerance stop, which compare each
  /// scene's objective. A backend
  /// that can sum per segment in the same element pass does one pass; the others run
  /// potentials() after it.
  /// `running` as for localStepGradientPerScene.
  virtual void localStepRhsPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                                    std::vector<PotentialEnergy>& per_scene,
                                    const std::vector<char>* /*running*/ = nullptr) {
    localStepRhs(x, y, c, t, rhs, nullptr);
    potentials(x, t, per_scene);
  }
  /// potentials()[segment] alone; a backend that can pass over one segment's elements costs that
  /// segment's (one scene's event in a batch), the others pass over all of them.
  virtual PotentialEnergy potentialOf(int segment, int x, double t) {
    std::vector<PotentialEnergy> all;
    potentials(x, t, all);
    return all[static_cast<std::size_t>(segment)];
  }
  /// out[i] = potentialOf(segments[i], x, t), bit for bit (several scenes' events at once). A
  /// device backend passes over those segments' elements and waits once for all their sums.
  virtual void potentialsOf(const std::vector<int>& segments, int x, double t, std::vector<PotentialEnergy>& out) {
    out.clear();
    for (int segment : segments) out.push_back(potentialOf(segment, x, t));
  }

  /// Waits until everything queued has completed.
  virtual void synchronize() {}

  /// The scene's element blocks and contribution lists were rebuilt (SceneData::setPins): the
  /// backend drops what it derived from the old ones.
  virtual void elementsChanged() {}

  /// Phase timers (local, gather, transfer, energy) accumulated since the last reset.
  PhaseTimes& times() { return times_; }
  /// Bytes copied between host and device and kernels launched since the backend was made
  /// (zeros on the CPU reference): what issue 50's rule of no transfer inside a solve's
  /// iterations counts. Device-side copies and fills are neither.
  struct Traffic {
    std::int64_t to_device = 0, to_host = 0, launches = 0;
  };
  const Traffic& traffic() const { return traffic_; }
  virtual std::string description() const = 0;

 protected:
  PhaseTimes times_;
  Traffic traffic_;

 private:
  void noGlobalSolver() const { throw Error(description() + " does not solve the global system itself"); }
  void notPerScene() const { throw Error(description() + " has no per-scene results of a batch yet"); }
};

}  // namespace stabint
