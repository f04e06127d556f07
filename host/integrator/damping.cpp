#include "integrator/damping.hpp"

#include "integrator/rigid_motion.hpp"

namespace stabint {

double applyMomentumPreservingDamping(const std::vector<Body>& bodies, const Eigen::VectorXd& masses,
                                      const Eigen::MatrixX3d& positions, Eigen::MatrixX3d& velocities) {
  double removed = 0.0;
  for (const Body& body : bodies) {
    if (body.damping <= 0.0 || body.particles.empty()) continue;
    const RigidMotion rigid = rigidMotion(masses, positions, velocities, body.particles);
    for (int j : body.particles) {
      const Eigen::Vector3d v = velocities.row(j).transpose();
      const Eigen::Vector3d damped = v + body.damping * (rigid.velocityAt(positions.row(j).transpose()) - v);
      removed += 0.5 * masses[j] * (v.squaredNorm() - damped.squaredNorm());
      velocities.row(j) = damped.transpose();
    }
  }
  return removed;
}

}  // namespace stabint
