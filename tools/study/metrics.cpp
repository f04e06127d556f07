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
    if (!(std::abs(h - m.h0) <= kExplodeFactor * available_energy) && !std::isfinite(m.exploded_at))
      m.exploded_at = f.time;
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

  if (run.blew_up_frame >= 0 && !std::isfinite(m.exploded_at)) m.exploded_at = s.back().time;
  if (run.blew_up_frame >= 0 || run.stopped_early || !(max_abs_change <= kExplodeFactor * e))
    m.verdict = "exploded";
  else if (m.damping > kOverDampedFraction)
    m.verdict = "over-damped";
  else
    m.verdict = "stable";
  return m;
}

double positionRmsError(const RunResult& run, const std::vector<Eigen::MatrixX3d>& reference) {
  return rmsTrajectoryError(run.positions, reference, static_cast<int>(reference.size()) - 1);
}

double rmsTrajectoryError(const std::vector<Eigen::MatrixX3d>& run, const std::vector<Eigen::MatrixX3d>& reference,
                          int last_frame) {
  if (last_frame < 1 || static_cast<int>(reference.size()) <= last_frame) return kNaN;
  if (static_cast<int>(run.size()) <= last_frame) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  size_t count = 0;
  for (int f = 1; f <= last_frame; ++f) {
    sum += (run[f] - reference[f]).rowwise().squaredNorm().sum();
    count += static_cast<size_t>(reference[f].rows());
  }
  const double rms = std::sqrt(sum / static_cast<double>(count));
  return std::isfinite(rms) ? rms : std::numeric_limits<double>::infinity();
}

double meanOverWindow(const std::vector<double>& values, double frame_step, double t0, double t1) {
  constexpr double kSlack = 1e-9;  // frame times are f * h in floating point
  if (values.empty() || frame_step * static_cast<double>(values.size() - 1) < t1 - kSlack) return kNaN;
  double sum = 0.0;
  int count = 0;
  for (size_t f = 0; f < values.size(); ++f) {
    const double t = frame_step * static_cast<double>(f);
    if (t < t0 - kSlack || t > t1 + kSlack) continue;
    sum += values[f];
    ++count;
  }
  return count > 0 ? sum / count : kNaN;
}

double median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid)));
}

double kineticFlicker(const std::vector<double>& kinetic, double floor) {
  std::vector<double> ratios;
  for (size_t i = 1; i + 1 < kinetic.size(); ++i) {
    const double a = kinetic[i] + floor, b = kinetic[i + 1] + floor;
    ratios.push_back(std::max(a, b) / std::min(a, b));
  }
  return median(std::move(ratios));
}

double swingPeriod(const std::vector<double>& series, double frame_step) {
  const int n = static_cast<int>(series.size());
  for (double v : series)
    if (!std::isfinite(v)) return kNaN;
  std::vector<double> minima;
  for (int i = kSwingWindow; i + kSwingWindow < n; ++i) {
    bool lowest = true;
    for (int j = i - kSwingWindow; j <= i + kSwingWindow && lowest; ++j)
      lowest = j == i || (j < i ? series[size_t(i)] < series[size_t(j)] : series[size_t(i)] <= series[size_t(j)]);
    if (!lowest) continue;
    // Vertex of the parabola through (i-1, i, i+1): offset in (-1/2, 1/2) for a strict minimum.
    const double a = series[size_t(i - 1)], b = series[size_t(i)], c = series[size_t(i + 1)];
    const double curvature = a - 2.0 * b + c;
    const double offset = curvature > 0.0 ? 0.5 * (a - c) / curvature : 0.0;
    minima.push_back((i + offset) * frame_step);
  }
  if (minima.size() < 3) return kNaN;
  return (minima.back() - minima.front()) / double(minima.size() - 1);
}

Eigen::Vector3d centreOfMass(const Eigen::MatrixX3d& x, const Eigen::VectorXd& masses) {
  return (x.transpose() * masses) / masses.sum();
}

Eigen::Vector3d angularMomentum(const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v, const Eigen::VectorXd& masses) {
  const Eigen::Vector3d c = centreOfMass(x, masses);
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (Eigen::Index p = 0; p < x.rows(); ++p) l += masses[p] * (x.row(p).transpose() - c).cross(v.row(p).transpose());
  return l;
}

TimeWindow kineticWindow(double horizon) {
  if (horizon >= 10.0 - 1e-9) return {5.0, 10.0};
  return {0.5 * horizon, horizon};
}

std::string combinedVerdict(const std::string& energy_verdict, double mean_k_ratio, double flicker) {
  if (energy_verdict == "exploded") return energy_verdict;
  std::string flags;
  auto add = [&](const char* flag) { flags += (flags.empty() ? "" : "+") + std::string(flag); };
  if (energy_verdict == "over-damped") add("over-damped");
  if (mean_k_ratio < kFrozenFraction) add("frozen");  // false for NaN: no reference, no flag
  if (flicker > kJitteryFlicker) add("jittery");
  return flags.empty() ? "stable" : flags;
}

std::vector<double> kineticSeries(const RunResult& run) {
  std::vector<double> k;
  k.reserve(run.samples.size());
  for (const FrameSample& f : run.samples) k.push_back(f.kinetic);
  return k;
}

MotionMetrics motionMetrics(const RunResult& run, int frames, const MotionReference& reference, const Metrics& energy) {
  MotionMetrics m;
  const double h = reference.frame_step;
  const auto framesOf = [h](double seconds) { return static_cast<int>(std::lround(seconds / h)); };
  if (!run.positions.empty()) {
    m.rms_short = rmsTrajectoryError(run.positions, reference.positions, framesOf(kShortRmsSeconds));
    m.rms_long = rmsTrajectoryError(run.positions, reference.positions, framesOf(kLongRmsSeconds));
  }
  m.k_window = kineticWindow(std::min(h * frames, reference.horizon()));
  m.mean_k_ref = meanOverWindow(reference.kinetic, h, m.k_window.from, m.k_window.to);
  // A run that blew up has no mean K over the window (NaN), and is "exploded" anyway.
  m.mean_k = meanOverWindow(kineticSeries(run), h, m.k_window.from, m.k_window.to);
  m.mean_k_ratio = m.mean_k / m.mean_k_ref;
  const double floor = kFlickerFloor * reference.available;
  m.flicker = kineticFlicker(kineticSeries(run), floor);
  m.flicker_ref = kineticFlicker(reference.kinetic, floor);
  m.verdict = combinedVerdict(energy.verdict, m.mean_k_ratio, m.flicker);
  return m;
}

}  // namespace study
