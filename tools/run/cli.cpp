#include "cli.hpp"

#include <stabint/options_table.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <set>
#include <sstream>

namespace stabint_run {
namespace {

// --- simulator options: one flag per field of the field list (stabint/options_table.h) ------
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

// A decimal number: digits with an optional sign, point and exponent (strtod alone also takes
// hexadecimal floats, "inf", "nan" and leading spaces, which no option means).
bool decimalNumber(const std::string& text) {
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t from = i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) ++i;
    return i > from;
  };
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  bool mantissa = digits();
  if (i < text.size() && text[i] == '.') {
    ++i;
    mantissa = digits() || mantissa;
  }
  if (!mantissa) return false;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    if (!digits()) return false;
  }
  return i == text.size();
}

double parseNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(text.c_str(), &end);
  if (!decimalNumber(text) || *end != '\0' || errno == ERANGE || !std::isfinite(x)) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
  return x;
}

int parseInteger(const std::string& option, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long x = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front())) || *end != '\0') {
    throw UsageError(option + ": expected an integer, got '" + text + "'");
  }
  // An integer, but not one an int holds.
  if (errno == ERANGE || x < INT32_MIN || x > INT32_MAX) {
    throw UsageError(option + ": " + text + " is out of range (" + std::to_string(INT32_MIN) + " to " +
                     std::to_string(INT32_MAX) + ")");
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
std::string placeholder(stabint::Integrator) {
  return stabint::enumNames(stabint::integratorName, stabint::kIntegratorCount, "|", "|");
}
std::string placeholder(stabint::Acceleration) {
  return stabint::enumNames(stabint::accelerationName, stabint::kAccelerationCount, "|", "|");
}
std::string placeholder(stabint::GlobalSolve) {
  return stabint::enumNames(stabint::globalSolveName, stabint::kGlobalSolveCount, "|", "|");
}
std::string placeholder(stabint::BackendKind) {
  return stabint::enumNames(stabint::backendName, stabint::kBackendKindCount, "|", "|");
}
std::string placeholder(stabint::Precision) {
  return stabint::enumNames(stabint::precisionName, stabint::kPrecisionCount, "|", "|");
}

// --precision's value: a name as precisionName prints it, exactly (the case too).
stabint::Precision precision(const std::string& text) {
  for (int i = 0; i < stabint::kPrecisionCount; ++i)
    if (text == stabint::precisionName(static_cast<stabint::Precision>(i))) return static_cast<stabint::Precision>(i);
  throw UsageError("--precision: expected " + stabint::enumNames(stabint::precisionName, stabint::kPrecisionCount) +
                   ", got '" + text + "'");
}

// Sets the field whose flag is `flag` (--time-step) from the text `value()` returns (called only
// then: it takes the next argument); `typed` is the flag as the user wrote it (an alias such as
// --dt). False when no field has that flag. The nested OpenCL options have their own flags
// (--platform, --device, --precision: --precision also notes that it was given).
bool setSimulatorOption(stabint::SimulatorOptions& o, const std::string& flag, const std::string& typed,
                        const std::function<std::string()>& value) {
#define STABINT_RUN_SET(type, name, default_value, rule, doc) \
  if (flag == flagOf(#name)) {                                \
    parseValue(typed, value(), o.name);                       \
    return true;                                              \
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
#define STABINT_RUN_HELP(type, name, default_value, rule, doc) \
  line(flagOf(#name) + " " + placeholder(d.name), std::string(doc) + " (default " + shown(d.name) + ")");
#define STABINT_RUN_HELP_NESTED(type, name, fields, doc)
  STABINT_SIMULATOR_OPTIONS_FIELDS(STABINT_RUN_HELP, STABINT_RUN_HELP_NESTED)
#undef STABINT_RUN_HELP
#undef STABINT_RUN_HELP_NESTED
  return s.str();
}

}  // namespace

std::string usage() {
  std::ostringstream s;
  s << "Usage: stabint-run --scene NAME|FILE [options]\n"
       "\n"
       "Steps one scene with one integrator and writes per-frame energies, timings and meshes.\n"
       "\n"
       "Scene:\n"
       "  --scene NAME|FILE         built-in scene (oscillator, chain, cloth, tetbar), a JSON scene\n"
       "                            file (.json, format: docs/scene-format.md) or a mesh file: OBJ\n"
       "                            cloth (.obj), TetGen (.node or .ele) or Medit (.mesh) tets. A mesh\n"
       "                            gets the loaders' default material (ClothMaterial, SolidMaterial),\n"
       "                            no pins, default gravity and a ground plane a quarter of its\n"
       "                            bounding-box diagonal below its lowest point; for anything else\n"
       "                            write a JSON scene with a \"mesh\" entry. Gmsh (.msh) is not read:\n"
       "                            convert it (meshio convert part.msh part.mesh)\n"
       "  --param KEY=VALUE         built-in scene parameter, repeatable (nx=50, pinned=[0,49])\n"
       "Simulator options, one per row of include/stabint/options_table.h;\n"
       "--dt is --time-step:\n"
    << simulatorOptionsHelp()
    << "Backend (--backend above: auto prints its choice and the reason; opencl runs on the selected\n"
       "device, PoCL included, and never falls back):\n"
    << "  --precision " << placeholder(stabint::Precision{})
    << "  OpenCL arithmetic (the CPU reference always runs in double)\n"
       "  --platform SEL            OpenCL platform: index or name substring\n"
       "  --device SEL              OpenCL device: index or name substring\n"
       "  --list-devices            list the OpenCL devices and exit\n"
       "Output:\n"
       "  --frames N                number of time steps (default 100): frames 1 to N, each after\n"
       "                            its step (frame 0 is the initial state)\n"
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
       "  -h, --help                this text\n"
       "  --version                 the version, and exit\n"
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
  std::set<std::string> seen;  // the options given so far
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    std::optional<std::string> inline_value;
    // -h is the one short option: --help, as most tools spell it.
    if (arg == "-h") arg = "--help";
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
      // No value starts with "--": that is the next option, and this one lacks its value.
      if (std::strncmp(argv[i + 1], "--", 2) == 0)
        throw UsageError(arg + ": missing value (the next argument is the option '" + argv[i + 1] + "')");
      return argv[++i];
    };
    // Each option once (--param once per key: paramsAsJson): a second value would silently
    // replace the first.
    const std::string name = arg == "--dt" ? "--time-step" : arg;
    if (name != "--param" && !seen.insert(name).second)
      throw UsageError(arg + ": given twice" + (name == "--time-step" ? " (--dt is --time-step)" : std::string()));
    const auto flag = [&]() {
      if (inline_value) throw UsageError(arg + ": takes no value");
    };
    try {
      if (arg == "--help") {
        flag();
        o.help = true;
      } else if (arg == "--version") {
        flag();
        o.version = true;
      } else if (arg == "--scene") {
        o.scene = value();
      } else if (arg == "--param") {
        const std::string kv = value();
        const size_t eq = kv.find('=');
        if (eq == std::string::npos || eq == 0) throw UsageError("--param: expected KEY=VALUE, got '" + kv + "'");
        o.params.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
      } else if (arg == "--precision") {
        o.sim.opencl.precision = precision(value());
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
  if (!o.help && !o.version && !o.list_devices && o.scene.empty()) throw UsageError("missing --scene (see --help)");
  return o;
}

std::string writeErrorText() { return errno != 0 ? std::string(": ") + std::strerror(errno) : std::string(); }

}  // namespace stabint_run
