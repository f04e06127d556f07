#pragma once
// The global step on the OpenCL device (GlobalSolve::ConjugateGradient): L resident as a CSR
// matrix, and a Jacobi-preconditioned CG on (c M + L) x = b for the three columns at once,
// warm-started from x (kernels/cg.cl). A fixed iteration count queues 1 + 2 * iterations
// launches and reads nothing back; the CPU reference of the algorithm is
// GlobalSystem::solveConjugateGradient.
#include "opencl/cl_runtime.hpp"

#include <Eigen/SparseCore>

#include <cstdint>
#include <vector>

namespace stabint::ocl {

template <typename Real>
class DeviceConjugateGradient {
 public:
  /// `masses` (n reals) stays owned by the caller and must outlive this object; `profile` gives
  /// the work-group size and the grid (device_profiles.hpp).
  DeviceConjugateGradient(const cl::Context& context, const cl::Device& device, const DeviceProfile& profile,
                          const cl::CommandQueue& queue, int n, const cl::Buffer& masses);

  /// Uploads L (symmetric, `n by n`; any storage order): a new matrix, or the same one after a
  /// change (grab, element stiffness), which may also change its pattern.
  void setMatrix(const Eigen::SparseMatrix<double>& laplacian);

  /// Queues the CG on (c M + L) x = b from the current x (both `n by 3` buffers). With
  /// `tolerance` > 0 it waits after each iteration to read the residual's three column norms and
  /// stops once ||b - K x|| <= tolerance ||b|| in every column. Returns the iterations queued.
  int solve(double c, const cl::Buffer& b, const cl::Buffer& x, int iterations, double tolerance);

  /// Bytes copied between host and device and kernels launched (OpenCLBackend adds them to its
  /// Backend::traffic after each call).
  std::int64_t to_device = 0, to_host = 0, launches = 0;

 private:
  cl::Buffer buffer(std::size_t count);
  // Column sums of 3 * groups_ partials read back from `partials` (blocking).
  void columnSums(const cl::Buffer& partials, double sums[3]);

  cl::Context context_;
  cl::CommandQueue queue_;
  int n_;
  cl::Buffer masses_;
  cl::Program program_;
  cl::Kernel start_, direction_, update_;
  std::size_t local_ = 1;
  int groups_ = 1;
  bool have_matrix_ = false;
  cl::Buffer row_start_, column_, value_;
  cl::Buffer r_, z_, dinv_, p_[2], q_;  // r, z, p, q row by row (kernels/cg.cl)
  cl::Buffer rz_[2], pq_, rr_, bb_;
  std::vector<Real> host_partials_;
};

extern template class DeviceConjugateGradient<float>;
extern template class DeviceConjugateGradient<double>;

}  // namespace stabint::ocl
