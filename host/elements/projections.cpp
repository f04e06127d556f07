#include "elements/projections.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>


namespace stabint::projections {

Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d& F) {
  // The reference path uses Eigen's two-sided Jacobi SVD: slow but accurate for any F,
  // including rank-deficient ones, which is what an oracle needs.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  // Singular values are sorted descending, so column 2 belongs to the smallest one.
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * V.transpose();
}

}  // namespace stabint::projections
