#pragma once
// Rigid part of a velocity field: the mass-weighted projection of v onto rigid motions
// v_rigid(x) = linear + angular x (x - center). It carries all of the linear and angular
// momentum, and v - v_rigid carries none, so scaling v - v_rigid keeps both momenta. Used by the
// momentum-preserving damping and by the blend's momentum and energy corrections.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace stabint {

struct RigidMotion {
  double mass = 0.0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();            // centre of mass
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();          // P = sum m v
  Eigen::Vector3d angular_momentum = Eigen::Vector3d::Zero();  // L about the centre of mass
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();           // about the centre of mass
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();            // P / M
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();           // I^-1 L (pseudo-inverse)
  double kinetic = 0.0;                                        // 1/2 (M |linear|^2 + angular . L)

  Eigen::Vector3d velocityAt(const Eigen::Vector3d& x) const { return linear + angular.cross(x - center); }
  /// L about the origin, so that momenta measured at different positions compare.
  Eigen::Vector3d angularMomentumAboutOrigin() const { return angular_momentum + center.cross(momentum); }
  /// Angular velocity about the centre of mass for an angular momentum (pseudo-inverse of the
  /// inertia: a collinear body, such as a chain, has none about its own axis).
  Eigen::Vector3d angularVelocityFor(const Eigen::Vector3d& angular_momentum_about_center) const;
};

/// Rigid part of the velocities of `particles` (every particle when empty).
RigidMotion rigidMotion(const Eigen::VectorXd& masses, const Eigen::MatrixX3d& positions,
                        const Eigen::MatrixX3d& velocities, const std::vector<int>& particles = {});

/// Adds, to the velocities of `particles` (every particle when empty), the rigid velocity field that
/// changes their momenta from `current` to the linear momentum `momentum` and the angular momentum
/// about the origin `angular_momentum`. `current` must be rigidMotion() of the same positions,
/// velocities and particles.
void setMomenta(const RigidMotion& current, const Eigen::Vector3d& momentum, const Eigen::Vector3d& angular_momentum,
                const Eigen::MatrixX3d& positions, Eigen::MatrixX3d& velocities,
                const std::vector<int>& particles = {});

}  // namespace stabint
