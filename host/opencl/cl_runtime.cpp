#include "opencl/cl_runtime.hpp"

#include "common/text_reader.hpp"  // shown: the selectors are user text
#include "common/kernel_constants.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <tuple>
#include <vector>

namespace stabint {
namespace ocl {

const char* errorName(cl_int code) {
  switch (code) {
#define STABINT_CL_ERROR(name) \
  case name: return #name;
    STABINT_CL_ERROR(CL_SUCCESS)
    STABINT_CL_ERROR(CL_DEVICE_NOT_FOUND)
    STABINT_CL_ERROR(CL_DEVICE_NOT_AVAILABLE)
    STABINT_CL_ERROR(CL_COMPILER_NOT_AVAILABLE)
    STABINT_CL_ERROR(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    STABINT_CL_ERROR(CL_OUT_OF_RESOURCES)
    STABINT_CL_ERROR(CL_OUT_OF_HOST_MEMORY)
    STABINT_CL_ERROR(CL_PROFILING_INFO_NOT_AVAILABLE)
    STABINT_CL_ERROR(CL_MEM_COPY_OVERLAP)
    STABINT_CL_ERROR(CL_IMAGE_FORMAT_MISMATCH)
    STABINT_CL_ERROR(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    STABINT_CL_ERROR(CL_BUILD_PROGRAM_FAILURE)
    STABINT_CL_ERROR(CL_MAP_FAILURE)
    STABINT_CL_ERROR(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    STABINT_CL_ERROR(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    STABINT_CL_ERROR(CL_COMPILE_PROGRAM_FAILURE)
    STABINT_CL_ERROR(CL_LINKER_NOT_AVAILABLE)
    STABINT_CL_ERROR(CL_LINK_PROGRAM_FAILURE)
    STABINT_CL_ERROR(CL_DEVICE_PARTITION_FAILED)
    STABINT_CL_ERROR(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    STABINT_CL_ERROR(CL_INVALID_VALUE)
    STABINT_CL_ERROR(CL_INVALID_DEVICE_TYPE)
    STABINT_CL_ERROR(CL_INVALID_PLATFORM)
    STABINT_CL_ERROR(CL_INVALID_DEVICE)
    STABINT_CL_ERROR(CL_INVALID_CONTEXT)
    STABINT_CL_ERROR(CL_INVALID_QUEUE_PROPERTIES)
    STABINT_CL_ERROR(CL_INVALID_COMMAND_QUEUE)
    STABINT_CL_ERROR(CL_INVALID_HOST_PTR)
    STABINT_CL_ERROR(CL_INVALID_MEM_OBJECT)
    STABINT_CL_ERROR(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    STABINT_CL_ERROR(CL_INVALID_IMAGE_SIZE)
    STABINT_CL_ERROR(CL_INVALID_SAMPLER)
    STABINT_CL_ERROR(CL_INVALID_BINARY)
    STABINT_CL_ERROR(CL_INVALID_BUILD_OPTIONS)
    STABINT_CL_ERROR(CL_INVALID_PROGRAM)
    STABINT_CL_ERROR(CL_INVALID_PROGRAM_EXECUTABLE)
    STABINT_CL_ERROR(CL_INVALID_KERNEL_NAME)
    STABINT_CL_ERROR(CL_INVALID_KERNEL_DEFINITION)
    STABINT_CL_ERROR(CL_INVALID_KERNEL)
    STABINT_CL_ERROR(CL_INVALID_ARG_INDEX)
    STABINT_CL_ERROR(CL_INVALID_ARG_VALUE)
    STABINT_CL_ERROR(CL_INVALID_ARG_SIZE)
    STABINT_CL_ERROR(CL_INVALID_KERNEL_ARGS)
    STABINT_CL_ERROR(CL_INVALID_WORK_DIMENSION)
    STABINT_CL_ERROR(CL_INVALID_WORK_GROUP_SIZE)
    STABINT_CL_ERROR(CL_INVALID_WORK_ITEM_SIZE)
    STABINT_CL_ERROR(CL_INVALID_GLOBAL_OFFSET)
    STABINT_CL_ERROR(CL_INVALID_EVENT_WAIT_LIST)
    STABINT_CL_ERROR(CL_INVALID_EVENT)
    STABINT_CL_ERROR(CL_INVALID_OPERATION)
    STABINT_CL_ERROR(CL_INVALID_GL_OBJECT)
    STABINT_CL_ERROR(CL_INVALID_BUFFER_SIZE)
    STABINT_CL_ERROR(CL_INVALID_MIP_LEVEL)
    STABINT_CL_ERROR(CL_INVALID_GLOBAL_WORK_SIZE)
    STABINT_CL_ERROR(CL_INVALID_PROPERTY)
    STABINT_CL_ERROR(CL_INVALID_IMAGE_DESCRIPTOR)
    STABINT_CL_ERROR(CL_INVALID_COMPILER_OPTIONS)
    STABINT_CL_ERROR(CL_INVALID_LINKER_OPTIONS)
    STABINT_CL_ERROR(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef STABINT_CL_ERROR
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return "CL_UNKNOWN_ERROR";
  }
}

void throwError(cl_int code, const char* call) {
  std::ostringstream msg;
  msg << "OpenCL: " << call << " failed: " << errorName(code) << " (" << code << ")";
  throw OpenCLError(msg.str());
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string trimmed(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

// Info strings from the C++ bindings may carry the terminating NUL; names are shown to users.
std::string platformName(const cl::Platform& p) {
  std::string name;
  check(p.getInfo(CL_PLATFORM_NAME, &name), "clGetPlatformInfo(CL_PLATFORM_NAME)");
  return trimmed(std::string(name.c_str()));
}

std::string deviceName(const cl::Device& d) {
  std::string name;
  check(d.getInfo(CL_DEVICE_NAME, &name), "clGetDeviceInfo(CL_DEVICE_NAME)");
  return trimmed(std::string(name.c_str()));
}

std::string deviceVendor(const cl::Device& d) {
  std::string vendor;
  check(d.getInfo(CL_DEVICE_VENDOR, &vendor), "clGetDeviceInfo(CL_DEVICE_VENDOR)");
  return trimmed(std::string(vendor.c_str()));
}

bool deviceIsGpu(const cl::Device& d) {
  cl_device_type type = 0;
  return d.getInfo(CL_DEVICE_TYPE, &type) == CL_SUCCESS && (type & CL_DEVICE_TYPE_GPU) != 0;
}

bool deviceHasFp64(const cl::Device& d) {
  std::string extensions;
  check(d.getInfo(CL_DEVICE_EXTENSIONS, &extensions), "clGetDeviceInfo(CL_DEVICE_EXTENSIONS)");
  return extensions.find("cl_khr_fp64") != std::string::npos;
}

// An empty or missing platform list is not an error for listing; the loader reports it as
// CL_PLATFORM_NOT_FOUND_KHR (-1001).
std::vector<cl::Platform> platformsOrEmpty() {
  std::vector<cl::Platform> platforms;
  const cl_int err = cl::Platform::get(&platforms);
  if (err == -1001 /* CL_PLATFORM_NOT_FOUND_KHR */ || err == CL_INVALID_VALUE) return {};
  check(err, "clGetPlatformIDs");
  return platforms;
}

std::vector<cl::Device> devicesOrEmpty(const cl::Platform& platform) {
  std::vector<cl::Device> devices;
  const cl_int err = platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
  if (err == CL_DEVICE_NOT_FOUND) return {};
  check(err, "clGetDeviceIDs");
  return devices;
}

bool isIndex(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

bool matches(const std::string& selector, int index, const std::string& name) {
  if (selector.empty()) return true;
  if (isIndex(selector)) return std::atoi(selector.c_str()) == index;
  return lower(name).find(lower(selector)) != std::string::npos;
}

// Device discovery (clGetPlatformIDs, clGetDeviceIDs, the info queries) is serialized for the
// whole process: the ICD loader and PoCL initialise themselves on the first call and are not
// safe against two threads doing that at once (two simulators built at the same moment crashed
// inside PoCL, or one of them saw no platform and reported NoOpenCLDeviceError). Discovery is
// cheap after the first call, so one lock costs nothing measurable.
std::mutex& discoveryMutex() {
  static std::mutex* m = new std::mutex();  // never destroyed, like the caches below
  return *m;
}

std::string selectorFrom(const std::string& option, const char* env_var) {
  if (!option.empty()) return option;
  const char* env = std::getenv(env_var);
  return env ? trimmed(env) : std::string();
}

}  // namespace

SelectedDevice selectDevice(const OpenCLOptions& options) {
  const std::string platform_sel = selectorFrom(options.platform, "STABINT_OPENCL_PLATFORM");
  const std::string device_sel = selectorFrom(options.device, "STABINT_OPENCL_DEVICE");

  std::lock_guard<std::mutex> lock(discoveryMutex());
  const std::vector<cl::Platform> platforms = platformsOrEmpty();
  if (platforms.empty())
    throw NoOpenCLDeviceError(
        "OpenCL: no OpenCL platform found (no ICD driver installed or visible to the loader); "
        "install an OpenCL driver such as pocl-opencl-icd, or use the CPU reference backend");

  std::ostringstream available;
  for (int pi = 0; pi < static_cast<int>(platforms.size()); ++pi) {
    const std::string pname = platformName(platforms[pi]);
    const std::vector<cl::Device> devices = devicesOrEmpty(platforms[pi]);
    for (int di = 0; di < static_cast<int>(devices.size()); ++di) {
      const std::string dname = deviceName(devices[di]);
      available << "\n  platform " << pi << " '" << pname << "', device " << di << " '" << dname << "'";
      if (!matches(platform_sel, pi, pname) || !matches(device_sel, di, dname)) continue;
      SelectedDevice s;
      s.platform = platforms[pi];
      s.device = devices[di];
      s.platform_index = pi;
      s.device_index = di;
      s.platform_name = pname;
      s.device_name = dname;
      s.vendor = deviceVendor(devices[di]);
      s.gpu = deviceIsGpu(devices[di]);
      s.fp64 = deviceHasFp64(devices[di]);
      const std::string forced_profile = selectorFrom("", "STABINT_OPENCL_PROFILE");
      s.profile =
          forced_profile.empty() ? &deviceProfile(s.gpu, s.vendor, s.device_name) : &deviceProfileNamed(forced_profile);
      return s;
    }
  }
  std::ostringstream msg;
  msg << "OpenCL: no device matches platform selector '" << io::shown(platform_sel) << "' and device selector '"
      << io::shown(device_sel)
      << "' (from OpenCLOptions or STABINT_OPENCL_PLATFORM / STABINT_OPENCL_DEVICE); available:";
  const std::string list = available.str();
  msg << (list.empty() ? std::string(" none") : list);
  throw NoOpenCLDeviceError(msg.str());
}

void checkPrecisionSupported(Precision precision, bool device_has_fp64, const std::string& device_name) {
  if (precision == Precision::Double && !device_has_fp64)
    throw UnsupportedPrecisionError("OpenCL: device '" + device_name +
                                    "' does not support double precision (no cl_khr_fp64); "
                                    "request Precision::Float or choose another device");
}

namespace {

// The caches live for the whole process and are never destroyed: releasing OpenCL objects from
// static destructors can run after the driver has been unloaded.
struct Caches {
  std::mutex mutex;
  std::map<cl_device_id, cl::Context> contexts;
  std::map<std::tuple<cl_context, cl_device_id, std::string, std::string>, cl::Program> programs;
};

Caches& caches() {
  static Caches* c = new Caches();
  return *c;
}

}  // namespace

cl::Context sharedContext(const cl::Device& device) {
  Caches& c = caches();
  std::lock_guard<std::mutex> lock(c.mutex);
  auto it = c.contexts.find(device());
  if (it != c.contexts.end()) return it->second;
  cl_int err = CL_SUCCESS;
  cl::Context context(device, nullptr, nullptr, nullptr, &err);
  check(err, "clCreateContext");
  c.contexts.emplace(device(), context);
  return context;
}

std::string programOptions(Precision precision) {
  return std::string("-cl-std=CL1.2 ") + (precision == Precision::Double ? "-DSTABINT_DOUBLE" : "-DSTABINT_FLOAT");
}

cl::Program buildProgram(const cl::Context& context, const cl::Device& device, const std::string& source,
                         const std::string& options) {
  cl_int err = CL_SUCCESS;
  cl::Program program(context, kernelPrelude() + source, false, &err);
  check(err, "clCreateProgramWithSource");
  err = program.build(std::vector<cl::Device>{device}, options.c_str());
  if (err != CL_SUCCESS) {
    std::string log;
    program.getBuildInfo(device, CL_PROGRAM_BUILD_LOG, &log);
    log = std::string(log.c_str());
    if (err == CL_BUILD_PROGRAM_FAILURE || err == CL_INVALID_BUILD_OPTIONS) {
      std::ostringstream msg;
      msg << "OpenCL: clBuildProgram failed: " << errorName(err) << " (" << err << ") with options '" << options << "'";
      throw KernelBuildError(msg.str(), log);
    }
    throwError(err, "clBuildProgram");
  }
  return program;
}

cl::Program cachedProgram(const cl::Context& context, const cl::Device& device, const std::string& source,
                          const std::string& options) {
  Caches& c = caches();
  auto key = std::make_tuple(context(), device(), options, source);
  {
    std::lock_guard<std::mutex> lock(c.mutex);
    auto it = c.programs.find(key);
    if (it != c.programs.end()) return it->second;
  }
  // Built outside the lock: a build takes about a second; two threads racing on the same key
  // both build and the first one stored wins, which is harmless.
  cl::Program program = buildProgram(context, device, source, options);
  std::lock_guard<std::mutex> lock(c.mutex);
  return c.programs.emplace(std::move(key), program).first->second;
}

}  // namespace ocl

std::vector<OpenCLDeviceInfo> listOpenCLDevices() {
  std::vector<OpenCLDeviceInfo> list;
  std::lock_guard<std::mutex> lock(ocl::discoveryMutex());
  const std::vector<cl::Platform> platforms = ocl::platformsOrEmpty();
  for (int pi = 0; pi < static_cast<int>(platforms.size()); ++pi) {
    const std::string pname = ocl::platformName(platforms[pi]);
    const std::vector<cl::Device> devices = ocl::devicesOrEmpty(platforms[pi]);
    for (int di = 0; di < static_cast<int>(devices.size()); ++di) {
      OpenCLDeviceInfo info;
      info.platform_index = pi;
      info.device_index = di;
      info.platform_name = pname;
      info.device_name = ocl::deviceName(devices[di]);
      info.vendor = ocl::deviceVendor(devices[di]);
      info.fp64 = ocl::deviceHasFp64(devices[di]);
      info.gpu = ocl::deviceIsGpu(devices[di]);
      list.push_back(std::move(info));
    }
  }
  return list;
}

}  // namespace stabint
