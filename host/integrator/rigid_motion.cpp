#include "integrator/rigid_motion.hpp"

#include <Eigen/Dense>

namespace stabint {

Eigen::Vector3d RigidMotion::angularVelocityFor(const Eigen::Vector3d& angular_momentum_about_center) const {
  return inertia.completeOrthogonalDecomposition().solve(angular_momentum_about_center);
}

RigidMotion rigidMotion(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& positions,
                        const Eigen::MatrixX3d& velocities, const std::vector<int>& particles) {
  const bool all = particles.empty();
  const int count = all ? static_cast<int>(positions.rows()) : static_cast<int>(particles.size());
  auto index = [&](int k) { return all ? k : particles[k]; };
  RigidMotion r;
  Eigen::Vector3d weighted_position = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) {
    const int j = index(k);
    r.mass += masses[j];
    weighted_position += masses[j] * positions.row(j).transpose();
    r.momentum += masses[j] * velocities.row(j).transpose();
  }
  if (r.mass <= 0.0) return r;
  r.center = weighted_position / r.mass;
  r.linear = r.momentum / r.mass;
  for (int k = 0; k < count; ++k) {
    const int j = index(k);
    const Eigen::Vector3d d = positions.row(j).transpose() - r.center;
    r.angular_momentum += masses[j] * d.cross(velocities.row(j).transpose());
    r.inertia += masses[j] * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  r.angular = r.angularVelocityFor(r.angular_momentum);
  r.kinetic = 0.5 * (r.mass * r.linear.squaredNorm() + r.angular.dot(r.angular_momentum));
  return r;
}

void setMomenta(const RigidMotion& current, const Eigen::Vector3d& momentum, const Eigen::Vector3d& angular_momentum,
                const Eigen::MatrixX3d& positions, Eigen::MatrixX3d& velocities, const std::vector<int>& particles) {
  if (current.mass <= 0.0) return;
  // A rigid field u + w x (x - c) adds M u to P and I_c w + c x M u to L about the origin.
  const Eigen::Vector3d u = (momentum - current.momentum) / current.mass;
  const Eigen::Vector3d w = current.angularVelocityFor(angular_momentum - current.angularMomentumAboutOrigin() -
                                                       current.center.cross(current.mass * u));
  const auto add = [&](Eigen::Index j) {
    velocities.row(j) += (u + w.cross(positions.row(j).transpose() - current.center)).transpose();
  };
  if (particles.empty())
    for (Eigen::Index j = 0; j < positions.rows(); ++j) add(j);
  for (int j : particles) add(j);
}

}  // namespace stabint
