// Energy and accuracy metrics of a recorded run.
#include "study.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace study {

Metrics energyMetrics(const RunResult& run, double available_energy) {
  Metrics m;
  m.available = available_energy;
  const std::vector<FrameSample>& s = run.samples;
  m.h0 = s.front().total();
  m.h_end = s.back().total();
  m.h_min = m.h_max = m.h0;
  double max_abs_change = 0.0;
  for (const FrameSample& f : s) {
    const double h = f.total();
    m.h_min = std::min(m.h_min, h);
    m.h_max = std::max(m.h_max, h);
    m.max_target_dev = std::max(m.max_target_dev, std::abs(h - f.target));
    max_abs_change = std::max(max_abs_change, std::abs(h - m.h0));
  }
  const double e = available_energy;
  m.max_target_dev /= e;
  m.max_rise = (m.h_max - m.h0) / e;
  m.drift = (m.h_end - m.h0) / e;
  // The end of an oscillating run sits anywhere in its swing: average the last 10 % of frames.
  const size_t tail = std::max<size_t>(1, (s.size() - 1) / 10);
  double mean = 0.0;
  for (size_t i = s.size() - tail; i < s.size(); ++i) mean += s[i].total();
  mean /= static_cast<double>(tail);
  m.damping = (m.h0 - mean) / e;

  if (run.blew_up_frame >= 0 || run.stopped_early || !(max_abs_change <= kExplodeFactor * e))
    m.verdict = "exploded";
  else if (m.damping > kOverDampedFraction)
    m.verdict = "over-damped";
  else
    m.verdict = "stable";
  return m;
}

double positionRmsError(const RunResult& run, const std::vector<Eigen::MatrixX3d>& reference) {
  const size_t frames = reference.size() - 1;
  if (run.positions.size() < reference.size()) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  size_t count = 0;
  for (size_t f = 1; f <= frames; ++f) {
    sum += (run.positions[f] - reference[f]).rowwise().squaredNorm().sum();
    count += static_cast<size_t>(reference[f].rows());
  }
  const double rms = std::sqrt(sum / static_cast<double>(count));
  return std::isfinite(rms) ? rms : std::numeric_limits<double>::infinity();
}

}  // namespace study
