#pragma once
// stabint-run's command line: its options, their parsing and help, and the error a bad command
// line or a failed run ends with.
#include <stabint/stabint.hpp>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace stabint_run {

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
  bool version = false;
  bool quiet = false;
};

/// The whole tool: parses `argv` (argv[0] is the program), runs and returns the exit status,
/// having printed any error as "stabint-run: error: ...". The executable's main() and Python's
/// `stabint-run` command (stabint._stabint._run_cli) call it.
int runCli(int argc, char** argv);
/// The command line as options; a bad one is a UsageError naming the option.
Options parseArgs(int argc, char** argv);
/// The --help text: every option, with the simulator options' defaults.
std::string usage();
/// What the system said about the last failed write (e.g. ": No space left on device"), if anything.
std::string writeErrorText();

}  // namespace stabint_run
