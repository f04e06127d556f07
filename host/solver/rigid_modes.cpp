// The rigid motions of each scene segment as a coarse space in L-BFGS's initial inverse Hessian
// (docs/method.md, "Rigid motions in the initial Hessian"). The Projective-Dynamics matrix
// K_c = c M + L resists a rotation as it resists a stretch: its springs' and tets' A^T A do not
// know that a rotated element keeps its energy. So K_c^-1 g takes a rotation (a pinned cloth's
// swing, a falling cloth turning about its pins) in tiny steps, and the curvature pairs learn it
// only over many iterations. Every element but the one-particle ones (pins, contacts) keeps its
// energy under a rigid motion, so on the six rigid motions Z of a body (three translations,
// three rotations about its mass centre at the warm start) the objective's Hessian is about
// A = c M + W, W the one-particle elements' weights. The two-level (balancing) inverse
//   H0 q = Z S^+ Z^T q + (I - Z S^+ Z^T A) K_c^-1 (I - A Z S^+ Z^T) q,   S = Z^T A Z,
// is symmetric and positive definite; it takes the rigid part of a step from S and the rest from
// K_c. S^+ drops the directions that move nothing (a chain's rotation about its own axis) and
// those of negative curvature. Each body of a segment (what its elements connect) has its own six:
// the bodies of one scene move apart, and one coarse space over a cloth and a bar spinning beside
// it turned the cloth with the bar (0.16 m RMS from the converged run after 30 steps, 0.03 m
// apart, with BE). Measured: BE on the peer cloth is 0.051 m (RMS) from the converged
// run after 30 frames at 10 iterations, against 0.93 m with K_c^-1 alone (docs/method.md).
#include "elements/element_type.hpp"
#include "scene/connected_bodies.hpp"
#include "scene/scene_data.hpp"
#include "scene/scene_view.hpp"
#include "common/simd.hpp"
#include "solver/accelerations.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace stabint {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// An eigenvalue of S below this fraction of the largest is a motion that moves (almost) nothing.
constexpr double kNullMotion = 1e-12;

// [project rule] A coarse direction whose curvature the tension brings below this share of its
// inertia's takes a step shrunk smoothly to nothing at zero curvature: the tension is the
// Hessian's at the warm start, and where it nearly cancels the inertia the step 1/lambda
// overshoots by the estimate's error. A cloth snapping back from a stretch (clothOnCloth's upper
// cloth) grew a rotation of its corner sevenfold per iteration, with the sign flipping, from a
// rounding to 1e-9 m within one step; at a half the step is at most twice the inertia's.
constexpr double kCurvatureFloor = 0.5;

// Z^T (w v) over `count` rows of three columns (Weighted = false: w_i = 1): the sums of w_i v_i
// and of arm_i x w_i v_i, in kRigidLanes lanes (row j of the segment in lane j % kRigidLanes), the
// lanes then summed in a fixed tree (laneSum): the same bits on any machine, and a batch's scene
// gets its own Simulator's sums (the lanes count from the segment's first row). In row order the
// six sums were one chain of additions each, which the two-level inverse waited on twice per
// iteration.
constexpr int kRigidLanes = 8;

template <bool Weighted>
STABINT_TARGET_CLONES_TEMPLATE void rigidSums(int count, const double* __restrict vx, const double* __restrict vy,
                                              const double* __restrict vz, const double* __restrict ax,
                                              const double* __restrict ay, const double* __restrict az,
                                              const double* __restrict w, double* out) {
  constexpr int L = kRigidLanes;
  double f0[L] = {}, f1[L] = {}, f2[L] = {}, t0[L] = {}, t1[L] = {}, t2[L] = {};
  auto row = [&](int i, int l) {
    double v0 = vx[i], v1 = vy[i], v2 = vz[i];
    if constexpr (Weighted) {
      v0 = w[i] * v0;
      v1 = w[i] * v1;
      v2 = w[i] * v2;
    }
    f0[l] += v0;
    f1[l] += v1;
    f2[l] += v2;
    t0[l] += ay[i] * v2 - az[i] * v1;
    t1[l] += az[i] * v0 - ax[i] * v2;
    t2[l] += ax[i] * v1 - ay[i] * v0;
  };
  int i = 0;
  for (; i + L <= count; i += L) STABINT_LANES for (int l = 0; l < L; ++l) row(i + l, l);
  for (int l = 0; i + l < count; ++l) row(i + l, l);
  const double* sums[6] = {f0, f1, f2, t0, t1, t2};
  for (int k = 0; k < 6; ++k) out[k] = laneSum<L>(sums[k]);
}

// rigidSums over rows [first, first + count) of the n by 3 (column-major) v and arms.
template <bool Weighted>
Vector6d rigidComponents(const Eigen::MatrixX3d& arms, const Eigen::MatrixX3d& v, int first, int count,
                         const double* w) {
  const Eigen::Index n = v.rows();
  const double* p = v.data() + first;
  const double* a = arms.data() + first;
  Vector6d out;
  rigidSums<Weighted>(count, p, p + n, p + 2 * n, a, a + n, a + 2 * n, w == nullptr ? nullptr : w + first, out.data());
  return out;
}

// The rigid motion u (translation, rotation) at particle i, u_t + u_r x arm_i, subtracted with
// weight w_i (Weighted) or added, over `count` rows of three columns, in SIMD lanes: Eigen's
// arithmetic of u.head<3>() + u.tail<3>().cross(arm_i), row by row.
template <bool Weighted>
STABINT_TARGET_CLONES_TEMPLATE void moveByRigidMotion(int count, const double* u, const double* ax, const double* ay,
                                                      const double* az, const double* w, double* x, double* y,
                                                      double* z) {
  const double u0 = u[0], u1 = u[1], u2 = u[2], u3 = u[3], u4 = u[4], u5 = u[5];
  STABINT_LANES for (int i = 0; i < count; ++i) {
    const double m0 = u0 + (u4 * az[i] - u5 * ay[i]);
    const double m1 = u1 + (u5 * ax[i] - u3 * az[i]);
    const double m2 = u2 + (u3 * ay[i] - u4 * ax[i]);
    if constexpr (Weighted) {
      x[i] = x[i] - w[i] * m0;
      y[i] = y[i] - w[i] * m1;
      z[i] = z[i] - w[i] * m2;
    } else {
      x[i] = x[i] + m0;
      y[i] = y[i] + m1;
      z[i] = z[i] + m2;
    }
  }
}

// moveByRigidMotion on rows [first, first + count) of the n by 3 matrix x.
template <bool Weighted>
void moveRows(const Vector6d& u, const Eigen::MatrixX3d& arms, const double* w, int first, int count,
              Eigen::MatrixX3d& x) {
  const Eigen::Index n = x.rows();
  const double* a = arms.data() + first;
  double* p = x.data() + first;
  moveByRigidMotion<Weighted>(count, u.data(), a, a + n, a + 2 * n, w == nullptr ? nullptr : w + first, p, p + n,
                              p + 2 * n);
}

// S = Z^T A Z's sums over rows [first, first + count), with the arms (x_i - centre) written into
// `arms`: the weight sum (translations), the weighted first moment of the arms (translation x
// rotation), the weighted inertia tensor sum a_i (|arm_i|^2 I - arm_i arm_i^T) (rotations) and the
// elastic tension sum (g_i.arm_i I - arm_i g_i^T) along the rotations. Eigen's arithmetic of one row
// at a time (Matrix3d expressions), in row order, on scalar sums in two loops: in one loop the 19
// sums did not fit the registers, and every addition waited on a store to the stack.
struct CoarseSums {
  double weight = 0.0;
  Eigen::Vector3d first_moment;
  Eigen::Matrix3d inertia, tension;
};

CoarseSums coarseSums(const Eigen::MatrixX3d& x, const Eigen::RowVector3d& centre, const Eigen::VectorXd& w,
                      const Eigen::MatrixX3d& g, int first, int count, Eigen::MatrixX3d& arms) {
  const Eigen::Index n = x.rows();
  const double *x0 = x.data() + first, *x1 = x0 + n, *x2 = x1 + n;
  double *a0 = arms.data() + first, *a1 = a0 + n, *a2 = a1 + n;
  const double c0 = centre[0], c1 = centre[1], c2 = centre[2];
  // (ctx, l) and (l, k) of the inertia add the same terms (a_k a_l = a_l a_k): six sums.
  double weight = 0.0, f0 = 0.0, f1 = 0.0, f2 = 0.0;
  double i00 = 0.0, i01 = 0.0, i02 = 0.0, i11 = 0.0, i12 = 0.0, i22 = 0.0;
  for (int i = 0; i < count; ++i) {
    const double r0 = x0[i] - c0, r1 = x1[i] - c1, r2 = x2[i] - c2;
    a0[i] = r0;
    a1[i] = r1;
    a2[i] = r2;
    const double a = w[first + i];
    weight += a;
    f0 += a * r0;
    f1 += a * r1;
    f2 += a * r2;
    const double squared = (r0 * r0 + r1 * r1) + r2 * r2;
    // |arm|^2 I's entries as |arm|^2 * Identity() forms them (the products by 1 and 0 keep the
    // sums the Matrix3d expression gave, bit for bit, signed zeros included).
    const double on = squared * 1.0, off = squared * 0.0;
    i00 += a * (on - r0 * r0);
    i01 += a * (off - r0 * r1);
    i02 += a * (off - r0 * r2);
    i11 += a * (on - r1 * r1);
    i12 += a * (off - r1 * r2);
    i22 += a * (on - r2 * r2);
  }
  const double *g0 = g.data() + first, *g1 = g0 + n, *g2 = g1 + n;
  double t[3][3] = {};
  for (int i = 0; i < count; ++i) {
    const double r[3] = {a0[i], a1[i], a2[i]}, gi[3] = {g0[i], g1[i], g2[i]};
    const double dot = (gi[0] * r[0] + gi[1] * r[1]) + gi[2] * r[2];
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) t[k][l] += dot * (k == l ? 1.0 : 0.0) - r[k] * gi[l];
  }
  CoarseSums out;
  out.weight = weight;
  out.first_moment << f0, f1, f2;
  out.inertia << i00, i01, i02, i01, i11, i12, i02, i12, i22;
  out.tension << t[0][0], t[0][1], t[0][2], t[1][0], t[1][1], t[1][2], t[2][0], t[2][1], t[2][2];
  return out;
}

}  // namespace

void RigidModes::prepare(SolveContext& ctx, double c, double t, const IterationControl& control,
                         const std::vector<char>& wanted) {
  const std::size_t segments = ctx.rows().size();
  rigid_on_.assign(segments, 0);
  const bool none = !wanted.empty() && std::none_of(wanted.begin(), wanted.end(), [](char on) { return on != 0; });
  if (!control.rigid_modes || ctx.scene() == nullptr || none) return;
  const Eigen::Index n = ctx.x_cur.rows();
  // The one-particle elements (pins, contacts): their weights go into A, their forces
  // w (p - x_j) into rigid_gradient_, which then becomes the other elements' energy gradient.
  rigid_weights_ = c * ctx.masses;
  rigid_gradient_.setZero(n, 3);
  thread_local std::vector<double> params;
  const SceneView running(*ctx.scene(), *ctx.forcing());
  for (const ElementBlock& block : ctx.scene()->blocks()) {
    if (block.count == 0 || block.type->shape().vertices != 1) continue;
    const std::size_t stride = static_cast<std::size_t>(block.type->shape().params);
    const bool timed = block.type->timeDependent(running);
    if (timed) block.type->paramsAt(running, t, params);
    const std::vector<double>& p = timed ? params : block.params;
    for (int e = 0; e < block.count; ++e) {
      const double* element = p.data() + stride * std::size_t(e);
      if (element[0] == 0.0) continue;
      const int j = block.vertices[std::size_t(e)];
      const Eigen::Vector3d x = ctx.x_cur.row(j).transpose();
      Eigen::Vector3d projected;
      block.type->project(x.data(), element, projected.data());
      rigid_weights_[j] += element[0];
      rigid_gradient_.row(j) += element[0] * (projected - x).transpose();
    }
  }
  // The other elements keep their energy under a rigid motion, so along rotations their Hessian
  // is -g_el . (e_k x (e_l x arm)) summed over the particles (the second derivative of the
  // invariant energy along R(theta) x, whose path curves away from the linear motion), g_el their
  // energy's gradient: the gradient less the inertia, the external forces and the one-particle
  // elements' part. A stretched body's tension makes it positive, a compressed one's negative.
  thread_local Eigen::MatrixX3d external;
  ctx.forcing()->externalForces(t, external);
  rigid_gradient_ +=
      ctx.gradient - ((ctx.x_cur - ctx.y_host).array().colwise() * (c * ctx.masses).array()).matrix() + external;
  rigid_arms_.resize(n, 3);
  findUnits(ctx);
  rigid_inverse_.resize(units_.size());
  unit_on_.assign(units_.size(), 0);
  for (std::size_t s = 0; s < segments; ++s) {
    if (ctx.stops.stopped(s) || (!wanted.empty() && !wanted[s])) continue;  // setRigidModes
    for (std::size_t u = unit_first_[s]; u < unit_first_[s + 1]; ++u) {
      const SegmentRows& seg = units_[u];
      // Serial sums in particle order: a batch's scene gets the arms its own Simulator gets, bit for
      // bit (a vectorised reduction would add in an order that depends on where the rows start).
      Eigen::RowVector3d moment = Eigen::RowVector3d::Zero();
      double mass = 0.0;
      for (int i = seg.first; i < seg.first + seg.count; ++i) {
        moment += ctx.masses[i] * ctx.x_cur.row(i);
        mass += ctx.masses[i];
      }
      const Eigen::RowVector3d centre = moment / mass;
      const CoarseSums sums =
          coarseSums(ctx.x_cur, centre, rigid_weights_, rigid_gradient_, seg.first, seg.count, rigid_arms_);
      const double weight = sums.weight;
      const Eigen::Vector3d& first_moment = sums.first_moment;
      const Eigen::Matrix3d &inertia = sums.inertia, &tension = sums.tension;
      // Z^T A Z's off-diagonal block: sum_i a_i e_k . (e_l x arm_i) = (e_l x first_moment)_k.
      Eigen::Matrix3d cross;
      for (int l = 0; l < 3; ++l) cross.col(l) = Eigen::Vector3d::Unit(l).cross(first_moment);
      Matrix6d coarse;
      coarse << weight * Eigen::Matrix3d::Identity(), cross, cross.transpose(),
          inertia + 0.5 * (tension + tension.transpose());
      const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(coarse);
      const double largest = eigen.eigenvalues().maxCoeff();
      if (!(largest > 0.0) || !std::isfinite(largest)) continue;
      // Directions of no or negative curvature (a compressed body's rotation) get no coarse step, and
      // those the tension takes below kCurvatureFloor of their inertia's (Z^T A Z alone) a smaller one.
      Matrix6d bare = coarse;
      bare.bottomRightCorner<3, 3>() = inertia;
      Vector6d inverse = Vector6d::Zero();
      for (int k = 0; k < 6; ++k) {
        const double lambda = eigen.eigenvalues()[k];
        if (!(lambda > kNullMotion * largest)) continue;
        const Vector6d v = eigen.eigenvectors().col(k);
        const double floor = kCurvatureFloor * v.dot(bare * v);
        inverse[k] = lambda >= floor ? 1.0 / lambda : lambda / (floor * floor);
      }
      rigid_inverse_[u] = eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
      unit_on_[u] = 1;
      rigid_on_[s] = 1;
    }
  }
}

void RigidModes::apply(SolveContext& ctx, double c, const IterationControl& control, const Eigen::MatrixX3d& q,
                       Eigen::MatrixX3d& r) {
  const std::size_t segments = ctx.rows().size();
  bool any = false;
  for (std::size_t s = 0; s < segments; ++s) any = any || (on(s) && !ctx.stops.stopped(s));
  if (!any) {
    ctx.applyInitialInverseHessian(c, control, q, r);
    return;
  }
  // u = S^+ Z^T q, then q - A Z u through K_c^-1, then r + Z (u - S^+ Z^T A r), unit by unit.
  thread_local std::vector<Vector6d> coarse_step;
  coarse_step.assign(units_.size(), Vector6d::Zero());
  rigid_q_ = q;
  const auto units = [&](auto&& each) {
    for (std::size_t s = 0; s < segments; ++s) {
      if (!on(s) || ctx.stops.stopped(s)) continue;
      for (std::size_t u = unit_first_[s]; u < unit_first_[s + 1]; ++u)
        if (unit_on_[u]) each(u, units_[u]);
    }
  };
  units([&](std::size_t u, const SegmentRows& unit) {
    coarse_step[u] = rigid_inverse_[u] * rigidComponents<false>(rigid_arms_, q, unit.first, unit.count, nullptr);
    moveRows<true>(coarse_step[u], rigid_arms_, rigid_weights_.data(), unit.first, unit.count, rigid_q_);
  });
  ctx.applyInitialInverseHessian(c, control, rigid_q_, r);
  units([&](std::size_t u, const SegmentRows& unit) {
    const Vector6d correction =
        coarse_step[u] -
        rigid_inverse_[u] * rigidComponents<true>(rigid_arms_, r, unit.first, unit.count, rigid_weights_.data());
    moveRows<false>(correction, rigid_arms_, nullptr, unit.first, unit.count, r);
  });
}

void RigidModes::findUnits(const SolveContext& ctx) {
  const Scene& scene = ctx.scene()->scene();
  const std::size_t elements =
      scene.springs.size() + scene.tets.size() + scene.triangle_strains.size() + scene.bending_hinges.size();
  std::vector<std::pair<int, int>> segments;
  for (const SegmentRows& seg : ctx.rows()) segments.emplace_back(seg.first, seg.count);
  if (units_scene_ == &scene && units_elements_ == elements && units_segments_ == segments) return;
  units_scene_ = &scene;
  units_elements_ = elements;
  units_segments_ = segments;
  // The bodies of two particles or more: a particle no element holds has no rotation for a coarse
  // space to add to K_c, which solves it alone exactly. connectedBodies orders them by their first
  // particle, so each segment's come in row order.
  const std::vector<std::vector<int>> bodies = connectedBodies(scene);
  units_.clear();
  unit_first_.assign(1, 0);
  for (const SegmentRows& seg : ctx.rows()) {
    std::vector<SegmentRows> own;
    bool runs = true;
    for (const std::vector<int>& body : bodies) {
      if (body.size() < 2 || body.front() < seg.first || body.front() >= seg.first + seg.count) continue;
      const int count = static_cast<int>(body.size());
      runs = runs && body.back() - body.front() + 1 == count;
      own.push_back(SegmentRows{body.front(), count});
    }
    // One body, or bodies whose rows interleave: the segment as one, as a scene of one body is.
    if (!runs || own.size() < 2) own.assign(1, seg);
    units_.insert(units_.end(), own.begin(), own.end());
    unit_first_.push_back(units_.size());
  }
}

}  // namespace stabint
