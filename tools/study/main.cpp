// stabint-study: the main job's experiments. Each subcommand writes CSV files into the output
// directory (default results/); bench/study_charts.py turns them into charts and a summary.
#include "study.hpp"

#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

namespace {

void usage(std::FILE* to) {
  std::fprintf(to,
               "usage: stabint-study <command> [--out DIR] [--backend cpu|opencl] [--quick] [--mesh BASE]\n"
               "commands:\n"
               "  prefetch    every reference trajectory that `all` reads, computed two at a time on two\n"
               "              threads and cached in DIR/cache (`all` runs it first)\n"
               "  table       energy behaviour of every integrator: chain pendulum and cloth, 300 frames\n"
               "              (printed, and energy_table.csv)\n"
               "  reference   reference trajectories (IM, h/16, converged; cached in DIR/cache) and the\n"
               "              accuracy of every integrator at h = 1/30, 10 iterations (reference.csv,\n"
               "              accuracy.csv)\n"
               "  sweep       speed versus accuracy: iteration budgets 1..32, explicit substeps 1, 2, 4, ...\n"
               "              up to the first stable count, cloths and tet bar (sweep.csv)\n"
               "  stability   stiffness x step size grid per integrator, chain and tet bar (stability.csv)\n"
               "  energy      energy over time: tet bar and cloth with BE, BDF2, IM, blend\n"
               "              (energy_tetbar.csv, energy_cloth.csv, cloth_still_<integrator>.csv)\n"
               "  crosscheck  OpenCL backend against the CPU reference (backend_check.csv)\n"
               "  motion      issue 8's motion targets against small-step references (cached in DIR/cache):\n"
               "              cloth, chain, handle cloth, stiff cloth, stiff drag, spinning tet bars, particle on a\n"
               "              moving pin\n"
               "              (printed; motion.csv, motion_series.csv, motion_reference.csv, moving_pin.csv)\n"
               "  teaser      the teaser: a 40 x 40 cloth of triangle strain and bending hinges with BE, BDF2\n"
               "              and the blend (teaser_triangles.csv, teaser_energy.csv, teaser_<integrator>.bin)\n"
               "  interaction grab, drag and release of a cloth corner through the per-frame input API, BE,\n"
               "              BDF2 and the blend: H, H*, the hand's work and the events (interaction.csv);\n"
               "              a tet bar bouncing on the ground: H, H*, friction, final projection (bounce.csv)\n"
               "  contact     tet bars of 1e5, 1e6 and 1e7 Pa thrown at 1, 3 and 6 m/s onto a plane, a sphere and\n"
               "              a box with BE, BDF2, IM and the blend: max(H - H*) / K_max, the deepest vertex, the\n"
               "              rebound, ms per frame (printed; contact_table.csv, contact_table.md)\n"
               "  all         all of the above in order\n"
               "  drop        a TetGen soft body (--mesh BASE, made by scripts/soft_body_mesh.sh) dropped on the\n"
               "              ground with BE, BDF2 and the blend (drop_surface.csv, drop_energy.csv,\n"
               "              drop_<integrator>.bin); not part of all, which needs no mesher\n"
               "  fold        self-contact: a cloth folding on the ground, dragged over a TetGen body's surface\n"
               "              (--mesh BASE) with BE, BDF2 and the blend (fold_triangles.csv, fold_body.csv,\n"
               "              fold_energy.csv, fold_<integrator>.bin); not part of all\n"
               "options:\n"
               "  --out DIR          output directory (default results)\n"
               "  --backend NAME     opencl (default; cpu when no OpenCL device exists) or cpu for the\n"
               "                     simulations; references are\n"
               "                     always computed on the CPU reference backend\n"
               "  --quick            smoke-test sizes (fewer frames and cells); not for reported numbers\n"
               "  --mesh BASE        drop, fold: the TetGen mesh BASE.node/BASE.ele\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace study;
  if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  StudyOptions options;
  bool backend_given = false;
  try {
    for (int a = 2; a < argc; ++a) {
      const std::string arg = argv[a];
      auto value = [&]() -> std::string {
        if (a + 1 >= argc) throw stabint::InvalidInputError(arg + " needs a value");
        return argv[++a];
      };
      if (arg == "--out")
        options.out = value();
      else if (arg == "--backend") {
        options.backend = stabint::parseBackend(value());
        backend_given = true;
      } else if (arg == "--quick")
        options.quick = true;
      else if (arg == "--mesh")
        options.mesh = value();
      else
        throw stabint::InvalidInputError("unknown option " + arg);
    }

    // The default backend is OpenCL (PoCL when there is no GPU), falling back to the CPU
    // reference when no OpenCL device exists; an explicit --backend never falls back.
    if (!backend_given) {
      options.backend = stabint::BackendKind::OpenCL;
      if (stabint::listOpenCLDevices().empty()) {
        progress("no OpenCL device found: running on the CPU reference backend");
        options.backend = stabint::BackendKind::CpuReference;
      }
    }

    struct Step {
      const char* name;
      void (*run)(const StudyOptions&);
    };
    const Step steps[] = {{"prefetch", runPrefetch},
                          {"table", runTable},
                          {"reference", runReference},
                          {"sweep", runSweep},
                          {"stability", runStability},
                          {"energy", runEnergy},
                          {"crosscheck", runCrosscheck},
                          {"motion", runMotion},
                          {"teaser", runTeaser},
                          {"interaction", runInteraction},
                          {"contact", runContact},
                          {"drop", runDrop},
                          {"fold", runFold}};
    bool found = false;
    for (const Step& s : steps) {
      // `drop` and `fold` need a mesh made by an external mesher, so `all` leaves them out.
      if (command == "all" ? s.run == runDrop || s.run == runFold : command != s.name) continue;
      found = true;
      progress(std::string("== ") + s.name + " (backend " + stabint::backendName(options.backend) + ", out " +
               options.out + ")");
      s.run(options);
    }
    if (!found) {
      std::fprintf(stderr, "stabint-study: unknown command '%s'\n", command.c_str());
      usage(stderr);
      return 2;
    }
    progress("done; CSV files in " + options.out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stabint-study: %s\n", e.what());
    return 1;
  }
  return 0;
}
