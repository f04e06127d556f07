#pragma once
// How the particles of a self-contact pair answer an impulse (docs/method.md, "Self-contact"): a
// cloth's particle alone, a tet body as a rigid body. Shared by the steps of SelfContact
// (host/contact/self_contact.cpp) before, within and after the solve.
#include "contact/self_contact.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace stabint {

// How the particles answer a pair's impulse: a cloth's particle alone, through its own mass; a
// tet body as a rigid body, through its mass and its inertia about its centre at the reference
// positions x (a body's contact layer stopped or pushed back alone is carried on by the rest of
// the body within the step, and its elements invert: two tet bars dropped onto each other inverted
// 583 tets). A pair whose four vertices are all of one tet body (a body touching itself) answers
// per particle. A body with a pinned particle, like a pinned particle, takes no impulse.
class ImpulseResponse {
 public:
  ImpulseResponse(const std::vector<int>& solid_of, const std::vector<std::vector<int>>& solids, const PositionRows& x,
                  const Eigen::VectorXd& masses, const std::vector<int>& fixed)
      : solid_of_(solid_of), solids_(solids), x_(x), inverse_mass_(masses.cwiseInverse()) {
    for (int f : fixed) inverse_mass_[f] = 0.0;
    for (const std::vector<int>& body : solids) {
      double mass = 0.0;
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      bool pinned = false;
      for (int i : body) {
        mass += masses[i];
        centre += masses[i] * rowOf(x, i);
        pinned = pinned || inverse_mass_[i] == 0.0;
      }
      centre /= mass;
      Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
      for (int i : body) {
        const Eigen::Vector3d r = rowOf(x, i) - centre;
        inertia += masses[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
      }
      centres_.push_back(centre);
      inverse_body_mass_.push_back(pinned ? 0.0 : 1.0 / mass);
      inverse_inertia_.push_back(pinned ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(inertia.inverse()));
    }
  }

  // The body vertex i of `e` answers through (-1: alone).
  int bodyOf(const ContactEvent& e, int k) const {
    const int b = solid_of_[std::size_t(e.vertices[std::size_t(k)])];
    if (b < 0) return -1;
    for (int v : e.vertices)
      if (solid_of_[std::size_t(v)] != b) return b;
    return -1;  // the body touches itself
  }
  // Whether vertex k of `e` takes no share of a position push with `up` set: it is on the pair's
  // lower side, and the pair's direction within 60 degrees of the vertical (docs/method.md,
  // "Self-contact": a stack is pushed apart upwards, never into what supports it).
  static bool below(const ContactEvent& e, int k, const Eigen::Vector3d* up) {
    if (!up) return false;
    const double vertical = e.normal.dot(*up);
    return std::abs(vertical) >= 0.5 && e.weights[std::size_t(k)] * vertical < 0.0;
  }
  // A body's share of an impulse on `e` along `dir`: the sum of its vertices' weights and of their
  // moments about its centre.
  void share(const ContactEvent& e, int b, const Eigen::Vector3d& dir, double& weight, Eigen::Vector3d& moment,
             const Eigen::Vector3d* up = nullptr) const {
    weight = 0.0;
    moment.setZero();
    for (int k = 0; k < 4; ++k) {
      if (bodyOf(e, k) != b || below(e, k, up)) continue;
      const int i = e.vertices[std::size_t(k)];
      weight += e.weights[std::size_t(k)];
      moment += e.weights[std::size_t(k)] * (rowOf(x_, i) - centres_[std::size_t(b)]).cross(dir);
    }
  }
  // How far a unit impulse along `dir` (e's normal, or a tangent for friction) moves the pair's
  // relative motion along it: sum w_i^2 / m_i over the particles that answer alone, and
  // a^2 / M + t . I^-1 t over the bodies (a, t: share). With `up`, the pair's lower side takes no
  // share (below).
  double compliance(const ContactEvent& e, const Eigen::Vector3d& dir, const Eigen::Vector3d* up = nullptr) const {
    double c = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (below(e, k, up)) continue;
      const int b = bodyOf(e, k);
      const double w = e.weights[std::size_t(k)];
      if (b < 0) {
        c += w * w * inverse_mass_[e.vertices[std::size_t(k)]];
        continue;
      }
      if (firstOfBody(e, k, up)) {
        double a;
        Eigen::Vector3d t;
        share(e, b, dir, a, t, up);
        c += a * a * inverse_body_mass_[std::size_t(b)] + t.dot(inverse_inertia_[std::size_t(b)] * t);
      }
    }
    return c;
  }
  bool firstOfBody(const ContactEvent& e, int k, const Eigen::Vector3d* up = nullptr) const {
    for (int j = 0; j < k; ++j)
      if (!below(e, j, up) && bodyOf(e, j) == bodyOf(e, k)) return false;
    return true;
  }
  double inverseMass(int i) const { return inverse_mass_[i]; }
  const Eigen::Vector3d& centre(int b) const { return centres_[std::size_t(b)]; }
  double inverseBodyMass(int b) const { return inverse_body_mass_[std::size_t(b)]; }
  const Eigen::Matrix3d& inverseInertia(int b) const { return inverse_inertia_[std::size_t(b)]; }
  const std::vector<int>& solidOf() const { return solid_of_; }
  const std::vector<std::vector<int>>& solids() const { return solids_; }
  const PositionRows& reference() const { return x_; }

 private:
  const std::vector<int>& solid_of_;
  const std::vector<std::vector<int>>& solids_;
  PositionRows x_;
  Eigen::VectorXd inverse_mass_;
  std::vector<Eigen::Vector3d> centres_;
  std::vector<double> inverse_body_mass_;
  std::vector<Eigen::Matrix3d> inverse_inertia_;
};

// Rows (velocities or positions) that impulses change through a ImpulseResponse: a particle's row at
// once, a body's as a pending linear and angular change, applied to all its rows by settle().
class ImpulseMotion {
 public:
  ImpulseMotion(const ImpulseResponse& response, Eigen::MatrixX3d& rows)
      : response_(response),
        rows_(rows),
        linear_(response.solids().size(), Eigen::Vector3d::Zero()),
        angular_(response.solids().size(), Eigen::Vector3d::Zero()) {}

  Eigen::Vector3d at(int i) const {
    const int b = response_.solidOf()[std::size_t(i)];
    Eigen::Vector3d r = rowOf(rows_, i);
    if (b >= 0)
      r += linear_[std::size_t(b)] +
           angular_[std::size_t(b)].cross(rowOf(response_.reference(), i) - response_.centre(b));
    return r;
  }
  // The pair's relative row, sum w_i row_i.
  Eigen::Vector3d relative(const ContactEvent& e) const {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) d += e.weights[std::size_t(k)] * at(e.vertices[std::size_t(k)]);
    return d;
  }
  // The separation of `e` along its normal (n . sum w_i row_i).
  double along(const ContactEvent& e) const { return e.normal.dot(relative(e)); }
  // An impulse `j` along `dir` (with `up`, on the pair's upper side alone); `moved` (when given)
  // flags the particles that answer alone.
  void push(const ContactEvent& e, double j, const Eigen::Vector3d& dir, std::vector<char>* moved = nullptr,
            const Eigen::Vector3d* up = nullptr) {
    for (int k = 0; k < 4; ++k) {
      if (ImpulseResponse::below(e, k, up)) continue;
      const int b = response_.bodyOf(e, k);
      const int i = e.vertices[std::size_t(k)];
      if (b < 0) {
        const double share = e.weights[std::size_t(k)] * response_.inverseMass(i);
        if (share == 0.0) continue;
        rows_.row(i) += (j * share) * dir.transpose();
        if (moved) (*moved)[std::size_t(i)] = 1;
        continue;
      }
      if (!response_.firstOfBody(e, k, up)) continue;
      double a;
      Eigen::Vector3d t;
      response_.share(e, b, dir, a, t, up);
      linear_[std::size_t(b)] += (j * a * response_.inverseBodyMass(b)) * dir;
      angular_[std::size_t(b)] += j * (response_.inverseInertia(b) * t);
    }
  }
  // Applies the bodies' pending changes to their rows; `moved` flags the rows of bodies that changed.
  void settle(std::vector<char>* moved = nullptr) {
    for (std::size_t b = 0; b < linear_.size(); ++b) {
      if (linear_[b].isZero() && angular_[b].isZero()) continue;
      for (int i : response_.solids()[b]) {
        rows_.row(i) = at(i).transpose();
        if (moved) (*moved)[std::size_t(i)] = 1;
      }
      linear_[b].setZero();
      angular_[b].setZero();
    }
  }

 private:
  const ImpulseResponse& response_;
  Eigen::MatrixX3d& rows_;
  std::vector<Eigen::Vector3d> linear_, angular_;
};

}  // namespace stabint
