#pragma once
// Per-device launch sizes and policies as data: one row per class of OpenCL device (the table in
// device_profiles.cpp), picked from the device's type, vendor and name. The OpenCL backend takes
// its work-group sizes and reduction grids from the row; BackendKind::Auto takes the scene size
// from which the device pays (host/driver/backend_choice.cpp). No OpenCL types: the rule of
// Auto needs the table in a build without OpenCL too.
#include <stabint/types.hpp>

#include <limits>

namespace stabint {

/// One class of OpenCL device. Rows not measured on such a device carry defaults from the
/// vendors' tuning guides and say so (`measured` false, docs/benchmarks.md "GPU report").
struct DeviceProfile {
  const char* name;  ///< "cpu", "nvidia-gpu", ...: shown in the backend description
  bool measured;     ///< the sizes below were measured on such a device

  /// Work-group size of the element pass, the gathers and the vector operations (clamped to what
  /// the device allows for each kernel, rounded down to a power of two).
  int element_local_size;
  /// Work-group size of the mass-dot reduction and the device CG (a power of two).
  int reduce_local_size;
  /// At most this many groups in a reduction or CG grid: every CG kernel re-adds all the previous
  /// kernel's partials serially in each group, so more groups cost that sum.
  int max_reduce_groups;
  /// Fewer groups until each work-item has this many rows or terms (then the cap above).
  int min_terms_per_work_item;

  /// cl_khr_fp64 at a useful rate (at least a quarter of fp32). False on consumer GPUs, whose
  /// fp64 runs at 1/32-1/64 rate: Auto does not take them for Precision::Double, and an explicit
  /// OpenCL backend in double says so in its description.
  bool fast_fp64;

  /// BackendKind::Auto's estimate of one local/global iteration on this device beyond what the
  /// CPU reference pays too (host/driver/backend_choice.cpp): a fixed cost for the launches and
  /// blocking waits, plus, with the host factor, the transfer of every particle's position and
  /// right-hand side, or, with the device CG, each CG iteration's launches. Infinity: never taken.
  double auto_launch_us;
  double auto_particle_ns;
  double auto_cg_iteration_us;

  /// Work-group sums (kernels/reduce.cl) by one work-item instead of a tree of barriers: a CPU
  /// device runs a group's work-items as one loop per region between barriers, so each tree level
  /// costs a loop over the whole group (on PoCL the tree doubled an element pass that sums energies).
  bool serial_group_sum;
  static constexpr double kNever = std::numeric_limits<double>::infinity();
};

/// The row for a device: its type (GPU or not), CL_DEVICE_VENDOR and CL_DEVICE_NAME. Every
/// device gets a row (the last ones match any GPU and any other device).
const DeviceProfile& deviceProfile(bool gpu, const std::string& vendor, const std::string& device_name);
inline const DeviceProfile& deviceProfile(const OpenCLDeviceInfo& d) {
  return deviceProfile(d.gpu, d.vendor, d.device_name);
}

/// The row named `name` ("nvidia-gpu"); throws InvalidInputError naming the rows when none is.
/// For STABINT_OPENCL_PROFILE, which makes a backend use another row's launch sizes (to check a
/// GPU row's sizes on PoCL, or to compare rows on one device).
const DeviceProfile& deviceProfileNamed(const std::string& name);

}  // namespace stabint
