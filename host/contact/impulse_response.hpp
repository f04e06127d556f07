#pragma once
// How the particles of a self-contact pair answer an impulse (docs/method.md, "Self-contact"): a
// cloth's particle alone, a tet body as a rigid body. Shared by the steps of SelfContact
// (host/contact/self_contact.cpp) before, within and after the solve.
#include "contact/self_contact.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <vector>

namespace stabint {

// Which of a pair's vertices take no share of an impulse along its normal (docs/method.md,
// "Self-contact": a stack is pushed apart upwards, never into what supports it): with `held`, a
// side that a collider holds against the impulse (ImpulseResponse::heldSide); with `up`, also the
// pair's lower side where its direction is within 60 degrees of the vertical. Neither, for
// friction.
struct Exemption {
  bool held = false;
  const Eigen::Vector3d* up = nullptr;
};

// How the particles answer a pair's impulse: a cloth's particle alone, through its own mass; a
// tet body as a rigid body, through its mass and its inertia about its centre at the reference
// positions x (a body's contact layer stopped or pushed back alone is carried on by the rest of
// the body within the step, and its elements invert: two tet bars dropped onto each other inverted
// 583 tets). A pair whose four vertices are all of one tet body (a body touching itself) answers
// per particle. A body with a pinned particle, like a pinned particle, takes no impulse.
class ImpulseResponse {
 public:
  // `held` (rows as x's; null: none): the outward normal of the collider each particle rests on,
  // zero for a particle no collider holds.
  ImpulseResponse(const std::vector<int>& solid_of, const std::vector<std::vector<int>>& solids, const PositionRows& x,
                  const Eigen::VectorXd& masses, const std::vector<int>& fixed, const Eigen::MatrixX3d* held = nullptr)
      : solid_of_(solid_of),
        solids_(solids),
        x_(x),
        masses_(masses),
        inverse_mass_(masses.cwiseInverse()),
        held_(held) {
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
      held_particles_.emplace_back();
      if (held)
        for (int i : body)
          if (!held->row(i).isZero()) held_particles_.back().push_back(i);
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
  // Whether vertex k of `e` takes no share of an impulse under rule `x` (Exemption).
  bool exempt(const ContactEvent& e, int k, Exemption x) const {
    const double w = e.weights[std::size_t(k)];
    if (x.held && held_ && (heldSide(e, k) || heldBody(e, k))) return true;
    if (!x.up) return false;
    const double vertical = e.normal.dot(*x.up);
    return std::abs(vertical) >= 0.5 && w * vertical < 0.0;
  }
  // Whether the side of `e` vertex k is on (its vertex or first edge, or its triangle or second
  // edge) is held: most of its weight is on vertices that a collider holds and that the impulse
  // would push into it (within 60 degrees of the collider's normal). A
  // side is held whole, since the impulse on what is left of it (an edge's far end at a small
  // weight) would have to move that part by the push over its weight.
  bool heldSide(const ContactEvent& e, int k) const {
    const int split = e.edge_edge ? 2 : 1;  // the first side's vertices are [0, split)
    const int from = k < split ? 0 : split, to = k < split ? split : 4;
    double held = 0.0, all = 0.0;
    for (int j = from; j < to; ++j) {
      const double w = e.weights[std::size_t(j)];
      const Eigen::Vector3d n = held_->row(e.vertices[std::size_t(j)]).transpose();
      all += std::abs(w);
      if (!n.isZero() && w * e.normal.dot(n) <= -0.5 * std::abs(w)) held += std::abs(w);
    }
    return held >= 0.5 * all && held > 0.0;
  }
  // Whether vertex k of `e` is of a tet body that a collider holds against the impulse
  // (pushedIntoCollider) while the pair's other side is free to take it instead. A body is rarely
  // held on the side a pair touches (a bar lying on the ground is touched on its top), and pushed
  // whole, a stiff bar lying on the ground went 11 J into the ground's contact under a bar resting
  // on it.
  bool heldBody(const ContactEvent& e, int k) const {
    if (!pushedIntoCollider(e, k)) return false;
    const int split = e.edge_edge ? 2 : 1;
    const int from = k < split ? split : 0, to = k < split ? 4 : split;  // the other side
    for (int j = from; j < to; ++j)
      if (heldSide(e, j) || pushedIntoCollider(e, j)) return false;
    return true;
  }
  // Moving rigidly under an impulse on `e`, one of the held particles of vertex k's body would go
  // into its collider by more than a quarter of the contact point's move.
  bool pushedIntoCollider(const ContactEvent& e, int k) const {
    const int b = bodyOf(e, k);
    if (b < 0 || held_particles_[std::size_t(b)].empty() || inverse_body_mass_[std::size_t(b)] == 0.0) return false;
    double a;
    Eigen::Vector3d t;
    share(e, b, e.normal, a, t);
    const Eigen::Vector3d linear = (a * inverse_body_mass_[std::size_t(b)]) * e.normal;
    const Eigen::Vector3d angular = inverse_inertia_[std::size_t(b)] * t;
    const double contact_move = a * a * inverse_body_mass_[std::size_t(b)] + t.dot(angular);
    for (int i : held_particles_[std::size_t(b)]) {
      const Eigen::Vector3d move = linear + angular.cross(rowOf(x_, i) - centres_[std::size_t(b)]);
      if (-move.dot(held_->row(i).transpose()) > 0.25 * std::abs(contact_move)) return true;
    }
    return false;
  }
  // A body's share of an impulse on `e` along `dir`: the sum of its vertices' weights and of their
  // moments about its centre.
  void share(const ContactEvent& e, int b, const Eigen::Vector3d& dir, double& weight, Eigen::Vector3d& moment,
             Exemption x = {}) const {
    weight = 0.0;
    moment.setZero();
    for (int k = 0; k < 4; ++k) {
      if (bodyOf(e, k) != b || exempt(e, k, x)) continue;
      const int i = e.vertices[std::size_t(k)];
      weight += e.weights[std::size_t(k)];
      moment += e.weights[std::size_t(k)] * (rowOf(x_, i) - centres_[std::size_t(b)]).cross(dir);
    }
  }
  // How far a unit impulse along `dir` (e's normal, or a tangent for friction) moves the pair's
  // relative motion along it: sum w_i^2 / m_i over the particles that answer alone, and
  // a^2 / M + t . I^-1 t over the bodies (a, t: share), less the vertices `x` exempts.
  double compliance(const ContactEvent& e, const Eigen::Vector3d& dir, Exemption x = {}) const {
    double c = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (exempt(e, k, x)) continue;
      const int b = bodyOf(e, k);
      const double w = e.weights[std::size_t(k)];
      if (b < 0) {
        c += w * w * inverse_mass_[e.vertices[std::size_t(k)]];
        continue;
      }
      if (firstOfBody(e, k, x)) {
        double a;
        Eigen::Vector3d t;
        share(e, b, dir, a, t, x);
        c += a * a * inverse_body_mass_[std::size_t(b)] + t.dot(inverse_inertia_[std::size_t(b)] * t);
      }
    }
    return c;
  }
  bool firstOfBody(const ContactEvent& e, int k, Exemption x = {}) const {
    for (int j = 0; j < k; ++j)
      if (!exempt(e, j, x) && bodyOf(e, j) == bodyOf(e, k)) return false;
    return true;
  }
  double inverseMass(int i) const { return inverse_mass_[i]; }
  const Eigen::Vector3d& centre(int b) const { return centres_[std::size_t(b)]; }
  double inverseBodyMass(int b) const { return inverse_body_mass_[std::size_t(b)]; }
  const Eigen::Matrix3d& inverseInertia(int b) const { return inverse_inertia_[std::size_t(b)]; }
  const std::vector<int>& solidOf() const { return solid_of_; }
  const std::vector<std::vector<int>>& solids() const { return solids_; }
  const PositionRows& reference() const { return x_; }
  // The rigid part of body b's motion in `rows` as the body answers an impulse: the linear and the
  // angular velocity about its centre at the reference positions (none for a pinned body).
  void rigidPart(int b, const Eigen::MatrixX3d& rows, Eigen::Vector3d& linear, Eigen::Vector3d& angular) const {
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero(), angular_momentum = Eigen::Vector3d::Zero();
    for (int i : solids_[std::size_t(b)]) {
      const Eigen::Vector3d mv = masses_[i] * rowOf(rows, i);
      momentum += mv;
      angular_momentum += (rowOf(x_, i) - centres_[std::size_t(b)]).cross(mv);
    }
    linear = inverse_body_mass_[std::size_t(b)] * momentum;
    angular = inverse_inertia_[std::size_t(b)] * angular_momentum;
  }

 private:
  const std::vector<int>& solid_of_;
  const std::vector<std::vector<int>>& solids_;
  PositionRows x_;
  const Eigen::VectorXd& masses_;
  Eigen::VectorXd inverse_mass_;
  const Eigen::MatrixX3d* held_;
  std::vector<Eigen::Vector3d> centres_;
  std::vector<std::vector<int>> held_particles_;  // per body, the particles a collider holds
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
  // The normal velocity of `e` as the vertices that answer an impulse under `x` see it: a body's
  // rigid velocity at its vertex, a particle's own. An impulse j along the normal changes the
  // kinetic energy by j times this plus j^2/2 times the compliance (velocities only).
  // `body_answers`: whether a tet body takes a share.
  double answeringAlong(const ContactEvent& e, Exemption x, bool& body_answers) {
    body_answers = false;
    if (rigid_linear_.empty()) {
      rigid_linear_.resize(linear_.size());
      rigid_angular_.resize(linear_.size());
      for (std::size_t b = 0; b < linear_.size(); ++b)
        response_.rigidPart(static_cast<int>(b), rows_, rigid_linear_[b], rigid_angular_[b]);
    }
    double s = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (response_.exempt(e, k, x)) continue;
      const int i = e.vertices[std::size_t(k)];
      const int b = response_.bodyOf(e, k);
      Eigen::Vector3d v = rowOf(rows_, i);
      if (b >= 0) {
        body_answers = true;
        const std::size_t c = std::size_t(b);
        v = rigid_linear_[c] + linear_[c] +
            (rigid_angular_[c] + angular_[c]).cross(rowOf(response_.reference(), i) - response_.centre(b));
      }
      s += e.weights[std::size_t(k)] * e.normal.dot(v);
    }
    return s;
  }
  // An impulse `j` along `dir` on the vertices `x` does not exempt; `moved` (when given)
  // flags the particles that answer alone.
  void push(const ContactEvent& e, double j, const Eigen::Vector3d& dir, std::vector<char>* moved = nullptr,
            Exemption x = {}) {
    for (int k = 0; k < 4; ++k) {
      if (response_.exempt(e, k, x)) continue;
      const int b = response_.bodyOf(e, k);
      const int i = e.vertices[std::size_t(k)];
      if (b < 0) {
        const double share = e.weights[std::size_t(k)] * response_.inverseMass(i);
        if (share == 0.0) continue;
        rows_.row(i) += (j * share) * dir.transpose();
        if (moved) (*moved)[std::size_t(i)] = 1;
        continue;
      }
      if (!response_.firstOfBody(e, k, x)) continue;
      double a;
      Eigen::Vector3d t;
      response_.share(e, b, dir, a, t, x);
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
    rigid_linear_.clear();  // the rows changed
    rigid_angular_.clear();
  }

 private:
  const ImpulseResponse& response_;
  Eigen::MatrixX3d& rows_;
  std::vector<Eigen::Vector3d> linear_, angular_;
  // The bodies' rigid motion in rows_ before the pending changes (answeringAlong; empty: not known).
  std::vector<Eigen::Vector3d> rigid_linear_, rigid_angular_;
};

}  // namespace stabint
