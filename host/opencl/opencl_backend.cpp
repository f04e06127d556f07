#include "opencl/opencl_backend.hpp"

#include "opencl/cl_runtime.hpp"
#include "opencl/device_solver.hpp"
#include "opencl/element_program.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace stabint {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A kernel with its launch geometry. Arguments are appended in the order of the kernel's
// signature (add, addSlot); those that change between calls keep the index add returned and are
// re-set with set or bindSlot, the latter only when the slot differs from the bound one.
struct Launch {
  cl::Kernel kernel;
  cl::NDRange global = cl::NullRange;
  cl::NDRange local = cl::NullRange;
  std::vector<int> bound;  // slot bound to each argument index, -1 if none
  cl_uint next = 0;        // index of the next argument add appends

  template <typename T>
  cl_uint add(const T& value) {
    set(next, value);
    return next++;
  }
  cl_uint addSlot(int slot, const std::vector<cl::Buffer>& slots) {
    bindSlot(next, slot, slots);
    return next++;
  }
  void bindSlot(cl_uint arg, int slot, const std::vector<cl::Buffer>& slots) {
    if (bound.size() <= arg) bound.resize(arg + 1, -1);
    if (bound[arg] == slot) return;
    ocl::check(kernel.setArg(arg, slots[slot]), "clSetKernelArg");
    bound[arg] = slot;
  }
  template <typename T>
  void set(cl_uint arg, const T& value) {
    ocl::check(kernel.setArg(arg, value), "clSetKernelArg");
  }
};

template <typename Real>
class OpenCLBackend final : public Backend {
 public:
  OpenCLBackend(const SceneData& scene, int num_slots, const OpenCLOptions& options)
      : scene_(scene), n_(scene.numParticles()) {
    device_ = ocl::selectDevice(options);
    ocl::checkPrecisionSupported(kDouble ? Precision::Double : Precision::Float, device_.fp64, device_.device_name);
    context_ = ocl::sharedContext(device_.device);
    cl_int err = CL_SUCCESS;
    queue_ = cl::CommandQueue(context_, device_.device, CL_QUEUE_PROFILING_ENABLE, &err);
    ocl::check(err, "clCreateCommandQueue");

    // --- resident data -----------------------------------------------------------------------
    for (int s = 0; s < num_slots; ++s) slots_.push_back(zeroBuffer(3 * std::size_t(n_)));
    masses_ = upload(toReal(scene.masses().data(), std::size_t(n_)));
    fext_ = zeroBuffer(3 * std::size_t(n_));
    rhs_ = zeroBuffer(3 * std::size_t(n_));
    uploadElements();
    // A step writes x, v and the forcing (f_ext, params of any block) between two waits.
    pending_writes_.resize(3 + blocks_.size());

    buildKernels();

    // Forcing of a time-independent scene is uploaded once here.
    uploadForcing(0.0, /*force=*/true);
    ocl::check(queue_.finish(), "clFinish");
  }

  // Pending non-blocking writes read the staging buffers destroyed with us.
  ~OpenCLBackend() override { queue_.finish(); }

  // The element blocks and contribution lists were rebuilt (grab, release): upload them anew and
  // rebind the kernels (the program stays unless an element type appeared, see programTypes).
  void elementsChanged() override {
    ocl::check(queue_.finish(), "clFinish");
    uploadElements();
    buildKernels();
  }

  void write(int slot, const Eigen::MatrixX3d& host) override {
    checkSlot(slot);
    if (host.rows() != n_)
      throw InvalidInputError("OpenCL backend: write of a matrix with " + std::to_string(host.rows()) +
                              " rows, expected " + std::to_string(n_));
    const auto start = Clock::now();
    writeAsync(slots_[slot], host.data(), std::size_t(host.size()));
    times_.transfer += secondsSince(start);
  }

  void read(int slot, Eigen::MatrixX3d& host) override {
    checkSlot(slot);
    const auto start = Clock::now();
    readMatrix(slots_[slot], host);
    times_.transfer += secondsSince(start);
  }

  void readBoth(int slot_a, Eigen::MatrixX3d& a, int slot_b, Eigen::MatrixX3d& b) override {
    checkSlot(slot_a);
    checkSlot(slot_b);
    const auto start = Clock::now();
    readMatrices(slots_[slot_a], a, slots_[slot_b], b);
    times_.transfer += secondsSince(start);
  }

  void roundToStorage(Eigen::MatrixX3d& host) const override {
    if (!kDouble) host = host.cast<Real>().template cast<double>();
  }

  void copy(int dst, int src) override {
    checkSlot(dst);
    checkSlot(src);
    if (dst == src) return;
    ocl::check(queue_.enqueueCopyBuffer(slots_[src], slots_[dst], 0, 0, bytes(3 * n_)), "clEnqueueCopyBuffer");
  }

  void combine(int dst, double a, int x, double b, int y) override {
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

  double massDot(int a, int b) override {
    checkSlot(a);
    checkSlot(b);
    const auto start = Clock::now();
    mass_dot_.bindSlot(mass_dot_args_.a, a, slots_);
    mass_dot_.bindSlot(mass_dot_args_.b, b, slots_);
    enqueue(mass_dot_);
    readPartials(mass_dot_groups_);
    const double sum = sumPartials(0, mass_dot_groups_);
    times_.energy += secondsSince(start);
    return sum;
  }

  PotentialEnergy potential(int x, double t) override {
    checkSlot(x);
    uploadForcing(t, false);
    const auto start = Clock::now();
    enqueueElementPass(x, kPassEnergy);
    readPartials(full_groups_);
    const PotentialEnergy e = sumEnergies();
    times_.energy += secondsSince(start);
    return e;
  }

  // Timing without extra waits: the element pass and the gather are queued back to back and
  // the host waits once (blocking read or clFinish). The local and gather phases are the
  // device's own durations (event profiling); the rest of the wall time (command submission,
  // wake-up, the copy itself) is booked as transfer, or as local where nothing is copied.
  void accelerations(int dst, int x, double t) override {
    checkSlot(dst);
    checkSlot(x);
    uploadForcing(t, false);
    const auto start = Clock::now();
    enqueueElementPass(x, kPassForce);
    gather_accel_.bindSlot(gather_accel_dst_, dst, slots_);
    enqueue(gather_accel_, &gather_event_);
    ocl::check(queue_.finish(), "clFinish");
    const double wall = secondsSince(start);
    const double gather = deviceSeconds(gather_event_, gather_event_);
    times_.gather += gather;
    times_.local += std::max(0.0, wall - gather);
  }

  void localStepRhs(int x, int y, double c, double t, Eigen::MatrixX3d& rhs, PotentialEnergy* energy_at_x) override {
    gatheredLocalStep(kPassProjection, gather_rhs_, gather_rhs_args_, x, y, c, t, rhs, energy_at_x);
  }

  void localStepGradient(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                         PotentialEnergy* energy_at_x) override {
    gather_gradient_.bindSlot(gather_gradient_args_.x, x, slots_);
    gatheredLocalStep(kPassForce, gather_gradient_, gather_gradient_args_, x, y, c, t, gradient, energy_at_x);
  }

  // ---- the global step on the device (GlobalSolve::ConjugateGradient, device_solver.hpp) ----
  bool solvesGlobalSystem() const override { return true; }

  void setGlobalMatrix(const Eigen::SparseMatrix<double>& laplacian) override {
    const auto start = Clock::now();
    if (!cg_)
      cg_ = std::make_unique<ocl::DeviceConjugateGradient<Real>>(context_, device_.device, *device_.profile, queue_, n_,
                                                                 masses_);
    cg_->setMatrix(laplacian);
    times_.transfer += secondsSince(start);
  }

  // localStepRhs without the read of the right-hand side: queued, no wait unless the energy is
  // asked for (then the only wait is the read of the energy partials).
  void localStep(int x, int y, double c, double t, PotentialEnergy* energy_at_x) override {
    checkSlot(x);
    checkSlot(y);
    uploadForcing(t, false);
    const auto start = Clock::now();
    enqueueElementPass(x, kPassProjection | (energy_at_x ? kPassEnergy : 0));
    gather_rhs_.bindSlot(gather_rhs_args_.y, y, slots_);
    gather_rhs_.set(gather_rhs_args_.c, Real(c));
    enqueue(gather_rhs_);
    if (energy_at_x) {
      readPartials(full_groups_);
      *energy_at_x = sumEnergies();
      times_.local += secondsSince(start);
    }
  }

  int solveGlobal(double c, int x, int iterations, double tolerance) override {
    checkSlot(x);
    if (!cg_) throw Error("OpenCL backend: solveGlobal before setGlobalMatrix");
    return cg_->solve(c, rhs_, slots_[x], iterations, tolerance);
  }

  // ---- per-scene results of a batch (kernels/segments.cl) ----------------------------------
  bool computesPerScene() const override { return true; }

  void setSegments(const std::vector<SceneSegment>& segments) override {
    const std::string misfit = segmentsMisfit(segments);
    if (!misfit.empty()) throw InvalidInputError(misfit);
    segments_ = segments;
    segments_misfit_.clear();
    uploadSegmentTable();
  }

  // One launch and one read of one real per scene.
  void massDots(int a, int b, std::vector<double>& out) override {
    checkSlot(a);
    checkSlot(b);
    checkSegmentsFit();
    const auto start = Clock::now();
    out.resize(segments_.size());
    if (!segments_.empty()) {
      segment_mass_dots_.bindSlot(segment_mass_dots_args_.a, a, slots_);
      segment_mass_dots_.bindSlot(segment_mass_dots_args_.b, b, slots_);
      enqueue(segment_mass_dots_);
      readSegmentSums(segments_.size());
      for (std::size_t s = 0; s < segments_.size(); ++s) out[s] = double(host_segment_sums_[s]);
    }
    times_.energy += secondsSince(start);
  }

  // The element pass writing each element's energy, the per-scene sums, one read (one wait).
  void potentials(int x, double t, std::vector<PotentialEnergy>& out) override {
    checkSlot(x);
    checkSegmentsFit();
    uploadForcing(t, false);
    const auto start = Clock::now();
    out.assign(segments_.size(), PotentialEnergy{});
    if (!segments_.empty()) {
      enqueueElementPass(x, kPassEnergyPerElement);
      segment_energies_.bindSlot(segment_energies_x_, x, slots_);
      enqueue(segment_energies_);
      readSegmentSums(kSegmentEnergies * segments_.size());
      for (std::size_t s = 0; s < segments_.size(); ++s) {
        out[s].internal = double(host_segment_sums_[kSegmentEnergies * s + kSegmentInternal]);
        out[s].pins = double(host_segment_sums_[kSegmentEnergies * s + kSegmentPins]);
        out[s].external = double(host_segment_sums_[kSegmentEnergies * s + kSegmentExternal]);
      }
    }
    times_.energy += secondsSince(start);
  }

  void synchronize() override { ocl::check(queue_.finish(), "clFinish"); }

  // The device, the precision (with a warning where fp64 is slow: the caller asked for double
  // explicitly, Auto does not pick such a device for it) and the row of launch sizes.
  std::string description() const override {
    const DeviceProfile& profile = *device_.profile;
    return "OpenCL: " + device_.platform_name + " / " + device_.device_name + (kDouble ? " (double)" : " (float)") +
           " [device profile " + profile.name + (profile.measured ? "" : ", not yet measured") +
           (kDouble && !profile.fast_fp64 ? "; slow fp64 on this GPU: Precision::Float is much faster" : "") + "]";
  }

 private:
  static constexpr bool kDouble = std::is_same<Real, double>::value;

  // An element block on the device; the params of a time-dependent type are rewritten whenever
  // the time or the forcing (SceneData's version) changes.
  struct DeviceBlock {
    const ElementBlock* block = nullptr;
    int revision = -1;
    cl::Buffer vertices, coefficients, params;
    double params_time = std::numeric_limits<double>::quiet_NaN();
    int params_version = -1;
    bool params_timed = false;  // the buffer holds paramsAt's values, not the block's own
    bool params_uploaded = false;
    int params_revision = 0;  // ElementBlock::params_revision of the uploaded params
    std::vector<double> host_params;
  };

  static std::size_t bytes(std::size_t count) { return count * sizeof(Real); }

  static std::vector<Real> toReal(const double* data, std::size_t count) {
    return std::vector<Real>(data, data + count);
  }

  void checkSlot(int slot) const {
    if (slot < 0 || slot >= static_cast<int>(slots_.size()))
      throw InvalidInputError("OpenCL backend: slot " + std::to_string(slot) + " out of range (have " +
                              std::to_string(slots_.size()) + ")");
  }

  template <typename T>
  cl::Buffer upload(const std::vector<T>& data) {
    // An empty array still gets a one-element buffer: OpenCL has no zero-size buffers.
    static const T placeholder{};
    const T* src = data.empty() ? &placeholder : data.data();
    cl_int err = CL_SUCCESS;
    cl::Buffer buffer(context_, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      std::max<std::size_t>(data.size(), 1) * sizeof(T), const_cast<T*>(src), &err);
    ocl::check(err, "clCreateBuffer");
    return buffer;
  }

  cl::Buffer zeroBuffer(std::size_t count) {
    cl_int err = CL_SUCCESS;
    cl::Buffer buffer(context_, CL_MEM_READ_WRITE, bytes(std::max<std::size_t>(count, 1)), nullptr, &err);
    ocl::check(err, "clCreateBuffer");
    ocl::check(queue_.enqueueFillBuffer(buffer, Real(0), 0, bytes(std::max<std::size_t>(count, 1))),
               "clEnqueueFillBuffer");
    return buffer;
  }

  // External forces and time-dependent element params at time t; uploaded only when t changed
  // and they depend on time (or everything once, at construction).
  void uploadForcing(double t, bool force) {
    const auto start = Clock::now();
    const int version = scene_.forcingVersion();
    if (force || version != fext_version_ || (scene_.hasTimeDependentForces() && t != fext_time_)) {
      scene_.externalForces(t, host_fext_);
      writeAsync(fext_, host_fext_.data(), std::size_t(host_fext_.size()));
      fext_time_ = t;
      fext_version_ = version;
    }
    for (DeviceBlock& d : blocks_) {
      if (d.block->count == 0) continue;
      const bool timed = d.block->type->timeDependent(scene_);
      // Constant params are uploaded once, and again only when they replace time-dependent ones
      // (a restored checkpoint without pin ramps) or changed in place (a stiffness change).
      const bool stale = !d.params_uploaded || d.params_revision != d.block->params_revision ||
                         (timed ? (version != d.params_version || t != d.params_time) : d.params_timed);
      if (!force && !stale) continue;
      if (timed) {
        d.block->type->paramsAt(scene_, t, d.host_params);
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

  // Non-blocking: `host` is copied to a staging buffer of a small ring first, so the caller may
  // change or free it as soon as we return; the next blocking call of the in-order queue (every
  // read and energy pass ends with one) waits for the transfer, which saves a synchronisation
  // per local/global iteration (solve, write x, then the next local step or energy pass). A
  // staging buffer is refilled only after its previous transfer has completed.
  void writeAsync(const cl::Buffer& buffer, const double* host, std::size_t count) {
    if (count == 0) return;
    PendingWrite& w = pending_writes_[next_write_];
    next_write_ = (next_write_ + 1) % pending_writes_.size();
    if (w.done()) ocl::check(w.done.wait(), "clWaitForEvents");
    w.data.assign(host, host + count);
    ocl::check(queue_.enqueueWriteBuffer(buffer, CL_FALSE, 0, bytes(count), w.data.data(), nullptr, &w.done),
               "clEnqueueWriteBuffer");
  }

  // The element pass with `flags` (plus the energy when asked for), then `gather` over its
  // contributions into rhs_, read back to `out`: localStepRhs and localStepGradient.
  template <class GatherArgs>
  void gatheredLocalStep(int flags, Launch& gather, const GatherArgs& args, int x, int y, double c, double t,
                         Eigen::MatrixX3d& out, PotentialEnergy* energy_at_x) {
    checkSlot(x);
    checkSlot(y);
    uploadForcing(t, false);
    const auto start = Clock::now();
    const bool launched = enqueueElementPass(x, flags | (energy_at_x ? kPassEnergy : 0));
    gather.bindSlot(args.y, y, slots_);
    gather.set(args.c, Real(c));
    enqueue(gather, &gather_event_);
    if (energy_at_x) readPartials(full_groups_, /*blocking=*/false);
    readMatrix(rhs_, out);  // blocking: everything queued above has completed
    if (energy_at_x) *energy_at_x = sumEnergies();
    const double wall = secondsSince(start);
    const double local = launched ? deviceSeconds(element_event_, element_event_) : 0.0;
    const double gathered = deviceSeconds(gather_event_, gather_event_);
    times_.local += local;
    times_.gather += gathered;
    times_.transfer += std::max(0.0, wall - local - gathered);
  }

  void readMatrix(const cl::Buffer& buffer, Eigen::MatrixX3d& host) {
    host.resize(n_, 3);
    const std::size_t count = 3 * std::size_t(n_);
    if (count == 0) return;
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
  void readMatrices(const cl::Buffer& buffer_a, Eigen::MatrixX3d& a, const cl::Buffer& buffer_b, Eigen::MatrixX3d& b) {
    a.resize(n_, 3);
    b.resize(n_, 3);
    const std::size_t count = 3 * std::size_t(n_);
    if (count == 0) return;
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
  void readPartials(int count, bool blocking = true) {
    ocl::check(queue_.enqueueReadBuffer(partials_, blocking ? CL_TRUE : CL_FALSE, 0, bytes(std::size_t(count)),
                                        host_partials_.data()),
               "clEnqueueReadBuffer");
  }

  // The first `count` per-scene sums to the host (blocking: the only wait of a per-scene call).
  void readSegmentSums(std::size_t count) {
    ocl::check(queue_.enqueueReadBuffer(segment_sums_, CL_TRUE, 0, bytes(count), host_segment_sums_.data()),
               "clEnqueueReadBuffer");
  }

  // The kernels index buffers with the table, so a table that does not fit this scene is refused
  // rather than read out of bounds on the device: why it does not fit, or "".
  std::string segmentsMisfit(const std::vector<SceneSegment>& segments) const {
    const std::size_t num_blocks = blocks_.size();
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const SceneSegment& seg = segments[s];
      const std::string which = "OpenCL backend: segment " + std::to_string(s) + ": ";
      if (seg.first_particle < 0 || seg.num_particles < 0 || seg.first_particle > n_ - seg.num_particles)
        return which + "particles outside the scene's " + std::to_string(n_);
      if (seg.first_element.size() != num_blocks || seg.num_elements.size() != num_blocks)
        return which + "element ranges for " + std::to_string(seg.first_element.size()) + " types, the scene has " +
               std::to_string(num_blocks);
      for (std::size_t b = 0; b < num_blocks; ++b)
        if (seg.first_element[b] < 0 || seg.num_elements[b] < 0 ||
            seg.first_element[b] > blocks_[b].block->count - seg.num_elements[b])
          return which + "elements of " + blocks_[b].block->type->name() + " outside the scene's " +
                 std::to_string(blocks_[b].block->count);
    }
    return "";
  }

  // Per-scene calls need segments that fit the current elements (after setPins changed them, the
  // caller sets the new segments).
  void checkSegmentsFit() const {
    if (!segments_misfit_.empty()) throw InvalidInputError(segments_misfit_ + " (setSegments after setPins)");
  }

  // The segment table of kernels/segments.cl for the current element layout: per segment its
  // particle range, then per block the range of its elements' energies, which element_pass
  // writes at the element's global id (block b's element e at segment_groups_[b] groups + e).
  // Built again by buildKernels when the blocks change (elementsChanged).
  void uploadSegmentTable() {
    const std::size_t num_blocks = blocks_.size();
    std::vector<cl_int> table;
    static_assert(kSegmentRowHead == 2 && kSegmentRowPerBlock == 2, "a row below is 2 ints, then 2 per block");
    table.reserve(segments_.size() * (kSegmentRowHead + kSegmentRowPerBlock * num_blocks));
    for (const SceneSegment& seg : segments_) {
      table.push_back(seg.first_particle);
      table.push_back(seg.num_particles);
      for (std::size_t b = 0; b < num_blocks; ++b) {
        table.push_back(cl_int(std::size_t(segment_groups_[b]) * element_local_) + seg.first_element[b]);
        table.push_back(seg.num_elements[b]);
      }
    }
    std::vector<cl_int> block_is_pins;
    for (const DeviceBlock& d : blocks_) block_is_pins.push_back(d.block->type->term() == EnergyTerm::Pins ? 1 : 0);
    segment_table_ = upload(table);
    block_is_pins_ = upload(block_is_pins);
    segment_sums_ = zeroBuffer(kSegmentEnergies * segments_.size());
    host_segment_sums_.resize(kSegmentEnergies * std::max<std::size_t>(segments_.size(), 1));

    const cl_int segments = cl_int(segments_.size()), blocks = cl_int(num_blocks), n = n_;
    segment_energies_ = elementLaunch("segment_energies", int(segments_.size()));
    segment_energies_.add(segments), segment_energies_.add(blocks), segment_energies_.add(segment_table_);
    segment_energies_.add(block_is_pins_), segment_energies_.add(element_energies_), segment_energies_.add(n);
    segment_energies_x_ = segment_energies_.addSlot(0, slots_);
    segment_energies_.add(fext_), segment_energies_.add(segment_sums_);

    segment_mass_dots_ = elementLaunch("segment_mass_dots", int(segments_.size()));
    segment_mass_dots_.add(segments), segment_mass_dots_.add(blocks), segment_mass_dots_.add(segment_table_);
    segment_mass_dots_.add(n), segment_mass_dots_.add(masses_);
    segment_mass_dots_args_.a = segment_mass_dots_.addSlot(0, slots_);
    segment_mass_dots_args_.b = segment_mass_dots_.addSlot(0, slots_);
    segment_mass_dots_.add(segment_sums_);
  }

  // Partials [first, last) added in group order (a fixed order: deterministic).
  double sumPartials(int first, int last) const {
    double sum = 0.0;
    for (int g = first; g < last; ++g) sum += double(host_partials_[g]);
    return sum;
  }

  // The energies of a full element pass, segment by segment.
  PotentialEnergy sumEnergies() const {
    PotentialEnergy e;
    for (std::size_t s = 0; s < blocks_.size(); ++s) {
      const double sum = sumPartials(segment_groups_[s], segment_groups_[s + 1]);
      (blocks_[s].block->type->term() == EnergyTerm::Pins ? e.pins : e.internal) += sum;
    }
    e.external = sumPartials(segment_groups_[blocks_.size()], full_groups_);
    return e;
  }

  void enqueue(const Launch& launch, cl::Event* event = nullptr) {
    ocl::check(queue_.enqueueNDRangeKernel(launch.kernel, cl::NullRange, launch.global, launch.local, nullptr, event),
               "clEnqueueNDRangeKernel");
  }

  // Seconds from the start of `first` to the end of `last` on the device (both complete).
  static double deviceSeconds(const cl::Event& first, const cl::Event& last) {
    cl_ulong begin = 0, end = 0;
    ocl::check(first.getProfilingInfo(CL_PROFILING_COMMAND_START, &begin), "clGetEventProfilingInfo");
    ocl::check(last.getProfilingInfo(CL_PROFILING_COMMAND_END, &end), "clGetEventProfilingInfo");
    return end > begin ? double(end - begin) * 1e-9 : 0.0;
  }

  // Queues the element pass at positions `x` with `flags`: the element segments, plus the
  // vertex segment (external potential) when energies are asked for. Returns false when there
  // was nothing to launch (no elements, no energy).
  bool enqueueElementPass(int x, int flags) {
    const int groups = (flags & kPassEnergy) ? full_groups_ : segment_groups_[blocks_.size()];
    if (groups == 0) return false;
    element_pass_.bindSlot(element_args_.x, x, slots_);
    element_pass_.set(element_args_.flags, cl_int(flags));
    ocl::check(queue_.enqueueNDRangeKernel(element_pass_.kernel, cl::NullRange,
                                           cl::NDRange(element_local_ * std::size_t(groups)), element_pass_.local,
                                           nullptr, &element_event_),
               "clEnqueueNDRangeKernel");
    return true;
  }

  cl::Kernel makeKernel(const char* name) {
    cl_int err = CL_SUCCESS;
    cl::Kernel kernel(program_, name, &err);
    ocl::check(err, "clCreateKernel");
    return kernel;
  }

  // Largest power of two <= min(wanted, what the device allows for this kernel).
  std::size_t localSize(const cl::Kernel& kernel, std::size_t wanted) {
    std::size_t limit = 0;
    ocl::check(kernel.getWorkGroupInfo(device_.device, CL_KERNEL_WORK_GROUP_SIZE, &limit), "clGetKernelWorkGroupInfo");
    std::size_t size = 1;
    while (size * 2 <= std::min(wanted, limit)) size *= 2;
    return size;
  }

  // 1-D launch over `count` items (rounded up to the local size; kernels check the bound).
  Launch elementLaunch(const char* name, int count) {
    Launch l;
    l.kernel = makeKernel(name);
    const std::size_t local = localSize(l.kernel, std::size_t(device_.profile->element_local_size));
    const std::size_t global = (std::size_t(std::max(count, 1)) + local - 1) / local * local;
    l.global = cl::NDRange(global);
    l.local = cl::NDRange(local);
    return l;
  }

  // Groups of the mass-dot reduction over n terms: fixed by the scene size and the device's row,
  // so every call adds the same terms in the same order.
  int reductionGroups(int count, std::size_t local) const {
    const int per_group = device_.profile->min_terms_per_work_item * int(local);
    return std::clamp((count + per_group - 1) / per_group, 1, device_.profile->max_reduce_groups);
  }

  // The element types the program is built for: those the scene has, and pins always (a grab
  // adds them to a scene without pins; they cost the program nothing), so that a spring cloth
  // does not compile the tet and triangle-strain rotations.
  std::vector<const ElementType*> programTypes() const {
    std::vector<const ElementType*> types;
    for (const DeviceBlock& d : blocks_)
      if (d.block->count > 0 || d.block->type->term() == EnergyTerm::Pins) types.push_back(d.block->type);
    return types;
  }

  // The element program for the current types (the process-wide cache makes a repeated set free).
  void useProgramFor(const std::vector<const ElementType*>& types) {
    if (program_() != nullptr && types == program_types_) return;
    program_ = ocl::cachedProgram(context_, device_.device, ocl::elementProgramSource(types),
                                  ocl::programOptions(kDouble ? Precision::Double : Precision::Float));
    program_types_ = types;
  }

  // Per-element data of the blocks that are new or were rebuilt, and the contribution lists; the
  // params follow in uploadForcing.
  void uploadElements() {
    const ContributionCsr& csr = scene_.csr();
    contrib_ = zeroBuffer(3 * std::size_t(std::max(csr.numContributions, 1)));
    offsets_ = upload(csr.offsets);
    list_ = upload(csr.contributions.empty() ? std::vector<int>{0} : csr.contributions);
    blocks_.resize(scene_.blocks().size());
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      const ElementBlock& block = scene_.blocks()[b];
      DeviceBlock& d = blocks_[b];
      if (d.block == &block && d.revision == block.revision) continue;
      d = DeviceBlock{};
      d.block = &block;
      d.revision = block.revision;
      d.vertices = upload(block.vertices);
      d.coefficients = upload(toReal(block.coefficients.data(), block.coefficients.size()));
      d.params = zeroBuffer(block.params.size());
    }
  }

  void buildKernels() {
    const std::vector<const ElementType*> types = programTypes();
    useProgramFor(types);
    const cl_int n = n_;
    element_pass_ = Launch{};
    mass_dot_ = Launch{};
    // --- the element pass: one work-item per element, one segment of groups per type --------
    element_pass_.kernel = makeKernel("element_pass");
    element_local_ = localSize(element_pass_.kernel, std::size_t(device_.profile->element_local_size));
    element_pass_.local = cl::NDRange(element_local_);
    const auto groupsFor = [&](int count) { return int((std::size_t(count) + element_local_ - 1) / element_local_); };
    segment_groups_.assign(1, 0);
    for (const DeviceBlock& d : blocks_) segment_groups_.push_back(segment_groups_.back() + groupsFor(d.block->count));
    full_groups_ = segment_groups_.back() + groupsFor(n_);

    // Both reductions write their per-group partials into one buffer.
    mass_dot_.kernel = makeKernel("mass_dot_partials");
    const std::size_t reduce_local = localSize(mass_dot_.kernel, std::size_t(device_.profile->reduce_local_size));
    mass_dot_groups_ = reductionGroups(n_, reduce_local);
    mass_dot_.global = cl::NDRange(reduce_local * std::size_t(mass_dot_groups_));
    mass_dot_.local = cl::NDRange(reduce_local);
    const int max_partials = std::max(full_groups_, mass_dot_groups_);
    partials_ = zeroBuffer(std::size_t(max_partials));
    host_partials_.resize(std::size_t(max_partials));
    element_energies_ = zeroBuffer(std::size_t(segment_groups_.back()) * element_local_);

    element_args_.x = element_pass_.addSlot(0, slots_);
    element_pass_.add(n);
    element_args_.flags = element_pass_.add(cl_int(0));
    element_pass_.add(fext_);
    element_pass_.add(contrib_);
    element_pass_.add(partials_);
    element_pass_.add(element_energies_);
    element_pass_.add(cl::Local(bytes(element_local_)));
    element_pass_.add(cl_int(segment_groups_.back()));
    // The program's types in the table's order, as blocks_ (a skipped type has no elements, so no
    // groups: its segment is empty).
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      const DeviceBlock& d = blocks_[b];
      if (std::find(types.begin(), types.end(), d.block->type) == types.end()) continue;
      element_pass_.add(
          cl_int4{{segment_groups_[b], segment_groups_[b + 1], d.block->count, d.block->contribution_base}});
      element_pass_.add(d.vertices);
      element_pass_.add(d.coefficients);
      element_pass_.add(d.params);
    }

    // --- vector operations and the gathers -------------------------------------------------------
    combine_ = elementLaunch("combine", 3 * n_);
    combine_.add(cl_int(3 * n_));
    combine_args_.a = combine_.add(Real(0));
    combine_args_.x = combine_.addSlot(0, slots_);
    combine_args_.b = combine_.add(Real(0));
    combine_args_.y = combine_.addSlot(0, slots_);
    combine_args_.dst = combine_.addSlot(0, slots_);

    gather_rhs_ = elementLaunch("gather_rhs", n_);
    gather_gradient_ = elementLaunch("gather_gradient", n_);
    gather_accel_ = elementLaunch("gather_accelerations", n_);
    for (Launch* g : {&gather_rhs_, &gather_gradient_, &gather_accel_}) {
      g->add(n), g->add(offsets_), g->add(list_), g->add(contrib_), g->add(masses_), g->add(fext_);
    }
    gather_rhs_args_.y = gather_rhs_.addSlot(0, slots_);
    gather_rhs_args_.c = gather_rhs_.add(Real(0));
    gather_rhs_.add(rhs_);
    gather_gradient_args_.x = gather_gradient_.addSlot(0, slots_);
    gather_gradient_args_.y = gather_gradient_.addSlot(0, slots_);
    gather_gradient_args_.c = gather_gradient_.add(Real(0));
    gather_gradient_.add(rhs_);
    gather_accel_dst_ = gather_accel_.addSlot(0, slots_);

    mass_dot_.add(n), mass_dot_.add(masses_);
    mass_dot_args_.a = mass_dot_.addSlot(0, slots_);
    mass_dot_args_.b = mass_dot_.addSlot(0, slots_);
    mass_dot_.add(partials_);
    mass_dot_.add(cl::Local(bytes(reduce_local)));

    // The segment table indexes element_energies_ by the element groups just laid out.
    segments_misfit_ = segmentsMisfit(segments_);
    if (!segments_.empty() && segments_misfit_.empty()) uploadSegmentTable();
  }

  const SceneData& scene_;
  const int n_;
  std::vector<DeviceBlock> blocks_;
  // First group of each element segment, then of the vertex segment; full_groups_ ends it.
  std::vector<int> segment_groups_;
  int full_groups_ = 0;
  std::size_t element_local_ = 1;
  int mass_dot_groups_ = 1;

  ocl::SelectedDevice device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  cl::Program program_;
  std::vector<const ElementType*> program_types_;  // the element types program_ was built for

  std::vector<cl::Buffer> slots_;
  cl::Buffer masses_, fext_, rhs_, contrib_, offsets_, list_;
  cl::Buffer partials_;
  // Per-scene sums of a batch: each element's energy (element_pass with kPassEnergyPerElement),
  // the segment table, which blocks are pins, the sums (3 per segment, or 1 for massDots).
  std::vector<SceneSegment> segments_;
  std::string segments_misfit_;  // why segments_ no longer fit the elements, or ""
  cl::Buffer element_energies_, segment_table_, block_is_pins_, segment_sums_;
  std::vector<Real> host_segment_sums_;
  Launch segment_energies_, segment_mass_dots_;
  cl_uint segment_energies_x_ = 0;
  struct {
    cl_uint a, b;
  } segment_mass_dots_args_{};

  Launch element_pass_, mass_dot_, combine_, gather_rhs_, gather_gradient_, gather_accel_;
  struct {
    cl_uint x, flags;
  } element_args_{};
  struct {
    cl_uint a, x, b, y, dst;
  } combine_args_{};
  struct {
    cl_uint y, c;
  } gather_rhs_args_{};
  struct {
    cl_uint x, y, c;
  } gather_gradient_args_{};
  struct {
    cl_uint a, b;
  } mass_dot_args_{};
  cl_uint gather_accel_dst_ = 0;
  cl::Event element_event_, gather_event_;

  double fext_time_ = std::numeric_limits<double>::quiet_NaN();
  int fext_version_ = -1;
  Eigen::MatrixX3d host_fext_;
  std::vector<Real> staging_, staging_second_;
  struct PendingWrite {
    std::vector<Real> data;
    cl::Event done;
  };
  std::vector<PendingWrite> pending_writes_;
  std::size_t next_write_ = 0;
  std::vector<Real> host_partials_;
  std::unique_ptr<ocl::DeviceConjugateGradient<Real>> cg_;  // made by the first setGlobalMatrix
};

}  // namespace

std::unique_ptr<Backend> makeOpenCLBackend(const SceneData& scene, int num_slots, const OpenCLOptions& options) {
  if (options.precision == Precision::Float) return std::make_unique<OpenCLBackend<float>>(scene, num_slots, options);
  return std::make_unique<OpenCLBackend<double>>(scene, num_slots, options);
}

}  // namespace stabint
