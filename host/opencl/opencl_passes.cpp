// The OpenCL backend's element passes, gathers and reductions, and the global step on the device.
#include "opencl/opencl_backend_class.hpp"

namespace stabint::ocl {

template <typename Real>
double OpenCLBackend<Real>::massDot(int a, int b) {
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

template <typename Real>
PotentialEnergy OpenCLBackend<Real>::potential(int x, double t) {
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
template <typename Real>
void OpenCLBackend<Real>::accelerations(int dst, int x, double t) {
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

template <typename Real>
void OpenCLBackend<Real>::localStepRhs(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                                       PotentialEnergy* energy_at_x) {
  gatheredLocalStep(kPassProjection, gather_rhs_, gather_rhs_args_, x, y, c, t, rhs, energy_at_x);
}

template <typename Real>
void OpenCLBackend<Real>::localStepGradient(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                                            PotentialEnergy* energy_at_x) {
  gather_gradient_.bindSlot(gather_gradient_args_.x, x, slots_);
  gatheredLocalStep(kPassForce, gather_gradient_, gather_gradient_args_, x, y, c, t, gradient, energy_at_x);
}

// A batch's L-BFGS local step: the force pass also writes each element's energy, and the per-scene
// sums run after the gather (gatheredLocalStep), so that the gradient's read is the only wait: no
// second element pass.
// The per-element energies and their sums are those of potentials() (an element's energy does not
// depend on what else its pass writes).
template <typename Real>
void OpenCLBackend<Real>::localStepGradientPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& gradient,
                                                    std::vector<PotentialEnergy>& per_scene,
                                                    const std::vector<char>* running) {
  checkSegmentsFit();
  if (segmentIsWholeScene() || segments_.empty()) {
    Backend::localStepGradientPerScene(x, y, c, t, gradient, per_scene);
    return;
  }
  gather_gradient_.bindSlot(gather_gradient_args_.x, x, slots_);
  gatheredLocalStep(kPassForce, gather_gradient_, gather_gradient_args_, x, y, c, t, gradient, nullptr, &per_scene,
                    running);
}

// The same for a batch's Chebyshev and Anderson: the projection pass writes each element's energy.
template <typename Real>
void OpenCLBackend<Real>::localStepRhsPerScene(int x, int y, double c, double t, Eigen::MatrixX3d& rhs,
                                               std::vector<PotentialEnergy>& per_scene,
                                               const std::vector<char>* running) {
  checkSegmentsFit();
  if (segmentIsWholeScene() || segments_.empty()) {
    Backend::localStepRhsPerScene(x, y, c, t, rhs, per_scene);
    return;
  }
  gatheredLocalStep(kPassProjection, gather_rhs_, gather_rhs_args_, x, y, c, t, rhs, nullptr, &per_scene, running);
}

template <typename Real>
void OpenCLBackend<Real>::setGlobalMatrix(const Eigen::SparseMatrix<double>& laplacian) {
  const auto start = Clock::now();
  if (!cg_)
    cg_ = std::make_unique<ocl::DeviceConjugateGradient<Real>>(context_, device_.device, *device_.profile, queue_, n_,
                                                               masses_);
  cg_->setMatrix(laplacian);
  addDeviceSolverTraffic();
  times_.transfer += secondsSince(start);
}

// localStepRhs without the read of the right-hand side: queued, no wait unless the energy is
// asked for (then the only wait is the read of the energy partials).
template <typename Real>
void OpenCLBackend<Real>::localStep(int x, int y, double c, double t, PotentialEnergy* energy_at_x) {
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

template <typename Real>
int OpenCLBackend<Real>::solveGlobal(double c, int x, int iterations, double tolerance) {
  checkSlot(x);
  if (!cg_) throw Error("OpenCL backend: solveGlobal before setGlobalMatrix");
  const int done = cg_->solve(c, rhs_, slots_[x], iterations, tolerance);
  addDeviceSolverTraffic();
  return done;
}

template <typename Real>
void OpenCLBackend<Real>::addDeviceSolverTraffic() {
  traffic_.to_device += cg_->to_device;
  traffic_.to_host += cg_->to_host;
  traffic_.launches += cg_->launches;
  cg_->to_device = cg_->to_host = cg_->launches = 0;
}

template <typename Real>
template <class GatherArgs>
void OpenCLBackend<Real>::gatheredLocalStep(int flags, Launch& gather, const GatherArgs& args, int x, int y, double c,
                                            double t, Eigen::MatrixX3d& out, PotentialEnergy* energy_at_x,
                                            std::vector<PotentialEnergy>* per_scene, const std::vector<char>* running) {
  checkSlot(x);
  checkSlot(y);
  uploadForcing(t, false);
  const auto start = Clock::now();
  const int pass_flags = flags | (energy_at_x ? kPassEnergy : 0) | (per_scene ? kPassEnergyPerElement : 0);
  // The running segments' elements alone (the others' rows of `out` and sums are then stale).
  const bool skipping = per_scene && running && !energy_at_x && skippingRuns(*running, skip_segments_, skip_runs_);
  bool launched = false;
  if (skipping) {
    for (std::size_t r = 0; r < skip_runs_.size(); ++r) {
      enqueueElementGroups(x, pass_flags, skip_runs_[r].first, skip_runs_[r].second);
      if (r == 0) element_first_event_ = element_event_;
      launched = true;
    }
  } else {
    launched = enqueueElementPass(x, pass_flags);
  }
  gather.bindSlot(args.y, y, slots_);
  gather.set(args.c, Real(c));
  enqueue(gather, &gather_event_);
  if (energy_at_x) readPartials(full_groups_, /*blocking=*/false);
  if (per_scene) {
    segment_energies_.bindSlot(segment_energies_x_, x, slots_);
    enqueue(segment_energies_);
    readSegmentSums(kSegmentEnergies * segments_.size(), 0, /*blocking=*/false);
  }
  readMatrix(rhs_, out);  // blocking: everything queued above has completed
  if (energy_at_x) *energy_at_x = sumEnergies();
  if (per_scene) {
    per_scene->resize(segments_.size());
    for (std::size_t s = 0; s < segments_.size(); ++s)
      if (!skipping || (*running)[s]) (*per_scene)[s] = segmentEnergies(s);
  }
  const double wall = secondsSince(start);
  const double local = launched ? deviceSeconds(element_first_event_, element_event_) : 0.0;
  const double gathered = deviceSeconds(gather_event_, gather_event_);
  times_.local += local;
  times_.gather += gathered;
  times_.transfer += std::max(0.0, wall - local - gathered);
}

// Partials [first, last) added in group order (a fixed order: deterministic).
template <typename Real>
double OpenCLBackend<Real>::sumPartials(int first, int last) const {
  double sum = 0.0;
  for (int g = first; g < last; ++g) sum += double(host_partials_[g]);
  return sum;
}

// The energies of a full element pass, segment by segment.
template <typename Real>
PotentialEnergy OpenCLBackend<Real>::sumEnergies() const {
  PotentialEnergy e;
  for (std::size_t s = 0; s < blocks_.size(); ++s) {
    const double sum = sumPartials(segment_groups_[s], segment_groups_[s + 1]);
    (blocks_[s].block->type->term() == EnergyTerm::Pins ? e.pins : e.internal) += sum;
  }
  e.external = sumPartials(segment_groups_[blocks_.size()], full_groups_);
  return e;
}

template <typename Real>
void OpenCLBackend<Real>::enqueue(const Launch& launch, cl::Event* event) {
  ++traffic_.launches;
  ocl::check(queue_.enqueueNDRangeKernel(launch.kernel, cl::NullRange, launch.global, launch.local, nullptr, event),
             "clEnqueueNDRangeKernel");
}

// Seconds from the start of `first` to the end of `last` on the device (both complete).
template <typename Real>
double OpenCLBackend<Real>::deviceSeconds(const cl::Event& first, const cl::Event& last) {
  cl_ulong begin = 0, end = 0;
  ocl::check(first.getProfilingInfo(CL_PROFILING_COMMAND_START, &begin), "clGetEventProfilingInfo");
  ocl::check(last.getProfilingInfo(CL_PROFILING_COMMAND_END, &end), "clGetEventProfilingInfo");
  return end > begin ? double(end - begin) * 1e-9 : 0.0;
}

// Queues the element pass at positions `x` with `flags`: the element segments, plus the
// vertex segment (external potential) when energies are asked for. Returns false when there
// was nothing to launch (no elements, no energy).
template <typename Real>
bool OpenCLBackend<Real>::enqueueElementPass(int x, int flags) {
  const int groups = (flags & kPassEnergy) ? full_groups_ : segment_groups_[blocks_.size()];
  if (groups == 0) return false;
  enqueueElementGroups(x, flags, 0, groups);
  element_first_event_ = element_event_;
  return true;
}

// Groups [first_group, end_group) of the element pass (not empty): the same work-groups as in the
// whole pass, so each element gives the same results.
template <typename Real>
void OpenCLBackend<Real>::enqueueElementGroups(int x, int flags, int first_group, int end_group) {
  element_pass_.bindSlot(element_args_.x, x, slots_);
  element_pass_.set(element_args_.flags, cl_int(flags));
  if (first_group != element_first_group_) {
    element_pass_.set(element_args_.first_group, cl_int(first_group));
    element_first_group_ = first_group;
  }
  ++traffic_.launches;
  ocl::check(queue_.enqueueNDRangeKernel(element_pass_.kernel, cl::NullRange,
                                         cl::NDRange(element_local_ * std::size_t(end_group - first_group)),
                                         element_pass_.local, nullptr, &element_event_),
             "clEnqueueNDRangeKernel");
}

template class OpenCLBackend<double>;
template class OpenCLBackend<float>;

}  // namespace stabint::ocl
