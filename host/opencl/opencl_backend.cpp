#include "opencl/opencl_backend_class.hpp"

namespace stabint {
namespace ocl {

// The element blocks and contribution lists were rebuilt (grab, release): upload them anew and
// rebind the kernels (the program stays unless an element type appeared, see programTypes).
template <typename Real>
void OpenCLBackend<Real>::elementsChanged() {
  ocl::check(queue_.finish(), "clFinish");
  uploadElements();
  buildKernels();
}

// The device, the precision (with a warning where fp64 is slow: the caller asked for double
// explicitly, Auto does not pick such a device for it) and the row of launch sizes.
template <typename Real>
std::string OpenCLBackend<Real>::description() const {
  const DeviceProfile& profile = *device_.profile;
  return "OpenCL: " + device_.platform_name + " / " + device_.device_name + (kDouble ? " (double)" : " (float)") +
         " [device profile " + profile.name + (profile.measured ? "" : ", not yet measured") +
         (kDouble && !profile.fast_fp64 ? "; slow fp64 on this GPU: Precision::Float is much faster" : "") + "]";
}

template <typename Real>
cl::Kernel OpenCLBackend<Real>::makeKernel(const char* name) {
  cl_int err = CL_SUCCESS;
  cl::Kernel kernel(program_, name, &err);
  ocl::check(err, "clCreateKernel");
  return kernel;
}

// Largest power of two <= min(wanted, what the device allows for this kernel).
template <typename Real>
std::size_t OpenCLBackend<Real>::localSize(const cl::Kernel& kernel, std::size_t wanted) {
  std::size_t limit = 0;
  ocl::check(kernel.getWorkGroupInfo(device_.device, CL_KERNEL_WORK_GROUP_SIZE, &limit), "clGetKernelWorkGroupInfo");
  std::size_t size = 1;
  while (size * 2 <= std::min(wanted, limit)) size *= 2;
  return size;
}

// 1-D launch over `count` items (rounded up to the local size; kernels check the bound).
template <typename Real>
Launch OpenCLBackend<Real>::elementLaunch(const char* name, int count) {
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
template <typename Real>
int OpenCLBackend<Real>::reductionGroups(int count, std::size_t local) const {
  const int per_group = device_.profile->min_terms_per_work_item * int(local);
  return std::clamp((count + per_group - 1) / per_group, 1, device_.profile->max_reduce_groups);
}

// The element types the program is built for: those the scene has, and pins always (a grab
// adds them to a scene without pins; they cost the program nothing), so that a spring cloth
// does not compile the tet and triangle-strain rotations.
template <typename Real>
std::vector<const ElementType*> OpenCLBackend<Real>::programTypes() const {
  std::vector<const ElementType*> types;
  for (const DeviceBlock& d : blocks_)
    if (d.block->count > 0 || d.block->type->term() == EnergyTerm::Pins) types.push_back(d.block->type);
  return types;
}

// The element program for the current types (the process-wide cache makes a repeated set free).
template <typename Real>
void OpenCLBackend<Real>::useProgramFor(const std::vector<const ElementType*>& types) {
  if (program_() != nullptr && types == program_types_) return;
  // By the device's row, so that a GPU row forced on PoCL (STABINT_OPENCL_PROFILE) checks the
  // GPUs' tree there.
  std::string options = ocl::programOptions(kDouble ? Precision::Double : Precision::Float);
  if (device_.profile->serial_group_sum) options += " -DSTABINT_GROUP_SUM_SERIAL";
  program_ = ocl::cachedProgram(context_, device_.device, ocl::elementProgramSource(types), options);
  program_types_ = types;
}

// Per-element data of the blocks that are new or were rebuilt, and the contribution lists; the
// params follow in uploadForcing.
template <typename Real>
void OpenCLBackend<Real>::uploadElements() {
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

template <typename Real>
void OpenCLBackend<Real>::buildKernels() {
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
  element_args_.first_group = element_pass_.add(cl_int(0));
  element_first_group_ = 0;
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

template class OpenCLBackend<double>;
template class OpenCLBackend<float>;

}  // namespace ocl

std::unique_ptr<Backend> makeOpenCLBackend(const SceneData& scene, const Forcing& forcing, int num_slots,
                                           const OpenCLOptions& options) {
  if (options.precision == Precision::Float)
    return std::make_unique<ocl::OpenCLBackend<float>>(scene, forcing, num_slots, options);
  return std::make_unique<ocl::OpenCLBackend<double>>(scene, forcing, num_slots, options);
}

}  // namespace stabint
