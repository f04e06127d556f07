#include "integrator/damping.hpp"

#include <Eigen/Dense>

namespace stabint {

double applyMomentumPreservingDamping(const std::vector<Body>& bodies, const Eigen::VectorXd& masses,
                                      const Eigen::MatrixX3d& positions, Eigen::MatrixX3d& velocities) {
  double removed = 0.0;
  for (const Body& body : bodies) {
    if (body.damping <= 0.0 || body.particles.empty()) continue;
    double total_mass = 0.0;
    Eigen::Vector3d x_cm = Eigen::Vector3d::Zero(), v_cm = Eigen::Vector3d::Zero();
    for (int j : body.particles) {
      total_mass += masses[j];
      x_cm += masses[j] * positions.row(j).transpose();
      v_cm += masses[j] * velocities.row(j).transpose();
    }
    x_cm /= total_mass;
    v_cm /= total_mass;
    Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
    for (int j : body.particles) {
      const Eigen::Vector3d r = positions.row(j).transpose() - x_cm;
      angular_momentum += masses[j] * r.cross(velocities.row(j).transpose());
      inertia += masses[j] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    }
    // Collinear bodies (a chain) have a singular inertia tensor; the pseudo-inverse gives the
    // angular velocity about the axes that have inertia and none about the degenerate one.
    const Eigen::Vector3d omega = inertia.completeOrthogonalDecomposition().solve(angular_momentum);
    for (int j : body.particles) {
      const Eigen::Vector3d r = positions.row(j).transpose() - x_cm;
      const Eigen::Vector3d v = velocities.row(j).transpose();
      const Eigen::Vector3d damped = v + body.damping * (v_cm + omega.cross(r) - v);
      removed += 0.5 * masses[j] * (v.squaredNorm() - damped.squaredNorm());
      velocities.row(j) = damped.transpose();
    }
  }
  return removed;
}

}  // namespace stabint
