#include "cpu/cpu_backend.hpp"

#include "cpu/elements.hpp"
#include "scene/scene_data.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace stabint {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

class CpuBackend final : public Backend {
 public:
  CpuBackend(const SceneData& scene, int num_slots)
      : scene_(scene), slots_(num_slots, Eigen::MatrixX3d::Zero(scene.numParticles(), 3)) {
    const Eigen::MatrixX3d& rest = scene.scene().rest_positions;
    spring_rest_direction_.reserve(scene.springs().size());
    for (const Spring& s : scene.springs()) {
      Eigen::Vector3d dir = (rest.row(s.a) - rest.row(s.b)).transpose();
      const double len = dir.norm();
      spring_rest_direction_.push_back(len > 0.0 ? Eigen::Vector3d(dir / len)
                                                 : Eigen::Vector3d::UnitX());
    }
    tet_g_.reserve(scene.tets().size());
    for (const TetRest& tet : scene.tets()) tet_g_.push_back(elements::tetGradientOperator(tet.dm_inverse));
  }

  void write(int slot, const Eigen::MatrixX3d& host) override { slots_[slot] = host; }
  void read(int slot, Eigen::MatrixX3d& host) override { host = slots_[slot]; }
  void copy(int dst, int src) override { slots_[dst] = slots_[src]; }
  void combine(int dst, double a, int x, double b, int y) override {
    slots_[dst] = a * slots_[x] + b * slots_[y];
  }
  double massDot(int a, int b) override {
    return (slots_[a].cwiseProduct(slots_[b]).rowwise().sum().array() * scene_.masses().array()).sum();
  }

  PotentialEnergy potential(int slot, double t) override {
    const auto start = Clock::now();
    const Eigen::MatrixX3d& x = slots_[slot];
    PotentialEnergy e;
    for (const Spring& s : scene_.springs())
      e.strain += elements::springEnergy((x.row(s.a) - x.row(s.b)).transpose(), s.rest_length, s.stiffness);
    for (size_t i = 0; i < scene_.tets().size(); ++i) {
      const Eigen::Matrix3d F = tetDeformationGradient(x, i);
      e.strain += elements::tetEnergy(F, elements::nearestRotation(F), scene_.tets()[i].weight);
    }
    const Eigen::MatrixX3d& q = pinTargets(t);
    for (size_t i = 0; i < scene_.pins().size(); ++i) {
      const Pin& pin = scene_.pins()[i];
      e.pins += elements::pinEnergy(x.row(pin.vertex).transpose(), q.row(i).transpose(), pin.stiffness);
    }
    e.external = -externalForces(t).cwiseProduct(x).sum();
    times_.energy += secondsSince(start);
    return e;
  }

  void accelerations(int dst, int slot, double t) override {
    const auto start = Clock::now();
    // f = f_ext - sum_e w_e A_e^T (A_e x - p_e)
    Eigen::MatrixX3d f = externalForces(t);
    const Eigen::MatrixX3d& x = slots_[slot];
    forEachContribution(x, t, [&](int vertex, const Eigen::Vector3d& gradient_part) {
      f.row(vertex) -= gradient_part.transpose();
    }, /*gradient=*/true);
    slots_[dst] = f.array().colwise() / scene_.masses().array();
    times_.local += secondsSince(start);
  }

  void localStepRhs(int x_slot, int y_slot, double c, double t, Eigen::MatrixX3d& rhs,
                    PotentialEnergy* energy_at_x) override {
    if (energy_at_x) *energy_at_x = potential(x_slot, t);
    const auto start = Clock::now();
    rhs = (c * slots_[y_slot]).array().colwise() * scene_.masses().array();
    rhs += externalForces(t);
    forEachContribution(slots_[x_slot], t, [&](int vertex, const Eigen::Vector3d& projection_part) {
      rhs.row(vertex) += projection_part.transpose();
    }, /*gradient=*/false);
    times_.local += secondsSince(start);
  }

  std::string description() const override { return "CPU reference (double)"; }

 private:
  Eigen::Matrix3d tetDeformationGradient(const Eigen::MatrixX3d& x, size_t i) const {
    const TetRest& tet = scene_.tets()[i];
    Eigen::Matrix<double, 3, 4> X;
    for (int k = 0; k < 4; ++k) X.col(k) = x.row(tet.vertices[k]).transpose();
    return X * tet_g_[i];
  }

  /// Visits every per-vertex element contribution in the order of SceneData's CSR (springs,
  /// tets, pins): w A^T p (gradient = false) or w A^T (A x - p) (gradient = true).
  template <class Visit>
  void forEachContribution(const Eigen::MatrixX3d& x, double t, Visit&& visit, bool gradient) {
    const auto& springs = scene_.springs();
    for (size_t i = 0; i < springs.size(); ++i) {
      const Spring& s = springs[i];
      const Eigen::Vector3d d = (x.row(s.a) - x.row(s.b)).transpose();
      const Eigen::Vector3d p = elements::projectSpring(d, s.rest_length, spring_rest_direction_[i]);
      const Eigen::Vector3d part = s.stiffness * (gradient ? Eigen::Vector3d(d - p) : p);
      visit(s.a, part);
      visit(s.b, Eigen::Vector3d(-part));
    }
    for (size_t i = 0; i < scene_.tets().size(); ++i) {
      const TetRest& tet = scene_.tets()[i];
      const Eigen::Matrix3d F = tetDeformationGradient(x, i);
      const Eigen::Matrix3d R = elements::nearestRotation(F);
      const Eigen::Matrix<double, 3, 4> part =
          tet.weight * (gradient ? Eigen::Matrix3d(F - R) : R) * tet_g_[i].transpose();
      for (int k = 0; k < 4; ++k) visit(tet.vertices[k], Eigen::Vector3d(part.col(k)));
    }
    const Eigen::MatrixX3d& q = pinTargets(t);
    for (size_t i = 0; i < scene_.pins().size(); ++i) {
      const Pin& pin = scene_.pins()[i];
      const Eigen::Vector3d target = q.row(i).transpose();
      const Eigen::Vector3d xj = x.row(pin.vertex).transpose();
      visit(pin.vertex, Eigen::Vector3d(pin.stiffness * (gradient ? Eigen::Vector3d(xj - target) : target)));
    }
  }

  // Forcing at time t, cached because the driver asks for the same t many times per step.
  const Eigen::MatrixX3d& externalForces(double t) {
    if (!(t == external_time_)) {
      scene_.externalForces(t, external_);
      external_time_ = t;
    }
    return external_;
  }
  const Eigen::MatrixX3d& pinTargets(double t) {
    if (!(t == pin_time_)) {
      scene_.pinTargets(t, pin_targets_);
      pin_time_ = t;
    }
    return pin_targets_;
  }

  const SceneData& scene_;
  std::vector<Eigen::MatrixX3d> slots_;
  std::vector<Eigen::Vector3d> spring_rest_direction_;
  std::vector<Eigen::Matrix<double, 4, 3>> tet_g_;
  Eigen::MatrixX3d external_, pin_targets_;
  double external_time_ = std::numeric_limits<double>::quiet_NaN();
  double pin_time_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace

std::unique_ptr<Backend> makeCpuBackend(const SceneData& scene, int num_slots) {
  return std::make_unique<CpuBackend>(scene, num_slots);
}

}  // namespace stabint
