// stabint-run: one scene, one integrator, N frames; per-frame energies and timings as CSV and the
// deformed mesh as one OBJ per frame and/or a VTK time series (.vtu per frame + .pvd) for
// ParaView. Options are parsed by hand (no dependency for a CLI).
#include <nlohmann/json.hpp>

#include <stabint/options_fields.hpp>
#include <stabint/stabint.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kProgram = "stabint-run";

// A bad command line or a failed run: printed as "stabint-run: error: <message>", exit 1.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string scene;
  std::vector<std::pair<std::string, std::string>> params;
  stabint::SimulatorOptions sim;
  bool precision_explicit = false;
  int frames = 100;
  int every = 1;
  std::string csv;
  std::string obj_dir;
  std::string vtk_dir;
  bool list_devices = false;
  bool help = false;
  bool quiet = false;
};

// --- simulator options: one flag per field of the field list (stabint/options_fields.hpp) ------
// Adding a field to SimulatorOptions adds its flag (the field name with '-' for '_') and its help
// line here; a field of a new type needs its parseValue, shown and placeholder overloads.

// The options a run starts from: the library's defaults, except the backend (auto: a GPU when
// there is one).
stabint::SimulatorOptions defaultSimulatorOptions() {
  stabint::SimulatorOptions o;
  o.backend = stabint::BackendKind::Auto;
  return o;
}

std::string flagOf(const char* field) {
  std::string flag = std::string("--") + field;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(x)) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
  return x;
}

int parseInteger(const std::string& option, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long x = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || x < INT32_MIN || x > INT32_MAX) {
    throw UsageError(option + ": expected an integer, got '" + text + "'");
  }
  return static_cast<int>(x);
}

// Reads a flag's value into a field; `flag` is the flag as typed, for the messages.
void parseValue(const std::string& flag, const std::string& text, int& out) { out = parseInteger(flag, text); }
void parseValue(const std::string& flag, const std::string& text, double& out) { out = parseNumber(flag, text); }
void parseValue(const std::string&, const std::string& text, stabint::Integrator& out) {
  out = stabint::parseIntegrator(text);
}
void parseValue(const std::string&, const std::string& text, stabint::Acceleration& out) {
  out = stabint::parseAcceleration(text);
}
void parseValue(const std::string&, const std::string& text, stabint::GlobalSolve& out) {
  out = stabint::parseGlobalSolve(text);
}
void parseValue(const std::string&, const std::string& text, stabint::BackendKind& out) {
  out = stabint::parseBackend(text);
}

// A value as the help shows it (the default), and the placeholder of the flag's value.
std::string shown(int value) { return std::to_string(value); }
std::string shown(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}
std::string shown(stabint::Integrator value) { return stabint::integratorName(value); }
std::string shown(stabint::Acceleration value) { return stabint::accelerationName(value); }
std::string shown(stabint::GlobalSolve value) { return stabint::globalSolveName(value); }
std::string shown(stabint::BackendKind value) { return stabint::backendName(value); }
std::string placeholder(int) { return "N"; }
std::string placeholder(double) { return "X"; }
std::string placeholder(stabint::Integrator) { return "FE|SE|BE|BDF2|IM|blend"; }
std::string placeholder(stabint::Acceleration) { return "none|chebyshev|anderson|lbfgs|newton"; }
std::string placeholder(stabint::GlobalSolve) { return "factor|cg"; }
std::string placeholder(stabint::BackendKind) { return "cpu|opencl|auto"; }

// Sets the field whose flag is `flag` (--time-step) from the text `value()` returns (called only
// then: it takes the next argument); `typed` is the flag as the user wrote it (an alias such as
// --dt). False when no field has that flag. The nested OpenCL options have their own flags
// (--platform, --device, --precision: --precision also notes that it was given).
bool setSimulatorOption(stabint::SimulatorOptions& o, const std::string& flag, const std::string& typed,
                        const std::function<std::string()>& value) {
#define STABINT_RUN_SET(type, name, doc) \
  if (flag == flagOf(#name)) {           \
    parseValue(typed, value(), o.name);  \
    return true;                         \
  }
#define STABINT_RUN_SET_NESTED(type, name, fields, doc)
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_RUN_SET, STABINT_RUN_SET_NESTED)
#undef STABINT_RUN_SET
#undef STABINT_RUN_SET_NESTED
  return false;
}

// One help line per field, "  --flag VALUE   doc (default X)", wrapped at 100 columns.
std::string simulatorOptionsHelp() {
  const stabint::SimulatorOptions d = defaultSimulatorOptions();
  std::ostringstream s;
  const auto line = [&s](const std::string& flag, const std::string& text) {
    constexpr size_t kColumn = 28, kWidth = 100;
    std::string out = "  " + flag;
    out += out.size() < kColumn ? std::string(kColumn - out.size(), ' ') : "\n" + std::string(kColumn, ' ');
    size_t width = out.size() - out.rfind('\n') - 1;
    std::istringstream words(text);
    std::string word;
    bool first = true;
    while (words >> word) {
      if (!first && width + 1 + word.size() > kWidth) {
        out += "\n" + std::string(kColumn, ' ');
        width = kColumn;
      } else if (!first) {
        out += ' ';
        ++width;
      }
      out += word;
      width += word.size();
      first = false;
    }
    s << out << "\n";
  };
#define STABINT_RUN_HELP(type, name, doc) \
  line(flagOf(#name) + " " + placeholder(d.name), std::string(doc) + " (default " + shown(d.name) + ")");
#define STABINT_RUN_HELP_NESTED(type, name, fields, doc)
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_RUN_HELP, STABINT_RUN_HELP_NESTED)
#undef STABINT_RUN_HELP
#undef STABINT_RUN_HELP_NESTED
  return s.str();
}

std::string usage() {
  std::ostringstream s;
  s << "Usage: stabint-run --scene NAME|FILE.json [options]\n"
       "\n"
       "Steps one scene with one integrator and writes per-frame energies, timings and meshes.\n"
       "\n"
       "Scene:\n"
       "  --scene NAME|FILE.json    built-in scene (oscillator, chain, cloth, tetbar) or a JSON scene\n"
       "                            file (format: docs/scene-format.md)\n"
       "  --param KEY=VALUE         built-in scene parameter, repeatable (nx=50, pinned=[0,49])\n"
       "Simulator options, one per field of SimulatorOptions (include/stabint/simulator.hpp);\n"
       "--dt is --time-step:\n"
    << simulatorOptionsHelp()
    << "Backend (--backend above: auto prints its choice and the reason; opencl runs on the selected\n"
       "device, PoCL included, and never falls back):\n"
       "  --precision double|float  OpenCL arithmetic (the CPU reference always runs in double)\n"
       "  --platform SEL            OpenCL platform: index or name substring\n"
       "  --device SEL              OpenCL device: index or name substring\n"
       "  --list-devices            list the OpenCL devices and exit\n"
       "Output:\n"
       "  --frames N                number of time steps (default 100)\n"
       "  --csv FILE                per-frame CSV, '-' for standard output: frame, time, kinetic,\n"
       "                            elastic, external, total, target, forcing, damping,\n"
       "                            event_energy, friction, contact_projection (the step's\n"
       "                            energy book: what entered or left H*), branch, alpha,\n"
       "                            velocity_scale, iterations,\n"
       "                            energy_evaluations, local_s, gather_s, transfer_s, global_s,\n"
       "                            energy_s, bookkeeping_s (frame 0 is the initial state)\n"
       "  --obj-dir DIR             one OBJ per written frame (DIR/frame_00000.obj, ...): vertices,\n"
       "                            surface triangles when known, else tet boundary faces, else\n"
       "                            springs as lines\n"
       "  --vtk DIR                 a VTK time series for ParaView: DIR/frame_00000.vtu, ... (XML\n"
       "                            UnstructuredGrid, ASCII, positions and velocities to the last\n"
       "                            bit) and DIR/frames.pvd listing each frame with its time (open\n"
       "                            the .pvd); cells: the tets, else the surface triangles, else\n"
       "                            springs as lines, else one vertex per particle\n"
       "  --every N                 write every Nth frame to the CSV, OBJ and VTK files (default 1;\n"
       "                            the last frame is always written)\n"
       "  --quiet                   no progress or summary on standard error\n"
       "  --help                    this text\n"
       "\n"
       "Built-in scene parameters (see include/stabint/builders.hpp):\n";
  for (const std::string& name : stabint::builtinSceneNames()) {
    s << "  " << name << ":";
    for (const std::string& p : stabint::builtinSceneParameters(name)) s << " " << p;
    s << "\n";
  }
  s << "\n"
       "Exit status: 0 success; 1 error (a failed write included); 2 the state became non-finite or\n"
       "exceeded --energy-limit (the CSV keeps the frames before it); 130 / 143 interrupted by\n"
       "SIGINT / SIGTERM (the CSV keeps the frames up to the one reported).\n";
  return s.str();
}

// --- option parsing ------------------------------------------------------------------------------

Options parseArgs(int argc, char** argv) {
  Options o;
  o.sim = defaultSimulatorOptions();
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    std::optional<std::string> inline_value;
    if (arg.rfind("--", 0) == 0) {
      const size_t eq = arg.find('=');
      if (eq != std::string::npos) {
        inline_value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
      }
    } else {
      throw UsageError("unexpected argument '" + arg + "' (options start with --; see --help)");
    }
    const auto value = [&]() -> std::string {
      if (inline_value) return *inline_value;
      if (i + 1 >= argc) throw UsageError(arg + ": missing value");
      return argv[++i];
    };
    const auto flag = [&]() {
      if (inline_value) throw UsageError(arg + ": takes no value");
    };
    try {
      if (arg == "--help" || arg == "-h") {
        flag();
        o.help = true;
      } else if (arg == "--scene") {
        o.scene = value();
      } else if (arg == "--param") {
        const std::string kv = value();
        const size_t eq = kv.find('=');
        if (eq == std::string::npos || eq == 0) throw UsageError("--param: expected KEY=VALUE, got '" + kv + "'");
        o.params.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
      } else if (arg == "--precision") {
        const std::string p = value();
        if (p == "double")
          o.sim.opencl.precision = stabint::Precision::Double;
        else if (p == "float")
          o.sim.opencl.precision = stabint::Precision::Float;
        else
          throw UsageError("--precision: expected double or float, got '" + p + "'");
        o.precision_explicit = true;
      } else if (arg == "--platform") {
        o.sim.opencl.platform = value();
      } else if (arg == "--device") {
        o.sim.opencl.device = value();
      } else if (setSimulatorOption(o.sim, arg == "--dt" ? "--time-step" : arg, arg, value)) {
      } else if (arg == "--frames") {
        o.frames = parseInteger(arg, value());
        if (o.frames < 0) throw UsageError("--frames: must be >= 0, got " + std::to_string(o.frames));
      } else if (arg == "--every") {
        o.every = parseInteger(arg, value());
        if (o.every < 1) throw UsageError("--every: must be >= 1, got " + std::to_string(o.every));
      } else if (arg == "--csv") {
        o.csv = value();
      } else if (arg == "--obj-dir") {
        o.obj_dir = value();
      } else if (arg == "--vtk") {
        o.vtk_dir = value();
      } else if (arg == "--list-devices") {
        flag();
        o.list_devices = true;
      } else if (arg == "--quiet") {
        flag();
        o.quiet = true;
      } else {
        throw UsageError("unknown option '" + arg + "' (see --help)");
      }
    } catch (const stabint::InvalidInputError& e) {
      throw UsageError(arg + ": " + e.what());  // names from parseIntegrator / parseBackend
    }
  }
  if (!o.help && !o.list_devices && o.scene.empty()) throw UsageError("missing --scene (see --help)");
  return o;
}

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

// A scene file's events (docs/scene-format.md, "Events") replay as the frames run; a built-in
// scene has none.
stabint::SceneFile loadScene(const Options& o) {
  if (isBuiltin(o.scene)) {
    return {stabint::builtinScene(o.scene, paramsAsJson(o.params), "builtin scene '" + o.scene + "'"), {}};
  }
  if (!o.params.empty()) throw UsageError("--param applies to built-in scenes only, not to '" + o.scene + "'");
  if (fs::path(o.scene).extension() != ".json" && !fs::exists(o.scene)) {
    throw UsageError("--scene: unknown scene '" + o.scene +
                     "' (expected oscillator, chain, cloth, tetbar or a .json file)");
  }
  return stabint::loadSceneFileWithEvents(o.scene);
}

// Faces for the OBJ frames of a tet mesh: the triangles that belong to exactly one tet, wound
// outward (tets have positive rest volume).
std::vector<std::array<int, 3>> tetBoundary(const std::vector<stabint::Tet>& tets) {
  std::map<std::array<int, 3>, std::pair<int, std::array<int, 3>>> faces;
  for (const stabint::Tet& t : tets) {
    const auto& v = t.vertices;
    const std::array<std::array<int, 3>, 4> local = {
        {{v[0], v[2], v[1]}, {v[0], v[1], v[3]}, {v[0], v[3], v[2]}, {v[1], v[2], v[3]}}};
    for (const auto& f : local) {
      std::array<int, 3> key = f;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = f;
    }
  }
  std::vector<std::array<int, 3>> boundary;
  for (const auto& [key, entry] : faces) {
    if (entry.first == 1) boundary.push_back(entry.second);
  }
  return boundary;
}

// --- output ---------------------------------------------------------------------------------------

// What the system said about the last failed write (e.g. "No space left on device"), if anything.
std::string writeErrorText() { return errno != 0 ? std::string(": ") + std::strerror(errno) : std::string(); }

class ObjWriter {
 public:
  ObjWriter(std::string dir, const stabint::Scene& scene) : dir_(std::move(dir)) {
    fs::create_directories(dir_);
    triangles_ = scene.triangles.empty() ? tetBoundary(scene.tets) : scene.triangles;
    if (triangles_.empty()) {
      for (const stabint::Spring& s : scene.springs) lines_.push_back({s.a, s.b});
    }
  }

  void write(int frame, const Eigen::MatrixX3d& x) const {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.obj", frame);
    const std::string path = (fs::path(dir_) / name).string();
    std::ofstream out(path);
    if (!out) throw UsageError("--obj-dir: cannot write " + path);
    char line[96];
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      std::snprintf(line, sizeof(line), "v %.9g %.9g %.9g\n", x(i, 0), x(i, 1), x(i, 2));
      out << line;
    }
    for (const auto& t : triangles_) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    for (const auto& l : lines_) out << "l " << l[0] + 1 << ' ' << l[1] + 1 << '\n';
    out.close();  // the last buffer is written here: a full disk shows only now
    if (!out) throw UsageError("--obj-dir: write failed for " + path + writeErrorText());
  }

 private:
  std::string dir_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 2>> lines_;
};

// A VTK time series (--vtk DIR) for ParaView, written without the VTK library: one XML
// UnstructuredGrid file per written frame (DIR/frame_00000.vtu, ...) and DIR/frames.pvd, the
// collection that lists each file with its time. ASCII with 17 significant digits, so that a
// reader (meshio, ParaView) gets the simulator's doubles back to the last bit; binary would be
// smaller, but the OBJ frames are text too and a series this tool writes is for looking at.
// Cells: the tets (volume), else the surface triangles, else the springs as lines, else one
// vertex per particle, so that every scene shows something.
class VtkWriter {
 public:
  VtkWriter(std::string dir, const stabint::Scene& scene) : dir_(std::move(dir)) {
    fs::create_directories(dir_);
    // VTK cell types: 10 tetra, 5 triangle, 3 line, 1 vertex.
    if (!scene.tets.empty()) {
      for (const stabint::Tet& t : scene.tets) addCell(10, t.vertices);
    } else if (!scene.triangles.empty()) {
      for (const auto& t : scene.triangles) addCell(5, t);
    } else if (!scene.springs.empty()) {
      for (const stabint::Spring& s : scene.springs) addCell(3, std::array<int, 2>{s.a, s.b});
    } else {
      for (int i = 0; i < scene.numParticles(); ++i) addCell(1, std::array<int, 1>{i});
    }
  }

  void write(int frame, double time, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.vtu", frame);
    const std::string path = (fs::path(dir_) / name).string();
    errno = 0;
    std::ofstream out(path);
    if (!out) throw UsageError("--vtk: cannot write " + path + writeErrorText());
    const auto rows = [&out](const Eigen::MatrixX3d& m) {
      char line[96];
      for (Eigen::Index i = 0; i < m.rows(); ++i) {
        std::snprintf(line, sizeof(line), "%.17g %.17g %.17g\n", m(i, 0), m(i, 1), m(i, 2));
        out << line;
      }
    };
    out << "<?xml version=\"1.0\"?>\n"
           "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
           "header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\""
        << x.rows() << "\" NumberOfCells=\"" << types_.size()
        << "\">\n<PointData Vectors=\"velocity\">\n"
           "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    rows(v);
    out << "</DataArray>\n</PointData>\n<Points>\n"
           "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    rows(x);
    out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (int i : connectivity_) out << i << '\n';
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (int i : offsets_) out << i << '\n';
    out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    for (int i : types_) out << i << '\n';
    out << "</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    out.close();  // a full disk shows only now
    if (!out) throw UsageError("--vtk: write failed for " + path + writeErrorText());
    frames_.emplace_back(time, name);
  }

  // The collection, written once at the end of the run (also after a blow-up or a signal, with
  // the frames written so far), so that it never lists a file that was not written.
  void finish() const {
    const std::string path = (fs::path(dir_) / "frames.pvd").string();
    errno = 0;
    std::ofstream out(path);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<Collection>\n";
    char line[128];
    for (const auto& [time, file] : frames_) {
      std::snprintf(line, sizeof(line), "<DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"%s\"/>\n", time,
                    file.c_str());
      out << line;
    }
    out << "</Collection>\n</VTKFile>\n";
    out.close();
    if (!out) throw UsageError("--vtk: write failed for " + path + writeErrorText());
  }

 private:
  template <size_t N>
  void addCell(int type, const std::array<int, N>& vertices) {
    connectivity_.insert(connectivity_.end(), vertices.begin(), vertices.end());
    offsets_.push_back(static_cast<int>(connectivity_.size()));
    types_.push_back(type);
  }

  std::string dir_;
  std::vector<int> connectivity_, offsets_, types_;
  std::vector<std::pair<double, std::string>> frames_;
};

// Every write is checked: a full disk (--csv /dev/full) or a closed file must end the run with an
// error, not exit 0 with nothing written.
class CsvWriter {
 public:
  explicit CsvWriter(const std::string& path) : name_(path == "-" ? "standard output" : "'" + path + "'") {
    errno = 0;
    if (path == "-") {
      out_ = &std::cout;
    } else {
      file_.open(path);
      if (!file_) throw UsageError("--csv: cannot write '" + path + "'");
      out_ = &file_;
    }
    *out_
        << "frame,time,kinetic,elastic,external,total,target,forcing,damping,event_energy,friction,contact_projection,"
           "branch,alpha,velocity_scale,iterations,energy_evaluations,local_s,gather_s,transfer_s,global_s,energy_s,"
           "bookkeeping_s\n";
    check();
  }

  void row(int frame, const stabint::StepReport& r) {
    const auto& e = r.energy;
    const auto& t = r.times;
    char buf[768];
    std::snprintf(
        buf, sizeof(buf),
        "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%.17g,%.17g,%d,%d,%.9g,%.9g,%."
        "9g,%.9g,%.9g,%.9g\n",
        frame, r.time, e.kinetic, e.elastic, e.external, e.total(), r.target, r.forcing, r.damping, r.event_energy,
        r.friction, r.contact_projection, stabint::blendBranchName(r.branch), r.alpha, r.velocity_scale, r.iterations,
        r.energy_evaluations, t.local, t.gather, t.transfer, t.global, t.energy, t.bookkeeping);
    *out_ << buf;
    check();
  }

  void flush() {
    out_->flush();
    check();
  }

 private:
  void check() const {
    if (!*out_) throw UsageError("--csv: write failed for " + name_ + writeErrorText());
  }

  std::string name_;
  std::ofstream file_;
  std::ostream* out_ = nullptr;
};

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
  stabint::StepReport initial;
  initial.energy = sim->energy();
  initial.target = sim->target();
  const double initial_total = initial.energy.total();
  if (csv) csv->row(0, initial);
  if (obj) obj->write(0, sim->positions());
  if (vtk) vtk->write(0, sim->time(), sim->positions(), sim->velocities());

  const auto start = Clock::now();
  auto last_progress = start;
  int last_written = 0;
  const StopSignals stop_signals;
  for (int frame = 1; frame <= o.frames; ++frame) {
    try {
      events.apply(*sim);  // the events due before this step, and the dragged handles' targets
      sim->step();
    } catch (const stabint::NonFiniteStateError& e) {
      const int bad = e.step() + 1;
      // Keep the last finite frame even when --every skipped it.
      if (csv && last_written != bad - 1 && bad - 1 > 0) csv->row(bad - 1, sim->lastReport());
      if (csv) csv->flush();
      if (vtk && last_written != bad - 1 && bad - 1 > 0)
        vtk->write(bad - 1, sim->time(), sim->positions(), sim->velocities());  // as the CSV: the last finite frame
      if (vtk) vtk->finish();
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
      if (csv) csv->flush();
      if (vtk) vtk->finish();
      std::cerr << kProgram << ": interrupted by " << (stop_signal == SIGINT ? "SIGINT" : "SIGTERM") << " after frame "
                << frame << (csv ? "; CSV kept up to frame " + std::to_string(frame) : std::string()) << "\n";
      return 128 + stop_signal;
    }
    const auto now = Clock::now();
    if (!o.quiet && now - last_progress >= std::chrono::seconds(1)) {
      const double elapsed = std::chrono::duration<double>(now - start).count();
      std::cerr << kProgram << ": frame " << frame << "/" << o.frames << ", " << 1e3 * elapsed / frame << " ms/frame\n";
      last_progress = now;
    }
  }
  if (csv) csv->flush();
  if (vtk) vtk->finish();
  if (!o.quiet) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const double total = sim->energy().total();
    std::cerr << kProgram << ": " << o.frames << " frames in " << elapsed << " s ("
              << (o.frames ? 1e3 * elapsed / o.frames : 0.0) << " ms/frame); energy " << initial_total << " -> "
              << total << ", target " << sim->target() << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o = parseArgs(argc, argv);
    int status = 0;
    errno = 0;
    if (o.help) {
      std::cout << usage();
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
