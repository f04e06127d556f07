// The OpenCL backend's per-scene sums for a batch (kernels/segments.cl).
#include "opencl/opencl_backend_class.hpp"

#include <algorithm>
#include <utility>

namespace stabint::ocl {

template <typename Real>
void OpenCLBackend<Real>::setSegments(const std::vector<SceneSegment>& segments) {
  const std::string misfit = segmentsMisfit(segments);
  if (!misfit.empty()) throw InvalidInputError(misfit);
  segments_ = segments;
  segments_misfit_.clear();
  uploadSegmentTable();
}

// Whether the one segment is the whole scene (a batch of one): its sums then take the
// single-scene kernels, whose order of additions differs from the segments' kernels, so that a
// batch of one is its Simulator bit for bit.
template <typename Real>
bool OpenCLBackend<Real>::segmentIsWholeScene() const {
  if (segments_.size() != 1 || segments_[0].first_particle != 0 || segments_[0].num_particles != n_) return false;
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    if (segments_[0].first_element[b] != 0 || segments_[0].num_elements[b] != blocks_[b].block->count) return false;
  return true;
}

// One launch and one read of one real per scene.
template <typename Real>
void OpenCLBackend<Real>::massDots(int a, int b, std::vector<double>& out) {
  checkSegmentsFit();
  if (segmentIsWholeScene()) {
    out.assign(1, massDot(a, b));
    return;
  }
  checkSlot(a);
  checkSlot(b);
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
template <typename Real>
void OpenCLBackend<Real>::potentials(int x, double t, std::vector<PotentialEnergy>& out,
                                     const std::vector<char>* which) {
  checkSegmentsFit();
  if (segmentIsWholeScene()) {
    out.assign(1, potential(x, t));
    return;
  }
  if (which && skippingRuns(*which, skip_segments_, skip_runs_)) {  // those alone, the others' entries kept
    potentialsOf(skip_segments_, x, t, some_potentials_);
    out.resize(segments_.size());
    for (std::size_t i = 0; i < skip_segments_.size(); ++i) out[std::size_t(skip_segments_[i])] = some_potentials_[i];
    return;
  }
  checkSlot(x);
  uploadForcing(t, false);
  const auto start = Clock::now();
  out.assign(segments_.size(), PotentialEnergy{});
  if (!segments_.empty()) {
    enqueueElementPass(x, kPassEnergyPerElement);
    segment_energies_.bindSlot(segment_energies_x_, x, slots_);
    enqueue(segment_energies_);
    readSegmentSums(kSegmentEnergies * segments_.size());
    for (std::size_t s = 0; s < segments_.size(); ++s) out[s] = segmentEnergies(s);
  }
  times_.energy += secondsSince(start);
}

template <typename Real>
PotentialEnergy OpenCLBackend<Real>::potentialOf(int segment, int x, double t) {
  std::vector<PotentialEnergy> out;
  potentialsOf({segment}, x, t, out);
  return out[0];
}

namespace {

// [first, end) ranges, sorted and merged where they overlap or touch.
std::vector<std::pair<int, int>> mergedRanges(std::vector<std::pair<int, int>> ranges) {
  std::sort(ranges.begin(), ranges.end());
  std::vector<std::pair<int, int>> merged;
  for (const auto& r : ranges) {
    if (!merged.empty() && r.first <= merged.back().second)
      merged.back().second = std::max(merged.back().second, r.second);
    else
      merged.push_back(r);
  }
  return merged;
}

}  // namespace

template <typename Real>
std::vector<std::pair<int, int>> OpenCLBackend<Real>::elementGroupRuns(const std::vector<int>& segments) const {
  const int local = int(element_local_);
  std::vector<std::pair<int, int>> groups;
  for (std::size_t b = 0; b < blocks_.size(); ++b)
    for (int segment : segments) {
      const SceneSegment& seg = segments_[std::size_t(segment)];
      if (seg.num_elements[b] == 0) continue;
      groups.emplace_back(segment_groups_[b] + seg.first_element[b] / local,
                          segment_groups_[b] + (seg.first_element[b] + seg.num_elements[b] + local - 1) / local);
    }
  return mergedRanges(std::move(groups));
}

template <typename Real>
bool OpenCLBackend<Real>::skippingRuns(const std::vector<char>& which, std::vector<int>& segments,
                                       std::vector<std::pair<int, int>>& runs) const {
  segments.clear();
  runs.clear();
  for (std::size_t s = 0; s < segments_.size(); ++s)
    if (which[s]) segments.push_back(int(s));
  if (segments.size() == segments_.size()) return false;
  runs = elementGroupRuns(segments);
  int groups = 0;
  for (const auto& [first, end] : runs) groups += end - first;
  // Few launches that leave a quarter of the work or more.
  if (runs.size() <= kMostSkippingLaunches && 4 * groups <= 3 * segment_groups_[blocks_.size()]) return true;
  runs.clear();
  return false;
}

// Some scenes' part of potentials(), bit for bit: the element pass over the groups that hold those
// segments' elements (elementGroupRuns: a group shared with a neighbour computes the neighbour's
// too, with the same values: each element's energy is its own), then segment_energies over the
// work-groups that hold the segments' work-items, with potentials' work-group size (the same
// compiled kernel, each work-item summing its own segment), and one read of the sums from the
// first segment's to the last's: one wait for all. Adjacent groups go in one launch, so every
// scene at once is the whole pass. The other items of those groups sum their segments from
// energies that may be stale: those sums are not read.
template <typename Real>
void OpenCLBackend<Real>::potentialsOf(const std::vector<int>& segments, int x, double t,
                                       std::vector<PotentialEnergy>& out) {
  checkSegmentsFit();
  for (int segment : segments)
    if (segment < 0 || segment >= int(segments_.size()))
      throw InvalidInputError("OpenCL backend: segment " + std::to_string(segment) + " of " +
                              std::to_string(segments_.size()));
  out.clear();
  if (segments.empty()) return;
  if (segmentIsWholeScene()) {
    out.assign(segments.size(), potential(x, t));
    return;
  }
  checkSlot(x);
  uploadForcing(t, false);
  const auto start = Clock::now();
  for (const auto& [first, end] : elementGroupRuns(segments))
    enqueueElementGroups(x, kPassEnergyPerElement, first, end);
  segment_energies_.bindSlot(segment_energies_x_, x, slots_);
  const int group = int(segment_energies_.local[0]);
  std::vector<std::pair<int, int>> sums;
  for (int segment : segments) sums.emplace_back(segment / group, segment / group + 1);
  for (const auto& [first, end] : mergedRanges(std::move(sums))) {
    ++traffic_.launches;
    ocl::check(queue_.enqueueNDRangeKernel(segment_energies_.kernel, cl::NDRange(std::size_t(first * group)),
                                           cl::NDRange(std::size_t((end - first) * group)), segment_energies_.local),
               "clEnqueueNDRangeKernel");
  }
  const auto [lowest, highest] = std::minmax_element(segments.begin(), segments.end());
  readSegmentSums(kSegmentEnergies * std::size_t(*highest - *lowest + 1), kSegmentEnergies * std::size_t(*lowest));
  for (int segment : segments) out.push_back(segmentEnergies(std::size_t(segment)));
  times_.energy += secondsSince(start);
}

template <typename Real>
PotentialEnergy OpenCLBackend<Real>::segmentEnergies(std::size_t s) const {
  const Real* sums = host_segment_sums_.data() + kSegmentEnergies * s;
  PotentialEnergy e;
  e.internal = double(sums[kSegmentInternal]);
  e.pins = double(sums[kSegmentPins]);
  e.external = double(sums[kSegmentExternal]);
  return e;
}

// The kernels index buffers with the table, so a table that does not fit this scene is refused
// rather than read out of bounds on the device: why it does not fit, or "".
template <typename Real>
std::string OpenCLBackend<Real>::segmentsMisfit(const std::vector<SceneSegment>& segments) const {
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
template <typename Real>
void OpenCLBackend<Real>::checkSegmentsFit() const {
  if (!segments_misfit_.empty()) throw InvalidInputError(segments_misfit_ + " (setSegments after setPins)");
}

// The segment table of kernels/segments.cl for the current element layout: per segment its
// particle range, then per block the range of its elements' energies, which element_pass
// writes at the element's global id (block b's element e at segment_groups_[b] groups + e).
// Built again by buildKernels when the blocks change (elementsChanged).
template <typename Real>
void OpenCLBackend<Real>::uploadSegmentTable() {
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

template class OpenCLBackend<double>;
template class OpenCLBackend<float>;

}  // namespace stabint::ocl
