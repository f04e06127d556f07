#include "opencl/device_solver.hpp"

#include "common/kernel_constants.hpp"
#include "opencl/embedded_kernels.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

namespace stabint::ocl {

template <typename Real>
DeviceConjugateGradient<Real>::DeviceConjugateGradient(const cl::Context& context, const cl::Device& device,
                                                       const DeviceProfile& profile, const cl::CommandQueue& queue,
                                                       int n, const cl::Buffer& masses)
    : context_(context), queue_(queue), n_(n), masses_(masses) {
  constexpr bool kDouble = std::is_same<Real, double>::value;
  std::string source;
  for (const char* file : {"real.cl", "cg.cl"})
    source += "// ---- " + std::string(file) + " ----\n" + embeddedKernel(file) + "\n";
  program_ = cachedProgram(context_, device, source, programOptions(kDouble ? Precision::Double : Precision::Float));
  cl_int err = CL_SUCCESS;
  start_ = cl::Kernel(program_, "cg_start", &err);
  check(err, "clCreateKernel");
  direction_ = cl::Kernel(program_, "cg_direction", &err);
  check(err, "clCreateKernel");
  update_ = cl::Kernel(program_, "cg_update", &err);
  check(err, "clCreateKernel");
  // One local size for the three kernels (the reductions need a power of two), and groups from
  // the device's row: enough for every compute unit, few enough that each kernel's sum of the
  // partials (done by every group) stays small; each work-item serves several rows beyond that.
  std::size_t limit = std::size_t(profile.reduce_local_size);
  for (const cl::Kernel* k : {&start_, &direction_, &update_}) {
    std::size_t allowed = 0;
    check(k->getWorkGroupInfo(device, CL_KERNEL_WORK_GROUP_SIZE, &allowed), "clGetKernelWorkGroupInfo");
    limit = std::min(limit, allowed);
  }
  while (local_ * 2 <= limit) local_ *= 2;
  const int per_group = profile.min_terms_per_work_item * int(local_);
  groups_ = std::clamp((n_ + per_group - 1) / per_group, 1, profile.max_reduce_groups);

  const std::size_t size3 = 3 * std::size_t(std::max(n_, 1));
  r_ = buffer(size3);
  z_ = buffer(size3);
  q_ = buffer(size3);
  p_[0] = buffer(size3);
  p_[1] = buffer(size3);
  dinv_ = buffer(std::size_t(std::max(n_, 1)));
  for (cl::Buffer* partials : {&rz_[0], &rz_[1], &pq_, &rr_, &bb_}) *partials = buffer(3 * std::size_t(groups_));
  host_partials_.resize(3 * std::size_t(groups_));
}

template <typename Real>
cl::Buffer DeviceConjugateGradient<Real>::buffer(std::size_t count) {
  cl_int err = CL_SUCCESS;
  cl::Buffer b(context_, CL_MEM_READ_WRITE, count * sizeof(Real), nullptr, &err);
  check(err, "clCreateBuffer");
  check(queue_.enqueueFillBuffer(b, Real(0), 0, count * sizeof(Real)), "clEnqueueFillBuffer");
  return b;
}

template <typename Real>
void DeviceConjugateGradient<Real>::setMatrix(const Eigen::SparseMatrix<double>& laplacian) {
  // Row-major compressed: row i's entries are contiguous (L is symmetric, so this is also its
  // column-major storage; the conversion only compresses it).
  Eigen::SparseMatrix<double, Eigen::RowMajor> csr = laplacian;
  csr.makeCompressed();
  const std::vector<cl_int> rows(csr.outerIndexPtr(), csr.outerIndexPtr() + csr.rows() + 1);
  std::vector<cl_int> columns(csr.innerIndexPtr(), csr.innerIndexPtr() + csr.nonZeros());
  std::vector<Real> values(csr.valuePtr(), csr.valuePtr() + csr.nonZeros());
  if (columns.empty()) columns.push_back(0), values.push_back(Real(0));  // no zero-size buffers
  // The queue is in order: kernels queued before read the old buffers, which the runtime keeps
  // alive until they complete. The host vectors must stay until the blocking writes return.
  cl_int err = CL_SUCCESS;
  const auto upload = [&](const void* data, std::size_t bytes) {
    cl::Buffer b(context_, CL_MEM_READ_ONLY, bytes, nullptr, &err);
    check(err, "clCreateBuffer");
    to_device += std::int64_t(bytes);
    check(queue_.enqueueWriteBuffer(b, CL_TRUE, 0, bytes, data), "clEnqueueWriteBuffer");
    return b;
  };
  row_start_ = upload(rows.data(), rows.size() * sizeof(cl_int));
  column_ = upload(columns.data(), columns.size() * sizeof(cl_int));
  value_ = upload(values.data(), values.size() * sizeof(Real));
  have_matrix_ = true;
}

template <typename Real>
void DeviceConjugateGradient<Real>::columnSums(const cl::Buffer& partials, double sums[3]) {
  to_host += std::int64_t(host_partials_.size() * sizeof(Real));
  check(queue_.enqueueReadBuffer(partials, CL_TRUE, 0, host_partials_.size() * sizeof(Real), host_partials_.data()),
        "clEnqueueReadBuffer");
  for (int k = 0; k < 3; ++k) {
    sums[k] = 0.0;
    for (int g = 0; g < groups_; ++g) sums[k] += double(host_partials_[std::size_t(k * groups_ + g)]);
  }
}

template <typename Real>
int DeviceConjugateGradient<Real>::solve(double c, const cl::Buffer& b, const cl::Buffer& x, int iterations,
                                         double tolerance) {
  if (!have_matrix_) throw Error("DeviceConjugateGradient::solve before setMatrix");
  if (n_ == 0) return 0;
  const cl::NDRange global(local_ * std::size_t(groups_)), local(local_);
  // groupSums of up to kCgGroupSums values (kernels/cg.cl)
  const cl::LocalSpaceArg scratch = cl::Local(std::size_t(kCgGroupSums) * local_ * sizeof(Real));
  const auto set = [](cl::Kernel& k, cl_uint index, const auto& value) {
    check(k.setArg(index, value), "clSetKernelArg");
  };
  const auto run = [&](const cl::Kernel& k) {
    ++launches;
    check(queue_.enqueueNDRangeKernel(k, cl::NullRange, global, local), "clEnqueueNDRangeKernel");
  };
  const cl_int n = n_;
  const Real real_c = Real(c);
  cl_uint a = 0;
  set(start_, a++, n), set(start_, a++, real_c);
  set(start_, a++, row_start_), set(start_, a++, column_), set(start_, a++, value_), set(start_, a++, masses_);
  set(start_, a++, b), set(start_, a++, x), set(start_, a++, r_), set(start_, a++, z_), set(start_, a++, dinv_);
  set(start_, a++, rz_[0]), set(start_, a++, rr_), set(start_, a++, bb_), set(start_, a++, scratch);
  run(start_);

  // Arguments that stay for the whole solve.
  set(direction_, 0, n), set(direction_, 1, real_c), set(direction_, 2, row_start_), set(direction_, 3, column_);
  set(direction_, 4, value_), set(direction_, 5, masses_), set(direction_, 6, z_);
  set(direction_, 9, q_), set(direction_, 13, pq_), set(direction_, 14, scratch);
  set(update_, 0, n), set(update_, 1, dinv_), set(update_, 3, q_), set(update_, 4, x), set(update_, 5, r_);
  set(update_, 6, z_), set(update_, 8, pq_), set(update_, 10, rr_), set(update_, 11, scratch);

  double tolerance2_bb[3] = {0.0, 0.0, 0.0};
  const auto converged = [&] {
    double rr[3];
    columnSums(rr_, rr);
    return rr[0] <= tolerance2_bb[0] && rr[1] <= tolerance2_bb[1] && rr[2] <= tolerance2_bb[2];
  };
  if (tolerance > 0.0) {
    columnSums(bb_, tolerance2_bb);
    for (double& v : tolerance2_bb) v *= tolerance * tolerance;
    if (converged()) return 0;
  }
  // rz_[current] holds the partials of the latest r.z, rz_[1 - current] the previous ones; the
  // directions alternate between p_[0] and p_[1] (cg_direction reads the old one).
  int current = 0;
  int done = 0;
  while (done < iterations) {
    const cl::Buffer& p_old = p_[done % 2];
    const cl::Buffer& p_new = p_[(done + 1) % 2];
    set(direction_, 7, p_old), set(direction_, 8, p_new);
    set(direction_, 10, rz_[current]), set(direction_, 11, rz_[1 - current]), set(direction_, 12, cl_int(done == 0));
    run(direction_);
    set(update_, 2, p_new), set(update_, 7, rz_[current]), set(update_, 9, rz_[1 - current]);
    run(update_);
    current = 1 - current;
    ++done;
    if (tolerance > 0.0 && converged()) break;
  }
  return done;
}

template class DeviceConjugateGradient<float>;
template class DeviceConjugateGradient<double>;

}  // namespace stabint::ocl
