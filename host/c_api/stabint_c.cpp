// The C API (include/stabint/stabint_c.h) over the C++ API: errors and statuses, the helpers of
// c_api.hpp, names, scenes, the default options and checkpoints; the simulator is in
// simulator_c.cpp, the batch in batch_c.cpp, the conversions of
// the structs and enums in c_conversions.cpp, guarded() and the handles in c_api.hpp.
#include "c_api/c_api.hpp"

#include <algorithm>
#include <cstring>
#include <string>

namespace stabint::c_api {
namespace {

struct LastError {
  stabint_status status = STABINT_OK;
  std::string message;
  int step = -1;
};
thread_local LastError last_error;

}  // namespace

stabint_status fail(stabint_status status, const char* class_name, const std::string& text, int step) {
  last_error.status = status;
  last_error.message = std::string(class_name) + ": " + text;
  last_error.step = step;
  return status;
}

Eigen::MatrixX3d rowsFrom(Eigen::Index particles, const double* values, size_t count, const char* what) {
  require(values, what);
  const size_t n = static_cast<size_t>(particles);
  if (count != 3 * n) {
    throw ArgumentError{std::string(what) + ": " + std::to_string(count) + " values, " + std::to_string(3 * n) +
                        " expected (3 per particle)"};
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  return Eigen::Map<const RowMajor>(values, particles, 3);
}

std::vector<int> indexList(const int* indices, size_t count) {
  if (count > 0) require(indices, "indices");
  return count > 0 ? std::vector<int>(indices, indices + count) : std::vector<int>{};
}

Eigen::Vector3d vector3(const double* values, const char* what) {
  require(values, what);
  return Eigen::Vector3d(values[0], values[1], values[2]);
}

void copyVector3(const Eigen::Vector3d& v, double* out) {
  for (int k = 0; k < 3; ++k) out[k] = v[k];
}

size_t copyText(const std::string& text, char* out, size_t capacity) {
  if (out != nullptr && capacity > 0) {
    const size_t n = std::min(text.size(), capacity - 1);
    std::memcpy(out, text.data(), n);
    out[n] = '\0';
  }
  return text.size();
}

}  // namespace stabint::c_api

using namespace stabint::c_api;

extern "C" {

const char* stabint_status_name(stabint_status status) {
  switch (status) {
    case STABINT_OK: return "OK";
    case STABINT_ERROR: return "Error";
    case STABINT_INVALID_INPUT: return "InvalidInputError";
    case STABINT_FILE_FORMAT: return "FileFormatError";
    case STABINT_NON_FINITE_STATE: return "NonFiniteStateError";
    case STABINT_ENERGY_LIMIT: return "EnergyLimitError";
    case STABINT_OPENCL: return "OpenCLError";
    case STABINT_NO_OPENCL_DEVICE: return "NoOpenCLDeviceError";
    case STABINT_KERNEL_BUILD: return "KernelBuildError";
    case STABINT_UNSUPPORTED_PRECISION: return "UnsupportedPrecisionError";
    case STABINT_INVALID_ARGUMENT: return "InvalidArgument";
    case STABINT_OUT_OF_MEMORY: return "OutOfMemory";
    case STABINT_INTERNAL: return "InternalError";
    default: break;  // the sentinels and any other int
  }
  return "unknown";
}

int stabint_status_is(stabint_status status, stabint_status base) {
  if (status == base) return 1;
  if (status == STABINT_OK) return 0;
  switch (base) {
    case STABINT_ERROR: return 1;
    case STABINT_NON_FINITE_STATE: return status == STABINT_ENERGY_LIMIT;
    case STABINT_OPENCL:
      return status == STABINT_NO_OPENCL_DEVICE || status == STABINT_KERNEL_BUILD ||
             status == STABINT_UNSUPPORTED_PRECISION;
    default: return 0;
  }
}

const char* stabint_last_error_message(void) { return last_error.message.c_str(); }
stabint_status stabint_last_error_status(void) { return last_error.status; }
int stabint_last_error_step(void) { return last_error.step; }

const char* stabint_integrator_name(stabint_integrator integrator) {
  return nameOf<stabint::Integrator>(integrator, stabint::integratorName);
}

const char* stabint_blend_branch_name(stabint_blend_branch branch) {
  return nameOf<stabint::BlendBranch>(branch, stabint::blendBranchName);
}

stabint_status stabint_scene_create_builtin(const char* name, const char* params_json, stabint_scene** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(name, "name");
    require(out, "out");
    *out = new stabint_scene{stabint::builtinScene(name, params_json ? params_json : "{}")};
  });
}

stabint_status stabint_scene_load(const char* path, stabint_scene** out) {
  return guarded([&] {
    if (out != nullptr) *out = nullptr;  // a failed create leaves no handle behind
    require(path, "path");
    require(out, "out");
    *out = new stabint_scene{stabint::loadSceneFile(path)};
  });
}

void stabint_scene_destroy(stabint_scene* scene) { delete scene; }

int stabint_scene_num_particles(const stabint_scene* scene) { return scene ? scene->scene.numParticles() : -1; }

int stabint_scene_num_triangles(const stabint_scene* scene) {
  return scene ? static_cast<int>(scene->scene.triangles.size()) : -1;
}

stabint_status stabint_scene_copy_triangles(const stabint_scene* scene, int32_t* out, size_t capacity) {
  return guarded([&] {
    require(scene, "scene");
    const auto& triangles = scene->scene.triangles;
    requireCapacity(capacity, 3 * triangles.size(), "triangles");
    if (!triangles.empty()) require(out, "out");
    for (size_t t = 0; t < triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) out[3 * t + k] = triangles[t][k];
    }
  });
}

stabint_status stabint_checkpoint_save(const stabint_checkpoint* checkpoint, const char* path) {
  return saveCheckpoint(checkpoint, path);
}

stabint_status stabint_checkpoint_load(const char* path, stabint_checkpoint** out) { return loadCheckpoint(path, out); }

const void* stabint_checkpoint_data(const stabint_checkpoint* checkpoint, size_t* size) {
  return checkpointData(checkpoint, size);
}

stabint_status stabint_checkpoint_from_bytes(const void* data, size_t size, stabint_checkpoint** out) {
  return checkpointFromBytes(data, size, out);
}

void stabint_checkpoint_destroy(stabint_checkpoint* checkpoint) { delete checkpoint; }

double stabint_checkpoint_time(const stabint_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.time() : kNaN;
}
int stabint_checkpoint_step_count(const stabint_checkpoint* checkpoint) {
  return checkpoint ? checkpoint->checkpoint.stepCount() : -1;
}

}  // extern "C"
