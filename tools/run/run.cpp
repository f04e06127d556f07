// stabint-run: one scene, one integrator, N frames; per-frame energies and timings as CSV and the
// deformed mesh as one OBJ per frame and/or a VTK time series (.vtu per frame + .pvd) for
// ParaView. Options are parsed by hand (no dependency for a CLI). The whole tool is runCli(), which
// the executable's main() (main.cpp) and Python's `stabint-run` command (stabint._stabint._run_cli)
// both call.
#include "cli.hpp"
#include "frame_writers.hpp"
#include "progress.hpp"

#include <nlohmann/json.hpp>

#include <stabint/stabint.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace stabint_run;
namespace fs = std::filesystem;

// --- the scene ------------------------------------------------------------------------------------

bool isBuiltin(const std::string& name) {
  for (const std::string& b : stabint::builtinSceneNames()) {
    if (b == name) return true;
  }
  return false;
}

// A --param value becomes a JSON value: numbers and [lists] as written, anything else as a
// string (the loader then says which parameter wanted a number). Each value is parsed on its
// own and must be exactly one number or list, so that a value cannot carry more keys with it
// (`pinned=[0], "nx": 3` used to set nx too), and the object is built as a value, not as text.
std::string paramsAsJson(const std::vector<std::pair<std::string, std::string>>& params) {
  using nlohmann::json;
  // Parameters are numbers and flat lists; a deeper value is a mistake, and bounding the depth
  // keeps the recursive dump below from running out of stack on a hostile value.
  constexpr int kMaxDepth = 8;
  json object = json::object();
  for (const auto& param : params) {
    const std::string& key = param.first;  // a plain reference: lambdas cannot capture bindings in C++17
    const std::string& value = param.second;
    if (object.contains(key)) throw UsageError("--param " + key + ": given twice");
    char* end = nullptr;
    std::strtod(value.c_str(), &end);
    const bool number = !value.empty() && *end == '\0';
    if (!number && (value.empty() || value.front() != '[')) {
      object[key] = value;
      continue;
    }
    json parsed;
    try {
      parsed = json::parse(value, [&](int depth, json::parse_event_t, json&) {
        if (depth > kMaxDepth)
          throw UsageError("--param " + key + ": value nested deeper than " + std::to_string(kMaxDepth) + " levels");
        return true;
      });
    } catch (const json::exception&) {
      throw UsageError("--param " + key + ": expected a number, a [list] or a word, got '" + value + "'");
    }
    if (!parsed.is_number() && !parsed.is_array()) {
      throw UsageError("--param " + key + ": expected a number, a [list] or a word, got '" + value + "'");
    }
    object[key] = std::move(parsed);
  }
  return object.dump();
}

std::string lowerExtension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

// A mesh file runs as the library's loaders read it (the default material, no pins, default
// gravity) above a ground plane: otherwise an unpinned mesh would only fall, forever. The plane
// faces against gravity, a quarter of the mesh's bounding-box diagonal below its lowest point, so
// that the mesh falls and lands within a run of a few seconds. Anything else (another material,
// pins, no ground) is a JSON scene with a "mesh" entry (docs/scene-format.md).
stabint::Scene withGround(stabint::Scene scene) {
  const Eigen::Vector3d up =
      scene.gravity.norm() > 0.0 ? Eigen::Vector3d(-scene.gravity.normalized()) : Eigen::Vector3d::UnitY();
  const Eigen::VectorXd heights = scene.positions * up;
  const double size = (scene.positions.colwise().maxCoeff() - scene.positions.colwise().minCoeff()).norm();
  stabint::Collider ground;
  ground.shape = stabint::ColliderShape::Plane;
  ground.normal = up;
  ground.center = up * (heights.minCoeff() - 0.25 * size);
  scene.colliders.push_back(ground);
  return scene;
}

// The mesh formats of the library's loaders (stabint/io.hpp), by extension; nullopt for a path
// that is not one of them.
std::optional<stabint::Scene> loadMesh(const std::string& path) {
  const std::string extension = lowerExtension(path);
  if (extension == ".obj") return stabint::loadObjCloth(path);
  if (extension == ".mesh") return stabint::loadMedit(path);
  if (extension == ".node" || extension == ".ele") {
    return stabint::loadTetGen((fs::path(path).parent_path() / fs::path(path).stem()).string());
  }
  if (extension == ".msh") {
    throw UsageError("--scene: '" + path +
                     "': Gmsh .msh files are not read by the library's loaders (OBJ, TetGen .node/.ele, Medit "
                     ".mesh); convert it, e.g. `meshio convert " +
                     path + " part.mesh`, or read it in Python with stabint.io.read_mesh");
  }
  return std::nullopt;
}

// A scene file's events (docs/scene-format.md, "Events") replay as the frames run; a built-in
// scene or a mesh has none.
stabint::SceneFile loadScene(const Options& o) {
  if (isBuiltin(o.scene)) {
    return {stabint::builtinScene(o.scene, paramsAsJson(o.params), "builtin scene '" + o.scene + "'"), {}};
  }
  if (!o.params.empty()) throw UsageError("--param applies to built-in scenes only, not to '" + o.scene + "'");
  if (std::optional<stabint::Scene> mesh = loadMesh(o.scene)) return {withGround(std::move(*mesh)), {}};
  if (lowerExtension(o.scene) != ".json" && !fs::exists(o.scene)) {
    throw UsageError("--scene: unknown scene '" + o.scene +
                     "' (expected oscillator, chain, cloth, tetbar, a .json scene file or a mesh: .obj, "
                     ".node/.ele, .mesh)");
  }
  return stabint::loadSceneFileWithEvents(o.scene);
}

// --- running --------------------------------------------------------------------------------------

// SIGINT / SIGTERM during the frame loop: the handler only records the signal; the loop finishes
// the current step, writes and flushes what it has and exits with 128 + signal, so an interrupted
// run keeps its CSV up to the last frame instead of losing the buffered rows. SA_RESETHAND: a
// second signal terminates at once, as if there were no handler.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void onStopSignal(int signal) { g_stop_signal = signal; }

class StopSignals {
 public:
  StopSignals() {
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

int listDevices() {
  const auto devices = stabint::listOpenCLDevices();
  if (devices.empty()) {
    std::cout << "no OpenCL devices found\n";
    return 0;
  }
  for (const auto& d : devices) {
    std::cout << "platform " << d.platform_index << " device " << d.device_index << ": " << d.platform_name << " / "
              << d.device_name << " (fp64: " << (d.fp64 ? "yes" : "no") << ", gpu: " << (d.gpu ? "yes" : "no")
              << ", vendor: " << d.vendor << ")\n";
  }
  return 0;
}

int run(Options& o) {
  stabint::SceneFile file = loadScene(o);
  const stabint::Scene& scene = file.scene;
  stabint::EventScript& events = file.events;
  auto sim = std::make_unique<stabint::Simulator>(scene, o.sim);
  if (o.precision_explicit && sim->backendDescription().rfind("CPU reference", 0) == 0 &&
      o.sim.opencl.precision == stabint::Precision::Float && !o.quiet) {
    std::cerr << kProgram << ": note: --precision float applies to OpenCL only; the CPU reference runs in double\n";
  }
  if (!o.quiet) {
    std::cerr << kProgram << ": scene '" << scene.name << "' (" << scene.numParticles() << " particles, "
              << stabint::elementSummary(scene) << "), " << stabint::integratorName(o.sim.integrator) << ", dt "
              << o.sim.time_step << ", " << o.frames << " frames on " << sim->backendDescription()
              << (events.empty() ? std::string() : ", " + std::to_string(events.events().size()) + " scripted events")
              << "\n";
  }

  std::optional<CsvWriter> csv;
  if (!o.csv.empty()) csv.emplace(o.csv);
  std::optional<ObjWriter> obj;
  if (!o.obj_dir.empty()) obj.emplace(o.obj_dir, scene);
  std::optional<VtkWriter> vtk;
  if (!o.vtk_dir.empty()) vtk.emplace(o.vtk_dir, scene);

  // Frame 0 is the initial state: the reference every energy drift is measured against.
  const double initial_total = sim->energy().total();
  if (csv) csv->initialRow(*sim);
  if (obj) obj->write(0, sim->positions());
  if (vtk) vtk->write(0, sim->time(), sim->positions(), sim->velocities());

  Progress progress(o.frames, o.quiet);
  int last_written = 0;
  const StopSignals stop_signals;
  for (int frame = 1; frame <= o.frames; ++frame) {
    try {
      events.apply(*sim);  // the events due before this step, and the dragged handles' targets
      sim->step();
    } catch (const stabint::NonFiniteStateError& e) {
      // Frames count from 1 (frame 0 is the initial state), so the refused step, index e.step()
      // from 0, would have made frame e.step() + 1; the library's message names that index.
      const int bad = e.step() + 1;
      // Keep the last finite frame even when --every skipped it.
      if (csv && last_written != bad - 1 && bad - 1 > 0) csv->row(bad - 1, sim->lastReport());
      if (vtk && last_written != bad - 1 && bad - 1 > 0)
        vtk->write(bad - 1, sim->time(), sim->positions(), sim->velocities());  // as the CSV: the last finite frame
      if (vtk) vtk->finish();
      progress.end();
      const bool limit = dynamic_cast<const stabint::EnergyLimitError*>(&e) != nullptr;
      std::cerr << kProgram << ": error: " << (limit ? "the energy limit was exceeded" : "the state became non-finite")
                << " at frame " << bad << " (t = " << sim->time() + o.sim.time_step << " s); "
                << (csv ? "CSV kept up to frame " + std::to_string(bad - 1) + "; " : std::string()) << e.what() << "\n";
      return 2;
    }
    const int stop_signal = g_stop_signal;
    if (frame % o.every == 0 || frame == o.frames || stop_signal != 0) {
      if (csv) csv->row(frame, sim->lastReport());
      if (obj) obj->write(frame, sim->positions());
      if (vtk) vtk->write(frame, sim->time(), sim->positions(), sim->velocities());
      last_written = frame;
    }
    if (stop_signal != 0) {
      if (vtk) vtk->finish();
      progress.end();
      std::cerr << kProgram << ": interrupted by " << (stop_signal == SIGINT ? "SIGINT" : "SIGTERM") << " after frame "
                << frame << (csv ? "; CSV kept up to frame " + std::to_string(frame) : std::string()) << "\n";
      return 128 + stop_signal;
    }
    progress.frame(frame);
  }
  if (vtk) vtk->finish();
  progress.end();
  if (!o.quiet) {
    const double elapsed = progress.elapsed();
    const double total = sim->energy().total();
    std::cerr << kProgram << ": " << o.frames << " frames in " << elapsed << " s ("
              << (o.frames ? 1e3 * elapsed / o.frames : 0.0) << " ms/frame); energy " << initial_total << " -> "
              << total << ", target " << sim->target() << "\n";
  }
  return 0;
}

}  // namespace

namespace stabint_run {

int runCli(int argc, char** argv) {
  try {
    Options o = parseArgs(argc, argv);
    int status = 0;
    errno = 0;
    if (o.help) {
      std::cout << usage();
    } else if (o.version) {
      std::cout << kProgram << " " << STABINT_RUN_VERSION << "\n";
    } else {
      status = o.list_devices ? listDevices() : run(o);
    }
    // Whatever went to standard output (help, device list, --csv -) must have arrived.
    std::cout.flush();
    if (!std::cout) throw UsageError("write failed for standard output" + writeErrorText());
    return status;
  } catch (const std::exception& e) {
    std::cerr << kProgram << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace stabint_run
