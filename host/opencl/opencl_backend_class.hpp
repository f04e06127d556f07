#pragma once
// The OpenCL backend's class, shared by its four files: opencl_backend.cpp (setup: the program,
// kernels and element data), opencl_transfers.cpp (slots, host copies, the forcing),
// opencl_passes.cpp (element passes, reductions, the device CG) and opencl_segments.cpp (a
// batch's per-scene sums). Instantiated for double and float in each of them.
#include "opencl/opencl_backend.hpp"
#include "opencl/cl_runtime.hpp"
#include "opencl/device_solver.hpp"
#include "opencl/element_program.hpp"
#include "scene/scene_data.hpp"
#include "scene/scene_view.hpp"

#include <stabint/errors.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

namespace stabint::ocl {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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
  OpenCLBackend(const SceneData& scene, const Forcing& forcing, int num_slots, const OpenCLOptions& options)
      : scene_(scene), forcing_(forcing), running_(scene, forcing), n_(scene.numParticles()) {
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

  void elementsChanged() override;

  void write(int slot, const Eigen::MatrixX3d& host) override;

  void read(int slot, Eigen::MatrixX3d& host) override;

  void readBoth(int slot_a, Eigen::MatrixX3d& a, int slot_b, Eigen::MatrixX3d& b) override;

  void roundToStorage(Eigen::MatrixX3d& host) const override {
    if (!kDouble) host = host.cast<Real>().template cast<double>();
  }

  bool writesRows() const override { return true; }

  void writeRows(int slot, int first, const Eigen::MatrixX3d& rows) override;

  void copy(int dst, int src) override;

  void combine(int dst, double a, int x, double b, int y) override;

  double massDot(int a, int b) override;

  PotentialEnergy potential(int x, double t) override;

  void accelerations(int dst, int x, double t) override;

  void localStepRhs(int x, int y, double c, double t, Eigen::MatrixX3d& rhs, PotentialEnergy* energy_at_x) override;

  void localStepGradient(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                         PotentialEnergy* energy_at_x) override;

  // ---- the global step on the device (GlobalSolve::ConjugateGradient, device_solver.hpp) ----
  bool solvesGlobalSystem() const override { return true; }

  void setGlobalMatrix(const Eigen::SparseMatrix<double>& laplacian) override;

  void localStep(int x, int y, double c, double t, PotentialEnergy* energy_at_x) override;

  int solveGlobal(double c, int x, int iterations, double tolerance) override;

  // ---- per-scene results of a batch (kernels/segments.cl) ----------------------------------
  bool computesPerScene() const override { return true; }

  void setSegments(const std::vector<SceneSegment>& segments) override;

  void massDots(int a, int b, std::vector<double>& out) override;

  // With `which`: the flagged segments alone where skippingRuns allows (potentialsOf), else every
  // segment in one launch.
  void potentials(int x, double t, std::vector<PotentialEnergy>& out, const std::vector<char>* which) override;

  // With `running`: the running segments' work-groups alone where skippingRuns allows
  // (gatheredLocalStep), else every segment's in one launch.
  void localStepGradientPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                                 std::vector<PotentialEnergy>& per_scene, const std::vector<char>* running) override;
  void localStepRhsPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                            std::vector<PotentialEnergy>& per_scene, const std::vector<char>* running) override;

  PotentialEnergy potentialOf(int segment, int x, double t) override;
  void potentialsOf(const std::vector<int>& segments, int x, double t, std::vector<PotentialEnergy>& out) override;

  void synchronize() override { ocl::check(queue_.finish(), "clFinish"); }

  std::string description() const override;

 private:
  static constexpr bool kDouble = std::is_same<Real, double>::value;

  // An element block on the device; the params of a time-dependent type are rewritten whenever
  // the time or the forcing (Forcing::version) changes.
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

  cl::Buffer zeroBuffer(std::size_t count);

  void uploadForcing(double t, bool force);

  void writeAsync(const cl::Buffer& buffer, const double* host, std::size_t count, std::size_t offset = 0);

  bool uploadChangedParams(DeviceBlock& d);

  struct PendingWrite;
  PendingWrite& nextStaging();

  // The element pass with `flags` (plus the energy when asked for), then `gather` over its
  // contributions into rhs_, read back to `out`: localStepRhs and localStepGradient. With
  // `per_scene` (a batch's: localStepGradientPerScene, localStepRhsPerScene) the pass also writes
  // each element's energy and the per-scene sums follow the gather, read before the same wait into
  // *per_scene (one per segment). With `running` as well, the pass covers the running segments'
  // elements alone where that takes few launches (elementGroupRuns), and only their entries of
  // *per_scene are written.
  template <class GatherArgs>
  void gatheredLocalStep(int flags, Launch& gather, const GatherArgs& args, int x, int y, double c, double t,
                         Eigen::MatrixX3d& out, PotentialEnergy* energy_at_x,
                         std::vector<PotentialEnergy>* per_scene = nullptr, const std::vector<char>* running = nullptr);

  void readMatrix(const cl::Buffer& buffer, Eigen::MatrixX3d& host);

  void readMatrices(const cl::Buffer& buffer_a, Eigen::MatrixX3d& a, const cl::Buffer& buffer_b, Eigen::MatrixX3d& b);

  void readPartials(int count, bool blocking = true);

  void readSegmentSums(std::size_t count, std::size_t first = 0, bool blocking = true);

  std::string segmentsMisfit(const std::vector<SceneSegment>& segments) const;

  void checkSegmentsFit() const;
  bool segmentIsWholeScene() const;

  void uploadSegmentTable();

  double sumPartials(int first, int last) const;

  PotentialEnergy sumEnergies() const;
  // Scene s's energies as segment_energies left them in host_segment_sums_.
  PotentialEnergy segmentEnergies(std::size_t s) const;

  void enqueue(const Launch& launch, cl::Event* event = nullptr);

  static double deviceSeconds(const cl::Event& first, const cl::Event& last);

  bool enqueueElementPass(int x, int flags);

  void enqueueElementGroups(int x, int flags, int first_group, int end_group);

  // The element pass's groups that hold the elements of `segments`, merged into runs
  // [first, end) of adjacent groups (a group shared with a neighbour computes its elements too,
  // with the same values).
  std::vector<std::pair<int, int>> elementGroupRuns(const std::vector<int>& segments) const;
  // The segments flagged in `which`, when they are not all of them, their elements take at most
  // kMostSkippingLaunches launches (each launch costs more than a small scene's elements) and
  // leave a quarter of the element groups or more (else one launch of the whole pass is
  // cheaper); else empty `runs` and false.
  static constexpr std::size_t kMostSkippingLaunches = 8;
  bool skippingRuns(const std::vector<char>& which, std::vector<int>& segments,
                    std::vector<std::pair<int, int>>& runs) const;

  cl::Kernel makeKernel(const char* name);

  std::size_t localSize(const cl::Kernel& kernel, std::size_t wanted);

  Launch elementLaunch(const char* name, int count);

  int reductionGroups(int count, std::size_t local) const;

  std::vector<const ElementType*> programTypes() const;

  void useProgramFor(const std::vector<const ElementType*>& types);

  void uploadElements();

  void buildKernels();

  const SceneData& scene_;
  const Forcing& forcing_;
  const SceneView running_;  // what the element types read
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
    cl_uint x, flags, first_group;
  } element_args_{};
  int element_first_group_ = 0;  // the value element_pass_'s first_group argument holds
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
  cl::Event element_first_event_;  // the first launch of the last element pass (several: skipping)
  // skippingRuns' results and potentials() of some segments, reused (no allocation per pass).
  std::vector<int> skip_segments_;
  std::vector<std::pair<int, int>> skip_runs_;
  std::vector<PotentialEnergy> some_potentials_;

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
  void addDeviceSolverTraffic();                            // cg_'s counts into traffic_
};

extern template class OpenCLBackend<double>;
extern template class OpenCLBackend<float>;

}  // namespace stabint::ocl
