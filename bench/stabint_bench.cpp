// stabint_bench: Google Benchmark suite of stabint. Case names are
//   step/<scene>/<integrator>/<backend>               one Simulator::step()
//   blend_vs_be/<scene>/<backend>                     one BE step and one blend step, alternated
//   iteration/<scene>/<integrator>/<backend>          one local/global iteration
//   rotation/<scene>/<method>                         the tets' nearest rotations alone
//   host_solve/<scene>/<backend>/<when>               the host's CHOLMOD solve alone, after a local step
//   scaling_step/cloth/<integrator>/<backend>/side:N  step on an N x N cloth
//   scaling_iteration/cloth/BE/<backend>/side:N       iteration on an N x N cloth
//   batch/<scene>/BE/cpu/<batch|separate>/scenes:N    N small scenes, one step each
//   frame/<scene>/<integrator>/<backend>/threads:N    tet-bar steps on N CPU threads (bench_frame.cpp)
//   frame/cloth128x128/BE-chebyshev-<global>/<backend>  the 16k-particle cloth's steps (GPU-sized)
//   thread_pass/<scene>/<pass>/threads:N[/<path>]   one CPU element pass on 1 or 2 threads
//                                                     (bench_thread_pass.cpp)
// with counters particles, elements, iterations and the phase times (seconds per benchmark
// iteration): local, gather, transfer, global, energy, bookkeeping. OpenCL cases are reported as
// errors ("skipped: ...") when no device exists. The default minimum time per case is 0.1 s
// (0.02 s with STABINT_BENCH_QUICK=1); --benchmark_min_time overrides it.
#include "bench_common.hpp"

#include <thread>

int main(int argc, char** argv) {
  using namespace stabint;
  std::string min_time = std::string("--benchmark_min_time=") + (bench::quickMode() ? "0.02" : "0.1");
  std::vector<char*> args{argv[0], min_time.data()};  // user flags come later and win
  for (int i = 1; i < argc; ++i) args.push_back(argv[i]);
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;

  std::string devices;
  for (const OpenCLDeviceInfo& d : listOpenCLDevices())
    devices += (devices.empty() ? "" : "; ") + d.platform_name + " / " + d.device_name + (d.fp64 ? " (fp64)" : "");
  benchmark::AddCustomContext("opencl_devices", devices.empty() ? "none" : devices);
  benchmark::AddCustomContext("hardware_threads", std::to_string(std::thread::hardware_concurrency()));
  benchmark::AddCustomContext("quick_mode", bench::quickMode() ? "1" : "0");

  bench::registerStepCases();
  bench::registerIterationCases();
  bench::registerSolverCases();
  bench::registerInteractionCases();
  bench::registerContactCases();
  bench::registerHostSolveCases();
  bench::registerBatchCases();
  bench::registerFrameCases();
  bench::registerThreadPassCases();
  bench::registerConvergenceCases();
  benchmark::RunSpecifiedBenchmarks();
  bench::releaseAllFixtures();  // OpenCL objects go while the runtime is still loaded
  benchmark::Shutdown();
  return 0;
}
