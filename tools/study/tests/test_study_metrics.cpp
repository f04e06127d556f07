// The study's motion metrics on small synthetic series whose answers are known in closed form
// (not produced by the code under test), and the reference cache's round trip.
#include "cache.hpp"
#include "study.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

namespace study {
namespace {

std::vector<Eigen::MatrixX3d> constantFrames(int frames, const Eigen::MatrixX3d& x) {
  return std::vector<Eigen::MatrixX3d>(static_cast<size_t>(frames), x);
}

TEST(RmsTrajectoryError, ConstantOffsetGivesItsLength) {
  Eigen::MatrixX3d x = Eigen::MatrixX3d::Random(5, 3);
  const auto reference = constantFrames(11, x);
  auto run = reference;
  for (size_t f = 1; f < run.size(); ++f) run[f].rowwise() += Eigen::RowVector3d(0.3, 0.4, 0.0);  // |d| = 0.5
  EXPECT_NEAR(rmsTrajectoryError(run, reference, 10), 0.5, 1e-15);
  EXPECT_NEAR(rmsTrajectoryError(run, reference, 3), 0.5, 1e-15);
}

TEST(RmsTrajectoryError, OnlyFramesUpToTheLimitCount) {
  const auto reference = constantFrames(11, Eigen::MatrixX3d::Zero(2, 3));
  auto run = reference;
  // Frames 1..4 off by 1 m in x, frames 5.. by 100 m: over 1..4 the RMS is 1; over 1..8 it is
  // sqrt((4 * 1 + 4 * 100^2) / 8).
  for (size_t f = 1; f < run.size(); ++f) run[f].col(0).setConstant(f <= 4 ? 1.0 : 100.0);
  EXPECT_DOUBLE_EQ(rmsTrajectoryError(run, reference, 4), 1.0);
  EXPECT_NEAR(rmsTrajectoryError(run, reference, 8), std::sqrt((4.0 + 4.0 * 1e4) / 8.0), 1e-12);
}

TEST(RmsTrajectoryError, ShortRunIsInfiniteAndShortReferenceIsNaN) {
  const auto reference = constantFrames(11, Eigen::MatrixX3d::Zero(2, 3));
  const auto short_run = constantFrames(5, Eigen::MatrixX3d::Zero(2, 3));  // blew up at frame 5
  EXPECT_TRUE(std::isinf(rmsTrajectoryError(short_run, reference, 10)));
  EXPECT_DOUBLE_EQ(rmsTrajectoryError(short_run, reference, 4), 0.0);
  EXPECT_TRUE(std::isnan(rmsTrajectoryError(reference, short_run, 10)));
  auto nonfinite = reference;
  nonfinite[3](1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isinf(rmsTrajectoryError(nonfinite, reference, 10)));
}

TEST(MeanOverWindow, LinearSeriesAveragesToTheWindowMidpoint) {
  // values[f] = t_f = f h with h = 1/30 over 10 s: the mean over the frames in [5, 10] of an
  // evenly sampled linear function is its value at the window's midpoint, 7.5.
  const double h = 1.0 / 30.0;
  std::vector<double> t;
  for (int f = 0; f <= 300; ++f) t.push_back(f * h);
  EXPECT_NEAR(meanOverWindow(t, h, 5.0, 10.0), 7.5, 1e-12);
  EXPECT_NEAR(meanOverWindow(t, h, 0.0, 1.0), 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(meanOverWindow(t, h, 5.0, 10.5)));  // the series ends at 10 s
}

TEST(KineticFlicker, SmoothAlternatingAndGeometricSeries) {
  // Frame 0 (released from rest, K = 0) is excluded by definition.
  EXPECT_DOUBLE_EQ(kineticFlicker({0.0, 2.0, 2.0, 2.0, 2.0}, 0.0), 1.0);
  // K flips between 1 and 6 every frame: every consecutive ratio is 6.
  EXPECT_DOUBLE_EQ(kineticFlicker({0.0, 1.0, 6.0, 1.0, 6.0, 1.0}, 0.0), 6.0);
  // K = 3^f: every ratio is 3, decreasing or increasing alike.
  EXPECT_NEAR(kineticFlicker({0.0, 3.0, 9.0, 27.0, 81.0}, 0.0), 3.0, 1e-15);
  EXPECT_NEAR(kineticFlicker({0.0, 81.0, 27.0, 9.0, 3.0}, 0.0), 3.0, 1e-15);
  // Two frames at rest count as 1 thanks to the floor, not 0/0.
  EXPECT_DOUBLE_EQ(kineticFlicker({0.0, 0.0, 0.0, 0.0}, 1e-12), 1.0);
  EXPECT_TRUE(std::isnan(kineticFlicker({0.0, 1.0}, 0.0)));
}

// A cosine of period 0.867 s sampled at 30 frames per second for 10 s (the main job's cloth
// swings at that period): the minima fall between frames, and the parabola places each to well
// under a frame (1/30 s), so the mean spacing is within 0.2 % of the period. Frame-to-frame jitter
// of 1 % of the swing makes no extra minima. Two minima give no period.
TEST(SwingPeriod, CosineBetweenFramesAndJitter) {
  const double period = 0.867, h = 1.0 / 30.0;
  std::vector<double> y, jittery;
  for (int f = 0; f <= 300; ++f) {
    y.push_back(-std::cos(2.0 * M_PI * f * h / period));
    jittery.push_back(y.back() + (f % 2 ? 0.01 : -0.01));
  }
  EXPECT_NEAR(swingPeriod(y, h), period, 2e-3 * period);
  EXPECT_NEAR(swingPeriod(jittery, h), period, 1e-2 * period);
  EXPECT_TRUE(std::isnan(swingPeriod(std::vector<double>(y.begin(), y.begin() + 40), h)));
  y[100] = kNaN;
  EXPECT_TRUE(std::isnan(swingPeriod(y, h)));
}

TEST(Median, OddAndEvenCounts) {
  EXPECT_DOUBLE_EQ(median({5.0, 1.0, 3.0}), 3.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_TRUE(std::isnan(median({})));
}

TEST(CentreOfMass, MassWeighted) {
  Eigen::MatrixX3d x(2, 3);
  x << 0.0, 0.0, 0.0, 4.0, 8.0, -4.0;
  const Eigen::Vector2d m(1.0, 3.0);
  EXPECT_TRUE(centreOfMass(x, m).isApprox(Eigen::Vector3d(3.0, 6.0, -3.0), 1e-15));
}

TEST(AngularMomentum, RigidRotationAndTranslationInvariance) {
  // Two masses m at +-r on x rotating about z at omega: L = 2 m r^2 omega e_z about the centre.
  const double m = 0.7, r = 0.4, omega = 6.0;
  Eigen::MatrixX3d x(2, 3), v(2, 3);
  x << r, 0.0, 0.0, -r, 0.0, 0.0;
  const Eigen::Vector3d w(0.0, 0.0, omega);
  for (int p = 0; p < 2; ++p) v.row(p) = w.cross(x.row(p).transpose()).transpose();
  const Eigen::Vector2d masses(m, m);
  const Eigen::Vector3d expected(0.0, 0.0, 2.0 * m * r * r * omega);
  EXPECT_TRUE(angularMomentum(x, v, masses).isApprox(expected, 1e-14));
  // About the centre of mass, a shift of the body and a common velocity change nothing.
  x.rowwise() += Eigen::RowVector3d(5.0, -2.0, 1.0);
  v.rowwise() += Eigen::RowVector3d(1.0, 2.0, 3.0);
  EXPECT_TRUE(angularMomentum(x, v, masses).isApprox(expected, 1e-13));
}

TEST(KineticWindow, FiveToTenSecondsElseTheSecondHalf) {
  EXPECT_DOUBLE_EQ(kineticWindow(10.0).from, 5.0);
  EXPECT_DOUBLE_EQ(kineticWindow(20.0).to, 10.0);
  EXPECT_DOUBLE_EQ(kineticWindow(2.0).from, 1.0);
  EXPECT_DOUBLE_EQ(kineticWindow(2.0).to, 2.0);
}

TEST(CombinedVerdict, FlagsAndPrecedence) {
  EXPECT_EQ(combinedVerdict("exploded", 0.0, 100.0), "exploded");
  EXPECT_EQ(combinedVerdict("stable", 1.0, 1.1), "stable");
  EXPECT_EQ(combinedVerdict("stable", 0.29, 1.1), "frozen");
  EXPECT_EQ(combinedVerdict("stable", 0.31, 1.6), "jittery");
  EXPECT_EQ(combinedVerdict("stable", 0.1, 6.0), "frozen+jittery");
  EXPECT_EQ(combinedVerdict("over-damped", 0.01, 1.0), "over-damped+frozen");
  EXPECT_EQ(combinedVerdict("stable", kNaN, kNaN), "stable");  // no reference: no motion flag
}

TEST(Cache, RoundTripAndDescriptionCheck) {
  const std::string dir = (std::filesystem::temp_directory_path() / "stabint_study_cache_test").string();
  std::filesystem::remove_all(dir);
  const std::string path = cachePath(dir, "scene", "description A");
  std::vector<Eigen::MatrixX3d> frames = {Eigen::MatrixX3d::Random(4, 3), Eigen::MatrixX3d::Random(4, 3)};
  std::vector<double> payload = {2.0, 4.0};
  appendFrames(payload, frames);
  writeCache(path, "description A", payload);

  std::vector<double> back;
  ASSERT_TRUE(readCache(path, "description A", back));
  PayloadReader in(back);
  double count = 0, particles = 0;
  ASSERT_TRUE(in.next(count) && in.next(particles));
  std::vector<Eigen::MatrixX3d> frames_back;
  ASSERT_TRUE(readFrames(in, static_cast<int>(count), static_cast<int>(particles), frames_back));
  EXPECT_TRUE(in.done());
  EXPECT_EQ(frames_back[1], frames[1]);             // bit for bit
  EXPECT_FALSE(readFrames(in, 1, 4, frames_back));  // nothing left: a short file reads as invalid

  EXPECT_FALSE(readCache(path, "description B", back));  // same file name, other settings
  EXPECT_NE(cachePath(dir, "scene", "description B"), path);
  std::filesystem::remove_all(dir);
}

// A cached reference is keyed by the scene's colliders too: no colliders leaves the key as it
// was (the params alone), and a change of any one collider field changes it.
TEST(Cache, DescriptionCoversEveryColliderField) {
  StudyScene s;
  s.params = "bar";
  EXPECT_EQ(cacheDescription(s), "bar");
  stabint::Collider c;
  c.shape = stabint::ColliderShape::Capsule;
  c.end = Eigen::Vector3d(1.0, 0.0, 0.0);
  c.radius = 0.1;
  s.scene.colliders.push_back(c);
  const std::string base = cacheDescription(s);
  EXPECT_NE(base, "bar");
  const std::vector<void (*)(stabint::Collider&)> changes = {
      [](stabint::Collider& k) { k.shape = stabint::ColliderShape::Sphere; },
      [](stabint::Collider& k) { k.center.y() += 1e-9; },
      [](stabint::Collider& k) { k.normal.x() = 0.5; },
      [](stabint::Collider& k) { k.half_extents.z() = 0.5; },
      [](stabint::Collider& k) { k.end.z() = 1e-12; },
      [](stabint::Collider& k) { k.radius = 0.1 + 1e-15; },
      [](stabint::Collider& k) { k.velocity.x() = 1.0; },
      [](stabint::Collider& k) { k.friction = 0.5; },
      [](stabint::Collider& k) { k.stiffness = 3e5; }};
  for (size_t i = 0; i < changes.size(); ++i) {
    StudyScene t = s;
    changes[i](t.scene.colliders[0]);
    EXPECT_NE(cacheDescription(t), base) << "change " << i;
  }
}

TEST(EnergyMetrics, ExplodedAtIsTheFirstFrameBeyondTheThreshold) {
  // H_0 = 1, E_avail = 1: H exceeds H_0 + 10 E_avail first at t = 0.3 s.
  RunResult run;
  const double energies[] = {1.0, 2.0, 5.0, 12.0, 3.0};
  for (int f = 0; f < 5; ++f) {
    FrameSample s;
    s.time = 0.1 * f;
    s.kinetic = energies[f];
    s.target = 1.0;
    run.samples.push_back(s);
  }
  const Metrics m = energyMetrics(run, 1.0);
  EXPECT_EQ(m.verdict, "exploded");
  EXPECT_DOUBLE_EQ(m.exploded_at, 0.3);
  run.samples[3].kinetic = 4.0;  // never beyond: +inf
  EXPECT_TRUE(std::isinf(energyMetrics(run, 1.0).exploded_at));
}

}  // namespace
// The drop's skin: on the tet bar (8 x 2 x 2 cells) the boundary is closed and consistently
// wound (every directed edge once, its reverse once) and faces outward (the divergence theorem:
// sum over faces of centroid . area normal / 3 is the volume, which the tets give directly).
TEST(TetBoundary, TetBarSkinIsClosedOutwardAndHasTheBarsVolume) {
  const stabint::Scene bar = stabint::makeTetBar(stabint::TetBarParams{});
  const std::vector<std::array<int, 3>> skin = stabint::tetSurface(bar.tets);
  ASSERT_FALSE(skin.empty());
  std::map<std::pair<int, int>, int> directed;
  double surface_volume = 0.0;
  const Eigen::MatrixX3d& x = bar.rest_positions;
  for (const auto& f : skin) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
    const Eigen::Vector3d a = x.row(f[0]), b = x.row(f[1]), c = x.row(f[2]);
    surface_volume += a.dot(b.cross(c)) / 6.0;
  }
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u);
  }
  double tet_volume = 0.0;
  for (const stabint::Tet& t : bar.tets) {
    const Eigen::Vector3d p0 = x.row(t.vertices[0]);
    tet_volume +=
        (Eigen::Vector3d(x.row(t.vertices[1])) - p0)
            .dot((Eigen::Vector3d(x.row(t.vertices[2])) - p0).cross(Eigen::Vector3d(x.row(t.vertices[3])) - p0)) /
        6.0;
  }
  EXPECT_GT(tet_volume, 0.0);
  EXPECT_NEAR(surface_volume, tet_volume, 1e-12 * tet_volume);
}

}  // namespace study
