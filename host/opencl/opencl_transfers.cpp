// The OpenCL backend's slots and host copies: writes without waits, reads with one, and the
// forcing (external forces, time-dependent params) uploaded when the time or the forcing changes.
#include "opencl/opencl_backend_class.hpp"

namespace stabint::ocl {

template <typename Real>
void OpenCLBackend<Real>::write(int slot, const Eigen::MatrixX3d& host) {
  checkSlot(slot);
  if (host.rows() != n_)
    throw InvalidInputError("OpenCL backend: write of a matrix with " + std::to_string(host.rows()) +
                            " rows, expected " + std::to_string(n_));
  const auto start = Clock::now();
  writeAsync(slots_[slot], host.data(), std::size_t(host.size()));
  times_.transfer += secondsSince(start);
}

// A slot is its three columns one after another (x of every particle, then y, then z), so rows
// first.. are one range of each column: one rectangular write of three lines of rows.rows() reals,
// n reals apart on the device.
template <typename Real>
void OpenCLBackend<Real>::writeRows(int slot, int first, const Eigen::MatrixX3d& rows) {
  checkSlot(slot);
  if (first < 0 || rows.rows() > n_ - first)
    throw InvalidInputError("OpenCL backend: write of rows " + std::to_string(first) + ".." +
                            std::to_string(first + rows.rows()) + " of a slot of " + std::to_string(n_) + " rows");
  if (rows.rows() == 0) return;
  const auto start = Clock::now();
  PendingWrite& w = nextStaging();
  w.data.assign(rows.data(), rows.data() + rows.size());
  const std::size_t count = std::size_t(rows.rows());
  const cl::array<cl::size_type, 3> device_origin{bytes(std::size_t(first)), 0, 0}, host_origin{0, 0, 0},
      region{bytes(count), 3, 1};
  traffic_.to_device += std::int64_t(bytes(3 * count));
  ocl::check(queue_.enqueueWriteBufferRect(slots_[slot], CL_FALSE, device_origin, host_origin, region,
                                           bytes(std::size_t(n_)), 0, bytes(count), 0, w.data.data(), nullptr, &w.done),
             "clEnqueueWriteBufferRect");
  times_.transfer += secondsSince(start);
}

template <typename Real>
void OpenCLBackend<Real>::read(int slot, Eigen::MatrixX3d& host) {
  checkSlot(slot);
  const auto start = Clock::now();
  readMatrix(slots_[slot], host);
  times_.transfer += secondsSince(start);
}

template <typename Real>
void OpenCLBackend<Real>::readBoth(int slot_a, Eigen::MatrixX3d& a, int slot_b, Eigen::MatrixX3d& b) {
  checkSlot(slot_a);
  checkSlot(slot_b);
  const auto start = Clock::now();
  readMatrices(slots_[slot_a], a, slots_[slot_b], b);
  times_.transfer += secondsSince(start);
}

template <typename Real>
void OpenCLBackend<Real>::copy(int dst, int src) {
  checkSlot(dst);
  checkSlot(src);
  if (dst == src) return;
  ocl::check(queue_.enqueueCopyBuffer(slots_[src], slots_[dst], 0, 0, bytes(3 * n_)), "clEnqueueCopyBuffer");
}

template <typename Real>
void OpenCLBackend<Real>::combine(int dst, double a, int x, double b, int y) {
  checkSlot(dst);
  checkSlot(x);
  checkSlot(y);
  combine_.set(combine_args_.a, Real(a));
  combine_.bindSlot(combine_args_.x, x, slots_);
  combine_.set(combine_args_.b, Real(b));
  combine_.bindSlot(combine_args_.y, y, slots_);
  combine_.bindSlot(combine_args_.dst, dst, slots_);
  enqueue(combine_);
}

template <typename Real>
cl::Buffer OpenCLBackend<Real>::zeroBuffer(std::size_t count) {
  cl_int err = CL_SUCCESS;
  cl::Buffer buffer(context_, CL_MEM_READ_WRITE, bytes(std::max<std::size_t>(count, 1)), nullptr, &err);
  ocl::check(err, "clCreateBuffer");
  ocl::check(queue_.enqueueFillBuffer(buffer, Real(0), 0, bytes(std::max<std::size_t>(count, 1))),
             "clEnqueueFillBuffer");
  return buffer;
}

// External forces and time-dependent element params at time t; uploaded only when t changed
// and they depend on time (or everything once, at construction).
template <typename Real>
void OpenCLBackend<Real>::uploadForcing(double t, bool force) {
  const auto start = Clock::now();
  const int version = forcing_.version(), forces_version = forcing_.forcesVersion();
  if (force || forces_version != fext_version_ || (forcing_.hasTimeDependentForces() && t != fext_time_)) {
    forcing_.externalForces(t, host_fext_);
    writeAsync(fext_, host_fext_.data(), std::size_t(host_fext_.size()));
    fext_time_ = t;
    fext_version_ = forces_version;
  }
  for (DeviceBlock& d : blocks_) {
    if (d.block->count == 0) continue;
    const bool timed = d.block->type->timeDependent(running_);
    // Constant params are uploaded once, and again only when they replace time-dependent ones
    // (a restored checkpoint without pin ramps) or changed in place (a stiffness change).
    const bool stale = !d.params_uploaded || d.params_revision != d.block->params_revision ||
                       (timed ? (version != d.params_version || t != d.params_time) : d.params_timed);
    if (!force && !stale) continue;
    if (!force && !timed && !d.params_timed && d.params_uploaded && uploadChangedParams(d)) continue;
    if (timed) {
      d.block->type->paramsAt(running_, t, d.host_params);
    } else {
      d.host_params = d.block->params;
    }
    writeAsync(d.params, d.host_params.data(), d.host_params.size());
    d.params_time = t;
    d.params_version = version;
    d.params_timed = timed;
    d.params_uploaded = true;
    d.params_revision = d.block->params_revision;
  }
  times_.transfer += secondsSince(start);
}

// Constant params that changed in place since the upload (ElementBlock::changed_params): the range
// of elements from the first changed to the last goes up alone. False when the log no longer
// reaches back to the uploaded revision (the caller uploads the whole block).
template <typename Real>
bool OpenCLBackend<Real>::uploadChangedParams(DeviceBlock& d) {
  const ElementBlock& block = *d.block;
  const std::size_t changes = std::size_t(block.params_revision - d.params_revision);
  if (block.params_revision < d.params_revision || changes > block.changed_params.size()) return false;
  const auto since = block.changed_params.end() - std::ptrdiff_t(changes);
  const auto [lowest, highest] = std::minmax_element(since, block.changed_params.end());
  if (changes > 0) {
    const std::size_t p = std::size_t(block.type->shape().params), first = p * std::size_t(*lowest);
    writeAsync(d.params, block.params.data() + first, p * std::size_t(*highest + 1) - first, first);
  }
  d.params_revision = block.params_revision;
  return true;
}

// `count` reals from `host` to the buffer from its real `offset` on. Non-blocking: `host` is
// copied to a staging buffer of a small ring first, so the caller may change or free it as soon
// as we return; the next blocking call of the in-order queue (every read and energy pass ends
// with one) waits for the transfer, which saves a synchronisation per local/global iteration
// (solve, write x, then the next local step or energy pass). A staging buffer is refilled only
// after its previous transfer has completed.
template <typename Real>
void OpenCLBackend<Real>::writeAsync(const cl::Buffer& buffer, const double* host, std::size_t count,
                                     std::size_t offset) {
  if (count == 0) return;
  PendingWrite& w = nextStaging();
  w.data.assign(host, host + count);
  traffic_.to_device += std::int64_t(bytes(count));
  ocl::check(queue_.enqueueWriteBuffer(buffer, CL_FALSE, bytes(offset), bytes(count), w.data.data(), nullptr, &w.done),
             "clEnqueueWriteBuffer");
}

// The next staging buffer of the ring, once its previous transfer has completed.
template <typename Real>
typename OpenCLBackend<Real>::PendingWrite& OpenCLBackend<Real>::nextStaging() {
  PendingWrite& w = pending_writes_[next_write_];
  next_write_ = (next_write_ + 1) % pending_writes_.size();
  if (w.done()) ocl::check(w.done.wait(), "clWaitForEvents");
  return w;
}

template <typename Real>
void OpenCLBackend<Real>::readMatrix(const cl::Buffer& buffer, Eigen::MatrixX3d& host) {
  host.resize(n_, 3);
  const std::size_t count = 3 * std::size_t(n_);
  if (count == 0) return;
  traffic_.to_host += std::int64_t(bytes(count));
  if (kDouble) {
    ocl::check(queue_.enqueueReadBuffer(buffer, CL_TRUE, 0, bytes(count), host.data()), "clEnqueueReadBuffer");
  } else {
    staging_.resize(count);
    ocl::check(queue_.enqueueReadBuffer(buffer, CL_TRUE, 0, bytes(count), staging_.data()), "clEnqueueReadBuffer");
    std::copy(staging_.begin(), staging_.begin() + count, host.data());
  }
}

// Two buffers with one wait: the first read is queued without blocking, the blocking second
// one completes both (in-order queue).
template <typename Real>
void OpenCLBackend<Real>::readMatrices(const cl::Buffer& buffer_a, Eigen::MatrixX3d& a, const cl::Buffer& buffer_b,
                                       Eigen::MatrixX3d& b) {
  a.resize(n_, 3);
  b.resize(n_, 3);
  const std::size_t count = 3 * std::size_t(n_);
  if (count == 0) return;
  traffic_.to_host += std::int64_t(2 * bytes(count));
  if (kDouble) {
    ocl::check(queue_.enqueueReadBuffer(buffer_a, CL_FALSE, 0, bytes(count), a.data()), "clEnqueueReadBuffer");
    ocl::check(queue_.enqueueReadBuffer(buffer_b, CL_TRUE, 0, bytes(count), b.data()), "clEnqueueReadBuffer");
  } else {
    staging_.resize(count);
    staging_second_.resize(count);
    ocl::check(queue_.enqueueReadBuffer(buffer_a, CL_FALSE, 0, bytes(count), staging_.data()), "clEnqueueReadBuffer");
    ocl::check(queue_.enqueueReadBuffer(buffer_b, CL_TRUE, 0, bytes(count), staging_second_.data()),
               "clEnqueueReadBuffer");
    std::copy(staging_.begin(), staging_.begin() + count, a.data());
    std::copy(staging_second_.begin(), staging_second_.begin() + count, b.data());
  }
}

// The first `count` per-group partials to the host: the only wait of an energy pass (or none,
// when a blocking read queued after it waits).
template <typename Real>
void OpenCLBackend<Real>::readPartials(int count, bool blocking) {
  traffic_.to_host += std::int64_t(bytes(std::size_t(count)));
  ocl::check(queue_.enqueueReadBuffer(partials_, blocking ? CL_TRUE : CL_FALSE, 0, bytes(std::size_t(count)),
                                      host_partials_.data()),
             "clEnqueueReadBuffer");
}

// `count` per-scene sums from `first` on to the host, at the same places (blocking: the only wait
// of a per-scene call; or none, when a blocking read queued after it waits).
template <typename Real>
void OpenCLBackend<Real>::readSegmentSums(std::size_t count, std::size_t first, bool blocking) {
  traffic_.to_host += std::int64_t(bytes(count));
  ocl::check(queue_.enqueueReadBuffer(segment_sums_, blocking ? CL_TRUE : CL_FALSE, bytes(first), bytes(count),
                                      host_segment_sums_.data() + first),
             "clEnqueueReadBuffer");
}

template class OpenCLBackend<double>;
template class OpenCLBackend<float>;

}  // namespace stabint::ocl
