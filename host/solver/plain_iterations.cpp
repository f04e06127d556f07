// Plain local/global iterations (docs/method.md, "Local/global iterations"): a local step and a
// global step each, over the whole system or each scene segment on its own.
#include "solver/accelerations.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace stabint {

int PlainIterations::solve(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                           std::vector<double>* objective_history, std::size_t taking_part) {
  const std::size_t segments = std::max<std::size_t>(1, ctx.rows().size());
  if ((control.tolerance > 0.0 || taking_part < segments) && ctx.rows().size() > 1)
    return solvePerSegment(ctx, c, y, x, t, control);
  const int done = solveWhole(ctx, c, y, x, t, control, objective_history);
  ctx.stops.iterations().assign(segments, done);
  return done;
}

int PlainIterations::solveWhole(SolveContext& ctx, double c, int y, int x, double t, const IterationControl& control,
                                std::vector<double>* objective_history) {
  const bool to_tolerance = control.tolerance > 0.0;
  const bool track = to_tolerance || objective_history != nullptr;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  if (control.global_solve == GlobalSolve::ConjugateGradient && !ctx.onBackend(control))
    ctx.backend().read(x, ctx.x_host);
  if (!track) {
    for (int done = 0; done < limit; ++done) {
      ctx.localStep(c, y, x, t, control, nullptr);
      ctx.globalStep(c, x, control, /*to_host=*/false);
    }
    // On the backend the iterations were only queued: wait here, once per solve, so that the
    // phase times (and a benchmark) see them done. Booked as global: local steps, gathers and CG
    // run back to back on the device without a wait between them.
    if (ctx.onBackend(control)) {
      const auto start = std::chrono::steady_clock::now();
      ctx.backend().synchronize();
      ctx.backend().times().global += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return std::max(limit, 0);
  }
  // The objective of each iterate comes from the local step at it, whose element pass also
  // returns the potential (equal to potential() bit for bit): one pass per iterate instead of an
  // energy pass and a local step with the same projections. The pass after the last iterate only
  // serves its objective.
  PotentialEnergy potential;
  auto localStepAndObjective = [&] {
    ctx.localStep(c, y, x, t, control, &potential);
    if (ctx.rows().size() <= 1) ctx.resultPotentials().assign(1, potential);  // a batch's is their sum
    ctx.backend().combine(ctx.scratch(), 1.0, x, -1.0, y);
    return 0.5 * c * ctx.backend().massDot(ctx.scratch(), ctx.scratch()) + potential.total();
  };
  double previous = localStepAndObjective();
  if (objective_history) objective_history->assign(1, previous);
  int done = 0;
  while (done < limit) {
    ctx.globalStep(c, x, control, /*to_host=*/false);
    ++done;
    const double current = localStepAndObjective();
    if (objective_history) objective_history->push_back(current);
    const double change = std::abs(previous - current);
    previous = current;
    if (to_tolerance && change <= control.tolerance * std::max(std::abs(current), control.energy_scale)) break;
  }
  return done;
}

// Plain iterations of a batch with the tolerance stop, or of some of its scenes (setSolving): each
// segment's objective is its scene's (the local step's per-scene energies and massDots: the
// numbers its own Simulator's solve computes) and so is its stop; a segment that has stopped, or
// takes no part, keeps its iterate (its rows are written back after every later global step) and
// the count at its stop, while the others go on. The local step at each iterate gives both its
// objectives and the next global step's right-hand side: one element pass per iteration.
int PlainIterations::solvePerSegment(SolveContext& ctx, double c, int y, int x, double t,
                                     const IterationControl& control) {
  const std::size_t segments = ctx.rows().size();
  const bool to_tolerance = control.tolerance > 0.0;
  const int limit = to_tolerance ? control.max_iterations : control.iterations;
  std::vector<double>&previous = ctx.scalars[0], &current = ctx.scalars[1], &dots = ctx.scalars[2];
  auto objectives = [&](std::vector<double>& out) {
    ctx.backend().localStepRhsPerScene(x, y, c, t, ctx.rhs, ctx.segment_potentials, ctx.stops.mask());
    ctx.backend().combine(ctx.scratch(), 1.0, x, -1.0, y);
    ctx.backend().massDots(ctx.scratch(), ctx.scratch(), dots);
    out.resize(segments);
    for (std::size_t s = 0; s < segments; ++s) out[s] = 0.5 * c * dots[s] + ctx.segment_potentials[s].total();
  };
  ctx.stops.start(segments);
  // The warm start: CG's, and the rows of the segments that take no part.
  if (control.global_solve == GlobalSolve::ConjugateGradient || ctx.stops.runningCount() < segments)
    ctx.backend().read(x, ctx.x_host);
  if (ctx.stops.runningCount() < segments) x_stopped_ = ctx.x_host;
  objectives(previous);
  int done = 0;
  while (done < limit) {
    ctx.globalStep(c, x, control, /*to_host=*/true);
    ++done;
    for (std::size_t s = 0; s < segments && ctx.stops.runningCount() < segments; ++s)
      if (ctx.stops.stopped(s)) ctx.segmentRows(ctx.x_host, s) = ctx.segmentRows(x_stopped_, s);
    ctx.backend().write(x, ctx.x_host);
    objectives(current);
    for (std::size_t s = 0; s < segments; ++s) {
      if (ctx.stops.stopped(s)) continue;
      const double scale = ctx.segmentScale(control, s);
      if (to_tolerance &&
          std::abs(previous[s] - current[s]) <= control.tolerance * std::max(std::abs(current[s]), scale)) {
        ctx.stops.stop(s, done);
        if (x_stopped_.rows() != ctx.x_host.rows()) x_stopped_.resize(ctx.x_host.rows(), 3);
        ctx.segmentRows(x_stopped_, s) = ctx.segmentRows(ctx.x_host, s);
      }
    }
    previous.swap(current);
    if (ctx.stops.runningCount() == 0) break;
  }
  ctx.stops.finish(done);
  ctx.keepResultPotentials();  // of slot x as it is left
  return done;
}

}  // namespace stabint
