#include "device_profiles.hpp"

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

constexpr int kNever = DeviceProfile::kNever;

// The GPU rows' Auto threshold (not yet measured): a step of the blend pays about 30 launches and
// 16 blocking waits, a few hundred microseconds with a GPU driver, and the factor path still
// solves on the host and copies the right-hand side and the result every iteration. The CPU
// reference's BE step (10 iterations) takes 0.6 ms at 400 particles and 5 ms at 2,500 on the
// 2-core VM (docs/bench_summary.md "Auto backend rule"), so the GPU can only pay from a few
// thousand particles: 4,096 (a 64 x 64 cloth) or 16,384 elements (a 5,000-particle tet bar has
// 23,814). scripts/gpu_report.sh measures the crossing (auto_* and scaling_* cases).
constexpr int kGpuMinParticles = 4096;
constexpr int kGpuMinElements = 16384;

// Work-groups on GPUs (not yet measured): 128 work-items (4 NVIDIA warps) for the element pass,
// whose tet and triangle-strain rotations need many registers; 256 on AMD (4 wavefronts of 64).
// Reductions and CG: one row per work-item (no minimum), up to 256 groups of 256 (65,536 rows
// before a work-item takes a second row; every CG group's serial sum of the partials, 256 loads
// by three work-items, bounds the count). scripts/gpu_report.sh's bench-rows compares the rows.
const std::vector<Row>& table() {
  static const std::vector<Row> rows{
      // Any non-GPU device: PoCL's pthread device on the 2-core VM, where these sizes were tuned:
      // large element groups amortise PoCL's per-group cost, 64 groups of 128 keep the reductions'
      // partial sums short. The cross-backend tests (1e-9 in double) run on this row.
      {false, {}, {}, {"cpu", true, 256, 128, 64, 4, true, kNever, kNever}},
      // Data-centre GPUs with fp64 at half the fp32 rate (device names: "NVIDIA H100 80GB HBM3",
      // "Tesla V100-SXM2-16GB", "NVIDIA A100-SXM4-40GB").
      {true,
       {"nvidia"},
       {"h100", "h200", "h800", "gh200", "b100", "b200", "a100", "a800", "a30", "v100", "p100", "titan v"},
       {"nvidia-datacenter-gpu", false, 128, 256, 256, 1, true, kGpuMinParticles, kGpuMinElements}},
      // GeForce, RTX and Quadro: fp64 at 1/32 (or 1/64) of fp32.
      {true, {"nvidia"}, {}, {"nvidia-gpu", false, 128, 256, 256, 1, false, kGpuMinParticles, kGpuMinElements}},
      // Instinct (ROCm names the device by its architecture: "gfx90a:sramecc+:xnack-" is MI200).
      {true,
       {"advanced micro devices", "amd"},
       {"instinct", "gfx906", "gfx908", "gfx90a", "gfx940", "gfx941", "gfx942", "gfx950"},
       {"amd-instinct-gpu", false, 256, 256, 256, 1, true, kGpuMinParticles, kGpuMinElements}},
      // Radeon: fp64 at 1/16-1/32 of fp32.
      {true,
       {"advanced micro devices", "amd"},
       {},
       {"amd-gpu", false, 256, 256, 256, 1, false, kGpuMinParticles, kGpuMinElements}},
      {true,
       {"intel"},
       {"data center gpu max"},
       {"intel-datacenter-gpu", false, 128, 128, 256, 1, true, kGpuMinParticles, kGpuMinElements}},
      // Arc and integrated GPUs: fp64 emulated or missing.
      {true, {"intel"}, {}, {"intel-gpu", false, 128, 128, 256, 1, false, kGpuMinParticles, kGpuMinElements}},
      // Any other GPU: cl_khr_fp64 is trusted (its rate is unknown).
      {true, {}, {}, {"gpu", false, 128, 128, 256, 1, true, kGpuMinParticles, kGpuMinElements}},
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
  throw InvalidInputError("no device profile '" + name + "' (STABINT_OPENCL_PROFILE); the rows: " + names);
}

}  // namespace stabint
