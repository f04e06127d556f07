// One recorded simulation run: frames of one or more simulator steps, energies per frame,
// positions on request, the blow-up frame, wall-clock time of the steps.
#include "study.hpp"

#include <chrono>
#include <cmath>

namespace study {

namespace {

// alpha comes out of a root find; "whole" means alpha_max = 1 itself, within round-off.
constexpr double kWholePartnerSlack = 1e-12;

FrameSample sampleOf(const stabint::Simulator& sim) {
  FrameSample f;
  f.time = sim.time();
  const stabint::EnergyReport e = sim.energy();
  f.kinetic = e.kinetic;
  f.elastic = e.elastic;
  f.external = e.external;
  f.target = sim.target();
  return f;
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
  stabint::SimulatorOptions o;
  o.integrator = spec.integrator;
  o.time_step = spec.frame_step / spec.substeps;
  o.iterations = spec.iterations;
  o.tolerance = spec.tolerance;
  o.max_iterations = spec.max_iterations;
  o.be_iterations = spec.be_iterations;
  o.acceleration = spec.acceleration;
  o.backend = spec.backend;
  stabint::Simulator sim(scene, o);

  RunResult run;
  run.energy_scale = sim.energyScale();
  run.substeps = spec.substeps;
  run.samples.push_back(sampleOf(sim));
  if (spec.record_positions) run.positions.push_back(sim.positions());
  const double h0 = run.samples.front().total();

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
        const stabint::StepReport& r = sim.lastReport();
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
    } catch (const stabint::NonFiniteStateError& e) {
      run.blew_up_frame = frame;
      run.blow_up_message = e.what();
      break;
    }
    FrameSample f = sampleOf(sim);
    f.iterations = partial.iterations;
    f.branch = partial.branch;
    f.alpha = partial.alpha;
    f.seconds = partial.seconds;
    run.samples.push_back(f);
    if (spec.record_positions) run.positions.push_back(sim.positions());
    run.frames_done = frame;
    if (on_frame) on_frame(frame, sim);
    if (spec.stop_factor > 0.0 && !(std::abs(f.total() - h0) <= spec.stop_factor * spec.energy_unit)) {
      run.stopped_early = true;
      break;
    }
  }
  return run;
}

}  // namespace study
