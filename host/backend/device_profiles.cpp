#include "backend/device_profiles.hpp"

#include "common/text_reader.hpp"  // shown: the name is user text

#include <stabint/errors.hpp>

#include <algorithm>
#include <cctype>
#include <string>
#include <vector>

namespace stabint {
namespace {

// A row of the table and the devices it is for: GPU or not, a vendor phrase (any when none) and a
// model phrase of the device name (any when none). Phrases are whole words of the lower-cased
// name ("a30" is not part of "rtx a3000").
struct Row {
  bool gpu;
  std::vector<const char*> vendors;
  std::vector<const char*> models;
  DeviceProfile profile;
};

constexpr double kNever = DeviceProfile::kNever;

// The GPU rows' Auto costs, measured on an NVIDIA H200 (OpenCL 3.0, driver 580.159; docs/benchmarks.md
// "GPU report", scripts/gpu_report.sh's auto_iteration, scaling_iteration and global_step cases):
// an iteration on the device costs about 60 us at any small size (a BE iteration: 62 us for 81
// particles); the host factor path adds the positions' and right-hand sides' transfers, which
// make a spring cloth (6 springs per particle, 36 ns of CPU work) a tie at every size from 1,225
// to 50,176 particles (0.83-1.40 of the CPU reference), so 40 ns per particle; the device CG adds
// about 12 us per CG iteration (10 iterations: 176-237 us from 425 to 5,000 particles).
constexpr double kGpuLaunchUs = 60.0;
constexpr double kGpuParticleNs = 40.0;
constexpr double kGpuCgIterationUs = 12.0;

// Work-groups on GPUs: 128 work-items (4 NVIDIA warps) for the element pass,
// whose tet and triangle-strain rotations need many registers; 256 on AMD (4 wavefronts of 64).
// Reductions and CG: one row per work-item (no minimum), up to 256 groups of 256 (65,536 rows
// before a work-item takes a second row; every CG group's serial sum of the partials, 256 loads
// by three work-items, bounds the count). scripts/gpu_report.sh's bench-rows compares the rows: on
// the H200 the NVIDIA rows' sizes gave the fastest tet bar iteration (641 us in double, against
// 704-1,010 with the other rows' sizes) and tied on the device CG; measured there, they are
// defaults on other GPUs.
const std::vector<Row>& table() {
  static const std::vector<Row> rows{
      // Any non-GPU device: PoCL's pthread device on the 2-core VM, where these sizes were tuned:
      // large element groups amortise PoCL's per-group cost, 64 groups of 128 keep the reductions'
      // partial sums short. The cross-backend tests (1e-9 in double) run on this row.
      {false, {}, {}, {"cpu", true, 256, 128, 64, 4, true, kNever, kNever, kNever, true}},
      // Data-centre GPUs with fp64 at half the fp32 rate (device names: "NVIDIA H100 80GB HBM3",
      // "Tesla V100-SXM2-16GB", "NVIDIA A100-SXM4-40GB").
      {true,
       {"nvidia"},
       {"h100", "h200", "h800", "gh200", "b100", "b200", "a100", "a800", "a30", "v100", "p100", "titan v"},
       {"nvidia-datacenter-gpu", true, 128, 256, 256, 1, true, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      // GeForce, RTX and Quadro: fp64 at 1/32 (or 1/64) of fp32.
      {true,
       {"nvidia"},
       {},
       {"nvidia-gpu", false, 128, 256, 256, 1, false, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      // Instinct (ROCm names the device by its architecture: "gfx90a:sramecc+:xnack-" is MI200).
      {true,
       {"advanced micro devices", "amd"},
       {"instinct", "gfx906", "gfx908", "gfx90a", "gfx940", "gfx941", "gfx942", "gfx950"},
       {"amd-instinct-gpu", false, 256, 256, 256, 1, true, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      // Radeon: fp64 at 1/16-1/32 of fp32.
      {true,
       {"advanced micro devices", "amd"},
       {},
       {"amd-gpu", false, 256, 256, 256, 1, false, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      {true,
       {"intel"},
       {"data center gpu max"},
       {"intel-datacenter-gpu", false, 128, 128, 256, 1, true, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      // Arc and integrated GPUs: fp64 emulated or missing.
      {true,
       {"intel"},
       {},
       {"intel-gpu", false, 128, 128, 256, 1, false, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
      // Any other GPU: cl_khr_fp64 is trusted (its rate is unknown).
      {true, {}, {}, {"gpu", false, 128, 128, 256, 1, true, kGpuLaunchUs, kGpuParticleNs, kGpuCgIterationUs, false}},
  };
  return rows;
}

// " word word ": lower case, every run of other characters one space, padded, so that a phrase
// " a30 " matches whole words only.
std::string words(const std::string& s) {
  std::string out = " ";
  for (unsigned char c : s) {
    if (std::isalnum(c))
      out += static_cast<char>(std::tolower(c));
    else if (out.back() != ' ')
      out += ' ';
  }
  if (out.back() != ' ') out += ' ';
  return out;
}

bool anyPhrase(const std::vector<const char*>& phrases, const std::string& text_words) {
  if (phrases.empty()) return true;
  return std::any_of(phrases.begin(), phrases.end(),
                     [&](const char* phrase) { return text_words.find(words(phrase)) != std::string::npos; });
}

}  // namespace

const DeviceProfile& deviceProfile(bool gpu, const std::string& vendor, const std::string& device_name) {
  const std::string vendor_words = words(vendor), name_words = words(device_name);
  for (const Row& row : table())
    if (row.gpu == gpu && anyPhrase(row.vendors, vendor_words) && anyPhrase(row.models, name_words)) return row.profile;
  return table().back().profile;  // unreachable: the last GPU row and the first row match anything
}

const DeviceProfile& deviceProfileNamed(const std::string& name) {
  std::string names;
  for (const Row& row : table()) {
    if (name == row.profile.name) return row.profile;
    names += std::string(names.empty() ? "" : ", ") + row.profile.name;
  }
  throw InvalidInputError("no device profile '" + io::shown(name) + "' (STABINT_OPENCL_PROFILE); the rows: " + names);
}

}  // namespace stabint
