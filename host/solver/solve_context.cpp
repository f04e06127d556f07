#include "solver/solve_context.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

namespace stabint {

namespace {

// Armijo's sufficient-decrease constant. A plain step satisfies the test with any constant up to
// 1/2 (f(x + d) <= f(x) - 1/2 d^T K_c d, d = -K_c^-1 g), so an empty history always passes.
constexpr double kArmijo = 1e-4;
// Halvings of a step that fails the test before the segment stays where it is for this iteration
// and drops its history (its next direction is the plain step).
constexpr int kMaxHalvings = 4;

}  // namespace

std::size_t SegmentStops::begin(std::size_t segments, std::vector<char> flags) {
  whole_ = segments <= 1;
  solving_ = std::move(flags);
  running_.clear();  // no stops yet: every pass and solve over the whole batch
  running_count_ = 0;
  const std::size_t count = std::max<std::size_t>(1, segments);
  std::size_t taking_part = 0;
  for (std::size_t s = 0; s < count; ++s) taking_part += solving(s) ? 1 : 0;
  if (taking_part == 0) iterations_.assign(count, 0);
  return taking_part;
}

void SegmentStops::start(std::size_t segments) {
  running_.assign(segments, 1);
  iterations_.assign(segments, 0);
  running_count_ = segments;
  for (std::size_t s = 0; s < segments; ++s)
    if (!solving(s)) stop(s, 0);
}

void SegmentStops::stop(std::size_t s, int done) {
  running_[s] = 0;
  iterations_[s] = done;
  --running_count_;
}

void SegmentStops::finish(int done) {
  for (std::size_t s = 0; s < running_.size(); ++s)
    if (running_[s]) iterations_[s] = done;
}

SolveContext::SolveContext(Backend& backend, GlobalSystem& system, int scratch_slot)
    : masses(system.masses()), backend_(backend), system_(system), scratch_(scratch_slot) {}

void SolveContext::coverWholeSystem() {
  if (rows_.empty()) rows_.push_back({0, static_cast<int>(masses.size())});
}

void SolveContext::setSegments(const std::vector<SceneSegment>& segments, const std::vector<double>& energy_scales) {
  rows_.clear();
  for (const SceneSegment& s : segments) rows_.push_back({s.first_particle, s.num_particles});
  segments_ = segments;
  system_.setBlocks(segments);  // a batch's host CG per scene
  segment_scales_ = energy_scales;
}

void SolveContext::setScene(const SceneData& scene, const Forcing& forcing) {
  scene_ = &scene;
  forcing_ = &forcing;
}

std::vector<char> SolveContext::changeContacts(double c, int done, int limit, int x, double t, bool& release) {
  // [project rule] The release after the third iteration: by then a lifted particle's iterate has
  // risen clearly, and seven of ten iterations remain to move it without its pair's weight in
  // K_c. A released particle that an iterate takes back inside its collider returns at once.
  constexpr int kReleaseIteration = 3;
  release = done == kReleaseIteration;
  if (!contact_change_ || done < kReleaseIteration || done >= limit) return {};
  std::vector<char> running(std::max<std::size_t>(1, rows_.size()));
  for (std::size_t s = 0; s < running.size(); ++s) running[s] = stops.stopped(s) ? 0 : 1;
  // The forces on the particles at the iterate less the inertia's: -(g - c M (x - y)).
  if (release) search = ((x_cur - y_host).array().colwise() * (c * masses).array()).matrix() - gradient;
  return contact_change_(x, search, t, running, release);
}

double SolveContext::objective(double c, int y, int x, double t) {
  backend_.combine(scratch_, 1.0, x, -1.0, y);
  return 0.5 * c * backend_.massDot(scratch_, scratch_) + backend_.potential(x, t).total();
}

double SolveContext::inertia(double c, const Eigen::MatrixX3d& x) const {
  return 0.5 * c * ((x - y_host).rowwise().squaredNorm().transpose() * masses)(0);
}

double SolveContext::segmentInertia(double c, const Eigen::MatrixX3d& x, std::size_t s) const {
  const SegmentRows& seg = rows_[s];
  const auto d = x.middleRows(seg.first, seg.count) - y_host.middleRows(seg.first, seg.count);
  return 0.5 * c * (d.rowwise().squaredNorm().transpose() * masses.segment(seg.first, seg.count))(0);
}

void SolveContext::segmentDots(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, std::vector<double>& out) const {
  out.resize(rows_.size());
  for (std::size_t s = 0; s < rows_.size(); ++s) {
    const SegmentRows& seg = rows_[s];
    out[s] = a.middleRows(seg.first, seg.count).cwiseProduct(b.middleRows(seg.first, seg.count)).sum();
  }
}

void SolveContext::keepResultPotentials() {
  result_potentials_ = segment_potentials;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t s = 0; s < result_potentials_.size(); ++s)
    if (!stops.solving(s)) result_potentials_[s] = PotentialEnergy{nan, nan, nan};
}

void SolveContext::localStep(double c, int y, int x, double t, const IterationControl& control,
                             PotentialEnergy* energy) {
  if (onBackend(control)) {
    backend_.localStep(x, y, c, t, energy);
  } else {
    backend_.localStepRhs(x, y, c, t, rhs, energy);
  }
}

void SolveContext::globalStep(double c, int x, const IterationControl& control, bool to_host) {
  const auto start = std::chrono::steady_clock::now();
  if (onBackend(control)) {
    // The backend's copy of L follows every change of L (grabs, element changes) here, before
    // the first solve that needs it.
    if (backend_matrix_version_ != system_.laplacianVersion()) {
      backend_.setGlobalMatrix(system_.stiffnessLaplacian());
      backend_matrix_version_ = system_.laplacianVersion();
    }
    backend_.solveGlobal(c, x, control.cg_iterations, control.cg_tolerance);
    backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (to_host) backend_.read(x, x_host);
    return;
  }
  if (control.global_solve == GlobalSolve::ConjugateGradient) {
    system_.solveConjugateGradient(c, rhs, x_host, control.cg_iterations, control.cg_tolerance, stops.mask());
  } else {
    system_.solve(c, rhs, x_host, stops.mask());
  }
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!to_host) backend_.write(x, x_host);  // the backend books its own transfer time
}

void SolveContext::applyInitialInverseHessian(double c, const IterationControl& control, const Eigen::MatrixX3d& q,
                                              Eigen::MatrixX3d& r) {
  const auto start = std::chrono::steady_clock::now();
  if (control.global_solve == GlobalSolve::ConjugateGradient) {
    r.setZero(q.rows(), 3);
    system_.solveConjugateGradient(c, q, r, control.cg_iterations, control.cg_tolerance, stops.mask());
  } else {
    system_.solve(c, q, r, stops.mask());
  }
  backend_.times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The objective of every segment at the positions x_trial (already in slot x), from the local
// step that also leaves the gradient there in trial_gradient.
void SolveContext::localStepObjectives(double c, int y, int x, double t, std::vector<double>& objective) {
  objective.resize(rows_.size());
  if (rows_.size() == 1) {
    PotentialEnergy potential;
    backend_.localStepGradient(x, y, c, t, trial_gradient, &potential);
    objective[0] = inertia(c, x_trial) + potential.total();
    result_potentials_.assign(1, potential);
    return;
  }
  backend_.localStepGradientPerScene(x, y, c, t, trial_gradient, segment_potentials, stops.mask());
  keepResultPotentials();
  for (std::size_t s = 0; s < rows_.size(); ++s)
    objective[s] = segmentInertia(c, x_trial, s) + segment_potentials[s].total();
}

// Backtracking line search from x_cur along direction, per segment: the full step where
// f(x + a d) <= f(x) + kArmijo a g.d up to round-off of the objective (two backends that agree to
// round-off must take the same decisions), else halved up to kMaxHalvings times. A segment whose
// slope is not negative takes no step (step 0); one that finds no decrease stays (step != 0).
// Leaves x_trial, slot x and trial_gradient at the kept positions, their objectives in `trial_objective`
// and the segments that moved in moved_.
void SolveContext::lineSearch(double c, int y, int x, double t, const IterationControl& control,
                              const std::vector<double>& objective, const std::vector<double>& slope,
                              std::vector<double>& step, std::vector<double>& trial_objective) {
  const std::size_t segments = rows_.size();
  step.resize(segments);
  // A segment that takes no step keeps its objective (when none steps, no local step runs).
  trial_objective = objective;
  accepted_.assign(segments, 0);
  moved_.assign(segments, 0);
  for (std::size_t s = 0; s < segments; ++s) {
    step[s] = slope[s] < 0.0 ? 1.0 : 0.0;
    accepted_[s] = step[s] == 0.0;
  }
  for (int halving = 0; halving <= kMaxHalvings; ++halving) {
    bool any_trial = false;
    for (std::size_t s = 0; s < segments; ++s) {
      if (accepted_[s]) continue;
      segmentRows(x_trial, s) = segmentRows(x_cur, s) + step[s] * segmentRows(direction, s);
      any_trial = true;
    }
    if (!any_trial) break;
    backend_.roundToStorage(x_trial);
    backend_.write(x, x_trial);
    localStepObjectives(c, y, x, t, trial_objective);
    for (std::size_t s = 0; s < segments; ++s) {
      if (accepted_[s]) continue;
      const double scale = segmentScale(control, s);
      const double noise = 1e-12 * std::max(std::abs(objective[s]), scale);
      if (trial_objective[s] <= objective[s] + kArmijo * step[s] * slope[s] + noise) {
        accepted_[s] = 1;
        moved_[s] = 1;
      } else if (halving < kMaxHalvings) {
        step[s] *= 0.5;
      } else {
        accepted_[s] = 1;
        segmentRows(x_trial, s) = segmentRows(x_cur, s);
      }
    }
  }
  // Slot x and trial_gradient must be at the kept positions: a segment that stayed changed slot x in its
  // trials, so one more local step at them.
  bool any_stayed = false;
  for (std::size_t s = 0; s < segments; ++s) any_stayed |= !moved_[s] && step[s] != 0.0;
  if (any_stayed) {
    backend_.write(x, x_trial);
    localStepObjectives(c, y, x, t, trial_objective);
  }
}

}  // namespace stabint
