// One recorded simulation run: frames of one or more simulator steps, energies per frame,
// positions on request, the blow-up frame, wall-clock time of the steps.
#include "study.hpp"

#include <chrono>
#include <cmath>

namespace study {

namespace {

// alpha comes out of a root find; "whole" means alpha_max = 1 itself, within round-off.
constexpr double kWholePartnerSlack = 1e-12;

FrameSample sampleOf(double time, const stabint::EnergyReport& e, double target) {
  FrameSample f;
  f.time = time;
  f.kinetic = e.kinetic;
  f.elastic = e.elastic;
  f.external = e.external;
  f.target = target;
  return f;
}

FrameSample sampleOf(const stabint::Simulator& sim) { return sampleOf(sim.time(), sim.energy(), sim.target()); }

// One accepted step's report into the frame under way and the run's branch counts.
void countStep(const stabint::StepReport& r, FrameSample& partial, RunResult& run) {
  partial.iterations += r.iterations;
  partial.branch = r.branch;
  partial.alpha = r.alpha;
  // Counted by printed name, so that branches added or renamed in the library need no
  // change here.
  if (r.branch != BlendBranch::None) {
    ++run.branches[stabint::blendBranchName(r.branch)];
    if (r.branch != BlendBranch::ImplicitMidpoint && r.alpha >= 1.0 - kWholePartnerSlack) {
      ++run.partner_whole;
      ++run.partner_whole_by_branch[stabint::blendBranchName(r.branch)];
    }
  }
}

// A completed frame: its sample, and whether the run stops here (|H - H_0| beyond stop_factor).
bool endFrame(int frame, FrameSample f, const FrameSample& partial, const RunSpec& spec, RunResult& run) {
  f.iterations = partial.iterations;
  f.branch = partial.branch;
  f.alpha = partial.alpha;
  f.seconds = partial.seconds;
  run.samples.push_back(f);
  run.frames_done = frame;
  if (spec.stop_factor > 0.0 &&
      !(std::abs(f.total() - run.samples.front().total()) <= spec.stop_factor * spec.energy_unit)) {
    run.stopped_early = true;
    return true;
  }
  return false;
}

stabint::SimulatorOptions simulatorOptions(const RunSpec& spec) {
  stabint::SimulatorOptions o;
  o.integrator = spec.integrator;
  o.time_step = spec.frame_step / spec.substeps;
  o.iterations = spec.iterations;
  o.tolerance = spec.tolerance;
  o.max_iterations = spec.max_iterations;
  o.be_iterations = spec.be_iterations;
  o.acceleration = spec.acceleration;
  o.backend = spec.backend;
  return o;
}

}  // namespace

namespace {
std::string countSummary(const std::map<std::string, int>& counts) {
  std::string text;
  for (const auto& [name, count] : counts) text += (text.empty() ? "" : ";") + name + "=" + std::to_string(count);
  return text.empty() ? "-" : text;
}
}  // namespace

std::string RunResult::branchSummary() const { return countSummary(branches); }
std::string RunResult::partnerWholeSummary() const { return countSummary(partner_whole_by_branch); }

double RunResult::medianMsPerFrame() const {
  std::vector<double> ms;
  for (size_t f = 1; f < samples.size(); ++f) ms.push_back(1e3 * samples[f].seconds);
  return ms.empty() ? ms_per_frame() : median(std::move(ms));
}

RunResult simulate(const Scene& scene, const RunSpec& spec,
                   const std::function<void(int, const stabint::Simulator&)>& on_frame) {
  stabint::Simulator sim(scene, simulatorOptions(spec));

  RunResult run;
  run.energy_scale = sim.energyScale();
  run.substeps = spec.substeps;
  run.samples.push_back(sampleOf(sim));
  if (spec.record_positions) run.positions.push_back(sim.positions());

  for (int frame = 1; frame <= spec.frames; ++frame) {
    FrameSample partial;
    try {
      for (int s = 0; s < spec.substeps; ++s) {
        const auto start = std::chrono::steady_clock::now();
        ++run.steps_tried;
        try {
          sim.step();
        } catch (...) {
          run.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          throw;
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        run.seconds += seconds;
        partial.seconds += seconds;
        countStep(sim.lastReport(), partial, run);
      }
    } catch (const stabint::NonFiniteStateError& e) {
      run.blew_up_frame = frame;
      run.blow_up_message = e.what();
      break;
    }
    const bool stop = endFrame(frame, sampleOf(sim), partial, spec, run);
    if (spec.record_positions) run.positions.push_back(sim.positions());
    if (on_frame) on_frame(frame, sim);
    if (stop) break;
  }
  return run;
}

std::vector<RunResult> simulateBatch(const std::vector<Scene>& scenes, const RunSpec& spec,
                                     const std::vector<double>& energy_units) {
  stabint::BatchSimulator batch(scenes, simulatorOptions(spec));
  const std::size_t n = scenes.size();
  std::vector<RunResult> runs(n);
  std::vector<bool> running(n, true);
  for (std::size_t s = 0; s < n; ++s) {
    const int i = static_cast<int>(s);
    runs[s].energy_scale = batch.energyScale(i);
    runs[s].substeps = spec.substeps;
    runs[s].samples.push_back(sampleOf(batch.time(i), batch.energy(i), batch.target(i)));
    if (spec.record_positions) runs[s].positions.push_back(batch.positions(i));
  }
  for (int frame = 1; frame <= spec.frames; ++frame) {
    std::vector<FrameSample> partial(n);
    for (int sub = 0; sub < spec.substeps; ++sub) {
      const auto start = std::chrono::steady_clock::now();
      const stabint::BatchStepReport& report = batch.step();
      const double share =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / static_cast<double>(n);
      for (std::size_t s = 0; s < n; ++s) {
        if (!running[s]) continue;
        ++runs[s].steps_tried;
        runs[s].seconds += share;
        partial[s].seconds += share;
        if (!report.refusals[s].empty()) {  // what Simulator::step throws: NonFiniteStateError
          runs[s].blew_up_frame = frame;
          runs[s].blow_up_message = report.refusals[s];
          running[s] = false;
          continue;
        }
        countStep(report.scenes[s], partial[s], runs[s]);
      }
    }
    bool any = false;
    for (std::size_t s = 0; s < n; ++s) {
      if (!running[s]) continue;
      const int i = static_cast<int>(s);
      RunSpec own = spec;
      own.energy_unit = energy_units[s];
      running[s] =
          !endFrame(frame, sampleOf(batch.time(i), batch.energy(i), batch.target(i)), partial[s], own, runs[s]);
      if (spec.record_positions) runs[s].positions.push_back(batch.positions(i));
      any = any || running[s];
    }
    if (!any) break;
  }
  return runs;
}

}  // namespace study
