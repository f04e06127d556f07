#include "opencl/opencl_backend.hpp"

#include "opencl/cl_runtime.hpp"
#include "opencl/embedded_kernels.hpp"
#include "scene/scene_data.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

namespace stabint {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Kernel files in the order they are concatenated into one program (real.cl defines `real`).
const char* const kProgramFiles[] = {"real.cl",       "springs.cl", "tets.cl",  "pins.cl",
                                     "gather.cl",     "vector_ops.cl", "reduce.cl", "energy.cl"};

std::string programSource() {
  std::string source;
  for (const char* file : kProgramFiles) {
    source += "// ---- ";
    source += file;
    source += " ----\n";
    source += ocl::embeddedKernel(file);
    source += "\n";
  }
  return source;
}

constexpr int kModeProjection = 0;
constexpr int kModeForce = 1;

// A kernel with its launch geometry; buffer arguments that change between calls (the slots) are
// re-set only when they differ from the bound one.
struct Launch {
  cl::Kernel kernel;
  cl::NDRange global = cl::NullRange;
  cl::NDRange local = cl::NullRange;
  std::vector<int> bound;  // slot bound to each argument index, -1 if none

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
    ocl::checkPrecisionSupported(kDouble ? Precision::Double : Precision::Float, device_.fp64,
                                 device_.device_name);
    context_ = ocl::sharedContext(device_.device);
    cl_int err = CL_SUCCESS;
    queue_ = cl::CommandQueue(context_, device_.device, CL_QUEUE_PROFILING_ENABLE, &err);
    ocl::check(err, "clCreateCommandQueue");
    program_ = ocl::cachedProgram(
        context_, device_.device, programSource(),
        std::string("-cl-std=CL1.2 ") + (kDouble ? "-DSTABINT_DOUBLE" : "-DSTABINT_FLOAT"));

    const ContributionCsr& csr = scene.csr();
    num_springs_ = static_cast<int>(scene.springs().size());
    num_tets_ = static_cast<int>(scene.tets().size());
    num_pins_ = static_cast<int>(scene.pins().size());

    // --- resident data -----------------------------------------------------------------------
    for (int s = 0; s < num_slots; ++s) slots_.push_back(zeroBuffer(3 * std::size_t(n_)));
    masses_ = upload(std::vector<Real>(scene.masses().data(), scene.masses().data() + n_));
    fext_ = zeroBuffer(3 * std::size_t(n_));
    rhs_ = zeroBuffer(3 * std::size_t(n_));
    contrib_ = zeroBuffer(3 * std::size_t(std::max(csr.numContributions, 1)));
    offsets_ = upload(csr.offsets);
    list_ = upload(csr.contributions.empty() ? std::vector<int>{0} : csr.contributions);
    uploadSprings();
    uploadTets();
    uploadPins();

    buildKernels(csr);

    // Forcing of a time-independent scene is uploaded once here.
    uploadForcing(0.0, /*force=*/true);
    ocl::check(queue_.finish(), "clFinish");
  }

  // Pending non-blocking writes read the staging buffers destroyed with us.
  ~OpenCLBackend() override { queue_.finish(); }

  void write(int slot, const Eigen::MatrixX3d& host) override {
    checkSlot(slot);
    if (host.rows() != n_) throw InvalidInputError("OpenCL backend: write of a matrix with " +
                                                   std::to_string(host.rows()) + " rows, expected " +
                                                   std::to_string(n_));
    const auto start = Clock::now();
    writeMatrixAsync(slots_[slot], host);
    times_.transfer += secondsSince(start);
  }

  void read(int slot, Eigen::MatrixX3d& host) override {
    checkSlot(slot);
    const auto start = Clock::now();
    readMatrix(slots_[slot], host);
    times_.transfer += secondsSince(start);
  }

  void copy(int dst, int src) override {
    checkSlot(dst);
    checkSlot(src);
    if (dst == src) return;
    ocl::check(queue_.enqueueCopyBuffer(slots_[src], slots_[dst], 0, 0, bytes(3 * n_)),
               "clEnqueueCopyBuffer");
  }

  void combine(int dst, double a, int x, double b, int y) override {
    checkSlot(dst);
    checkSlot(x);
    checkSlot(y);
    combine_.set(1, Real(a));
    combine_.bindSlot(2, x, slots_);
    combine_.set(3, Real(b));
    combine_.bindSlot(4, y, slots_);
    combine_.bindSlot(5, dst, slots_);
    enqueue(combine_);
  }

  double massDot(int a, int b) override {
    checkSlot(a);
    checkSlot(b);
    const auto start = Clock::now();
    mass_dot_.bindSlot(2, a, slots_);
    mass_dot_.bindSlot(3, b, slots_);
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
    potential_.bindSlot(0, x, slots_);
    enqueue(potential_);
    const std::array<int, 5>& g = energy_segments_;
    readPartials(g[4]);
    PotentialEnergy e;
    e.strain = sumPartials(g[0], g[1]) + sumPartials(g[1], g[2]);  // springs + tets
    e.pins = sumPartials(g[2], g[3]);
    e.external = sumPartials(g[3], g[4]);
    times_.energy += secondsSince(start);
    return e;
  }

  // Timing without extra waits: the element kernels and the gather are queued back to back and
  // the host waits once (blocking read or clFinish). The local and gather phases are the
  // device's own durations (event profiling); the rest of the wall time (command submission,
  // wake-up, the copy itself) is booked as transfer, or as local where nothing is copied.
  void accelerations(int dst, int x, double t) override {
    checkSlot(dst);
    checkSlot(x);
    uploadForcing(t, false);
    const auto start = Clock::now();
    enqueueContributions(x, kModeForce);
    gather_accel_.bindSlot(6, dst, slots_);
    enqueue(gather_accel_, &gather_event_);
    ocl::check(queue_.finish(), "clFinish");
    const double wall = secondsSince(start);
    const double gather = deviceSeconds(gather_event_, gather_event_);
    times_.gather += gather;
    times_.local += std::max(0.0, wall - gather);
  }

  void localStepRhs(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                    PotentialEnergy* energy_at_x) override {
    checkSlot(x);
    checkSlot(y);
    if (energy_at_x) *energy_at_x = potential(x, t);
    uploadForcing(t, false);
    const auto start = Clock::now();
    const int launched = enqueueContributions(x, kModeProjection);
    gather_rhs_.bindSlot(6, y, slots_);
    gather_rhs_.set(7, Real(c));
    enqueue(gather_rhs_, &gather_event_);
    readMatrix(rhs_, rhs);  // blocking: everything queued above has completed
    const double wall = secondsSince(start);
    const double local =
        launched > 0 ? deviceSeconds(local_events_[0], local_events_[launched - 1]) : 0.0;
    const double gather = deviceSeconds(gather_event_, gather_event_);
    times_.local += local;
    times_.gather += gather;
    times_.transfer += std::max(0.0, wall - local - gather);
  }

  std::string description() const override {
    return "OpenCL: " + device_.platform_name + " / " + device_.device_name +
           (kDouble ? " (double)" : " (float)");
  }

 private:
  static constexpr bool kDouble = std::is_same<Real, double>::value;
  static constexpr int kElementLocalSize = 256;  // larger groups amortise PoCL's per-group cost
  static constexpr int kReduceLocalSize = 128;
  static constexpr int kMaxReduceGroups = 64;  // per segment
  static constexpr int kMinTermsPerWorkItem = 4;

  static std::size_t bytes(std::size_t count) { return count * sizeof(Real); }

  void checkSlot(int slot) const {
    if (slot < 0 || slot >= static_cast<int>(slots_.size()))
      throw InvalidInputError("OpenCL backend: slot " + std::to_string(slot) +
                              " out of range (have " + std::to_string(slots_.size()) + ")");
  }

  template <typename T>
  cl::Buffer upload(const std::vector<T>& data) {
    // An empty array still gets a one-element buffer: OpenCL has no zero-size buffers.
    static const T placeholder{};
    const T* src = data.empty() ? &placeholder : data.data();
    cl_int err = CL_SUCCESS;
    cl::Buffer buffer(context_, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                      std::max<std::size_t>(data.size(), 1) * sizeof(T), const_cast<T*>(src),
                      &err);
    ocl::check(err, "clCreateBuffer");
    return buffer;
  }

  cl::Buffer zeroBuffer(std::size_t count) {
    cl_int err = CL_SUCCESS;
    cl::Buffer buffer(context_, CL_MEM_READ_WRITE, bytes(std::max<std::size_t>(count, 1)),
                      nullptr, &err);
    ocl::check(err, "clCreateBuffer");
    ocl::check(queue_.enqueueFillBuffer(buffer, Real(0), 0, bytes(std::max<std::size_t>(count, 1))),
               "clEnqueueFillBuffer");
    return buffer;
  }

  void uploadSprings() {
    const std::vector<Spring>& springs = scene_.springs();
    const Eigen::MatrixX3d& rest = scene_.scene().rest_positions;
    std::vector<cl_int> ends;
    std::vector<Real> params;
    ends.reserve(2 * springs.size());
    params.reserve(5 * springs.size());
    for (const Spring& s : springs) {
      ends.push_back(s.a);
      ends.push_back(s.b);
      // Direction for coincident endpoints: the rest direction from b to a, else +x.
      Eigen::Vector3d dir(1.0, 0.0, 0.0);
      if (rest.rows() == n_) {
        const Eigen::Vector3d d = (rest.row(s.a) - rest.row(s.b)).transpose();
        const double len = d.norm();
        if (len > 0.0 && std::isfinite(len)) dir = d / len;
      }
      params.insert(params.end(), {Real(s.rest_length), Real(s.stiffness), Real(dir.x()),
                                   Real(dir.y()), Real(dir.z())});
    }
    spring_ends_ = upload(ends);
    spring_params_ = upload(params);
  }

  void uploadTets() {
    std::vector<cl_int> vertices;
    std::vector<Real> rest;
    for (const TetRest& t : scene_.tets()) {
      vertices.insert(vertices.end(), t.vertices.begin(), t.vertices.end());
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) rest.push_back(Real(t.dm_inverse(i, j)));
      rest.push_back(Real(t.weight));
    }
    tet_vertices_ = upload(vertices);
    tet_rest_ = upload(rest);
  }

  void uploadPins() {
    std::vector<cl_int> vertex;
    std::vector<Real> stiffness;
    for (const Pin& p : scene_.pins()) {
      vertex.push_back(p.vertex);
      stiffness.push_back(Real(p.stiffness));
    }
    pin_vertex_ = upload(vertex);
    pin_stiffness_ = upload(stiffness);
    pin_targets_ = zeroBuffer(3 * std::size_t(num_pins_));
  }

  // External forces and pin targets at time t; uploaded only when t changed and they depend on
  // time (or once, at construction).
  void uploadForcing(double t, bool force) {
    const bool fields = force || (scene_.hasTimeDependentForceFields() && t != fext_time_);
    const bool pins = num_pins_ > 0 && (force || (scene_.hasMovingPins() && t != pins_time_));
    if (!fields && !pins) return;
    const auto start = Clock::now();
    if (fields) {
      scene_.externalForces(t, host_fext_);
      writeMatrixAsync(fext_, host_fext_);
      fext_time_ = t;
    }
    if (pins) {
      scene_.pinTargets(t, host_targets_);
      writeMatrixAsync(pin_targets_, host_targets_);
      pins_time_ = t;
    }
    times_.transfer += secondsSince(start);
  }

  // Non-blocking: `host` is copied to a staging buffer of a small ring first, so the caller may
  // change or free it as soon as we return; the next blocking call of the in-order queue (every
  // read and energy pass ends with one) waits for the transfer, which saves a synchronisation
  // per local/global iteration (solve, write x, then the next local step or energy pass). A
  // staging buffer is refilled only after its previous transfer has completed.
  void writeMatrixAsync(const cl::Buffer& buffer, const Eigen::MatrixX3d& host) {
    const std::size_t count = std::size_t(host.size());
    if (count == 0) return;
    PendingWrite& w = pending_writes_[next_write_];
    next_write_ = (next_write_ + 1) % pending_writes_.size();
    if (w.done()) ocl::check(w.done.wait(), "clWaitForEvents");
    w.data.assign(host.data(), host.data() + count);
    ocl::check(queue_.enqueueWriteBuffer(buffer, CL_FALSE, 0, bytes(count), w.data.data(), nullptr,
                                         &w.done),
               "clEnqueueWriteBuffer");
  }

  void readMatrix(const cl::Buffer& buffer, Eigen::MatrixX3d& host) {
    host.resize(n_, 3);
    const std::size_t count = 3 * std::size_t(n_);
    if (count == 0) return;
    if (kDouble) {
      ocl::check(queue_.enqueueReadBuffer(buffer, CL_TRUE, 0, bytes(count), host.data()),
                 "clEnqueueReadBuffer");
    } else {
      staging_.resize(count);
      ocl::check(queue_.enqueueReadBuffer(buffer, CL_TRUE, 0, bytes(count), staging_.data()),
                 "clEnqueueReadBuffer");
      std::copy(staging_.begin(), staging_.begin() + count, host.data());
    }
  }

  // The first `count` per-group partials to the host: the only wait of an energy pass.
  void readPartials(int count) {
    ocl::check(queue_.enqueueReadBuffer(partials_, CL_TRUE, 0, bytes(std::size_t(count)),
                                        host_partials_.data()),
               "clEnqueueReadBuffer");
  }

  // Partials [first, last) added in group order (a fixed order: deterministic).
  double sumPartials(int first, int last) const {
    double sum = 0.0;
    for (int g = first; g < last; ++g) sum += double(host_partials_[g]);
    return sum;
  }

  // Groups of a reduction segment of `count` terms: fixed by the scene size, so every call adds
  // the same terms in the same order; none for an empty element segment.
  static int reductionGroups(int count, std::size_t local) {
    if (count <= 0) return 0;
    const int per_group = kMinTermsPerWorkItem * int(local);
    return std::clamp((count + per_group - 1) / per_group, 1, kMaxReduceGroups);
  }

  void enqueue(const Launch& launch, cl::Event* event = nullptr) {
    ocl::check(queue_.enqueueNDRangeKernel(launch.kernel, cl::NullRange, launch.global, launch.local,
                                           nullptr, event),
               "clEnqueueNDRangeKernel");
  }

  // Seconds from the start of `first` to the end of `last` on the device (both complete).
  static double deviceSeconds(const cl::Event& first, const cl::Event& last) {
    cl_ulong begin = 0, end = 0;
    ocl::check(first.getProfilingInfo(CL_PROFILING_COMMAND_START, &begin), "clGetEventProfilingInfo");
    ocl::check(last.getProfilingInfo(CL_PROFILING_COMMAND_END, &end), "clGetEventProfilingInfo");
    return end > begin ? double(end - begin) * 1e-9 : 0.0;
  }

  // Queues the element kernels (springs, tets, pins) writing contributions of `mode`; their
  // events go to local_events_. Returns how many were queued.
  int enqueueContributions(int x, int mode) {
    Launch* launches[3] = {mode == kModeForce ? &spring_force_ : &spring_project_,
                           mode == kModeForce ? &tet_force_ : &tet_project_,
                           mode == kModeForce ? &pin_force_ : &pin_project_};
    const int counts[3] = {num_springs_, num_tets_, num_pins_};
    int launched = 0;
    for (int i = 0; i < 3; ++i) {
      if (counts[i] == 0) continue;
      launches[i]->bindSlot(0, x, slots_);
      enqueue(*launches[i], &local_events_[launched++]);
    }
    return launched;
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
    ocl::check(kernel.getWorkGroupInfo(device_.device, CL_KERNEL_WORK_GROUP_SIZE, &limit),
               "clGetKernelWorkGroupInfo");
    std::size_t size = 1;
    while (size * 2 <= std::min(wanted, limit)) size *= 2;
    return size;
  }

  // 1-D launch over `count` items (rounded up to the local size; kernels check the bound).
  Launch elementLaunch(const char* name, int count) {
    Launch l;
    l.kernel = makeKernel(name);
    const std::size_t local = localSize(l.kernel, kElementLocalSize);
    const std::size_t global = (std::size_t(std::max(count, 1)) + local - 1) / local * local;
    l.global = cl::NDRange(global);
    l.local = cl::NDRange(local);
    return l;
  }

  void buildKernels(const ContributionCsr& csr) {
    const cl_int n = n_;
    for (int mode : {kModeProjection, kModeForce}) {
      Launch& s = mode == kModeForce ? spring_force_ : spring_project_;
      s = elementLaunch("spring_contributions", num_springs_);
      s.set(1, n), s.set(2, cl_int(num_springs_)), s.set(3, spring_ends_), s.set(4, spring_params_);
      s.set(5, cl_int(csr.springBase)), s.set(6, cl_int(mode)), s.set(7, contrib_);

      Launch& t = mode == kModeForce ? tet_force_ : tet_project_;
      t = elementLaunch("tet_contributions", num_tets_);
      t.set(1, n), t.set(2, cl_int(num_tets_)), t.set(3, tet_vertices_), t.set(4, tet_rest_);
      t.set(5, cl_int(csr.tetBase)), t.set(6, cl_int(mode)), t.set(7, contrib_);

      Launch& p = mode == kModeForce ? pin_force_ : pin_project_;
      p = elementLaunch("pin_contributions", num_pins_);
      p.set(1, n), p.set(2, cl_int(num_pins_)), p.set(3, pin_vertex_), p.set(4, pin_stiffness_);
      p.set(5, pin_targets_), p.set(6, cl_int(csr.pinBase)), p.set(7, cl_int(mode));
      p.set(8, contrib_);
    }

    combine_ = elementLaunch("combine", 3 * n_);
    combine_.set(0, cl_int(3 * n_));

    gather_rhs_ = elementLaunch("gather_rhs", n_);
    gather_rhs_.set(0, n), gather_rhs_.set(1, offsets_), gather_rhs_.set(2, list_);
    gather_rhs_.set(3, contrib_), gather_rhs_.set(4, masses_), gather_rhs_.set(5, fext_);
    gather_rhs_.set(8, rhs_);
    gather_accel_ = elementLaunch("gather_accelerations", n_);
    gather_accel_.set(0, n), gather_accel_.set(1, offsets_), gather_accel_.set(2, list_);
    gather_accel_.set(3, contrib_), gather_accel_.set(4, masses_), gather_accel_.set(5, fext_);

    // Energy passes: element terms reduced per work-group inside the kernel (energy.cl). Segment
    // group ranges of potential_partials: [springs | tets | pins | vertices].
    potential_.kernel = makeKernel("potential_partials");
    mass_dot_.kernel = makeKernel("mass_dot_partials");
    const std::size_t local = std::min(localSize(potential_.kernel, kReduceLocalSize),
                                       localSize(mass_dot_.kernel, kReduceLocalSize));
    const int counts[4] = {num_springs_, num_tets_, num_pins_, n_};
    energy_segments_[0] = 0;
    for (int s = 0; s < 4; ++s)
      energy_segments_[s + 1] = energy_segments_[s] + reductionGroups(counts[s], local);
    energy_segments_[4] = std::max(energy_segments_[4], energy_segments_[3] + 1);  // n_ == 0
    mass_dot_groups_ = std::max(reductionGroups(n_, local), 1);
    const int max_partials = std::max(energy_segments_[4], mass_dot_groups_);
    partials_ = zeroBuffer(std::size_t(max_partials));
    host_partials_.resize(std::size_t(max_partials));

    potential_.global = cl::NDRange(local * std::size_t(energy_segments_[4]));
    potential_.local = cl::NDRange(local);
    potential_.set(1, n);
    potential_.set(2, cl_int(num_springs_)), potential_.set(3, spring_ends_);
    potential_.set(4, spring_params_);
    potential_.set(5, cl_int(num_tets_)), potential_.set(6, tet_vertices_);
    potential_.set(7, tet_rest_);
    potential_.set(8, cl_int(num_pins_)), potential_.set(9, pin_vertex_);
    potential_.set(10, pin_stiffness_), potential_.set(11, pin_targets_);
    potential_.set(12, fext_);
    const cl_int4 seg_begin = {{energy_segments_[1], energy_segments_[2], energy_segments_[3], 0}};
    potential_.set(13, seg_begin);
    potential_.set(14, partials_);
    potential_.set(15, cl::Local(bytes(local)));

    mass_dot_.global = cl::NDRange(local * std::size_t(mass_dot_groups_));
    mass_dot_.local = cl::NDRange(local);
    mass_dot_.set(0, n), mass_dot_.set(1, masses_);
    mass_dot_.set(4, partials_);
    mass_dot_.set(5, cl::Local(bytes(local)));
  }

  const SceneData& scene_;
  const int n_;
  int num_springs_ = 0, num_tets_ = 0, num_pins_ = 0;
  // First group of each potential_partials segment (springs, tets, pins, vertices), then the
  // launch's group count.
  std::array<int, 5> energy_segments_{};
  int mass_dot_groups_ = 1;

  ocl::SelectedDevice device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  cl::Program program_;

  std::vector<cl::Buffer> slots_;
  cl::Buffer masses_, fext_, rhs_, contrib_, offsets_, list_;
  cl::Buffer spring_ends_, spring_params_, tet_vertices_, tet_rest_;
  cl::Buffer pin_vertex_, pin_stiffness_, pin_targets_;
  cl::Buffer partials_;

  Launch spring_project_, spring_force_, tet_project_, tet_force_, pin_project_, pin_force_;
  Launch potential_;
  cl::Event local_events_[3], gather_event_;
  Launch mass_dot_, combine_, gather_rhs_, gather_accel_;

  double fext_time_ = std::numeric_limits<double>::quiet_NaN();
  double pins_time_ = std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixX3d host_fext_, host_targets_;
  std::vector<Real> staging_;
  struct PendingWrite {
    std::vector<Real> data;
    cl::Event done;
  };
  std::array<PendingWrite, 4> pending_writes_;  // a step writes at most x, v, f_ext, pin targets between waits
  std::size_t next_write_ = 0;
  std::vector<Real> host_partials_;
};

}  // namespace

std::unique_ptr<Backend> makeOpenCLBackend(const SceneData& scene, int num_slots,
                                           const OpenCLOptions& options) {
  if (options.precision == Precision::Float)
    return std::make_unique<OpenCLBackend<float>>(scene, num_slots, options);
  return std::make_unique<OpenCLBackend<double>>(scene, num_slots, options);
}

}  // namespace stabint
