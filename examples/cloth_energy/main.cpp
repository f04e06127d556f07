// A hanging cloth stepped with the paper's energy-tracking blend; prints the energy per frame.
//   cloth_energy [frames] [cpu|opencl|auto]
// The default backend is auto: a GPU when there is one, else the CPU reference (the description
// says which).
#include <stabint/stabint.hpp>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 30;
  try {
    stabint::ClothGridParams cloth;
    cloth.nx = 12;
    cloth.ny = 12;
    const stabint::Scene scene = stabint::makeClothGrid(cloth);

    stabint::SimulatorOptions options;
    options.integrator = stabint::Integrator::EnergyBlend;
    options.time_step = 1.0 / 60.0;
    options.backend = stabint::parseBackend(argc > 2 ? argv[2] : "auto");
    auto sim = std::make_unique<stabint::Simulator>(scene, options);
    std::printf("# %s, %d particles, %s\n", scene.name.c_str(), scene.numParticles(),
                sim->backendDescription().c_str());
    std::printf("frame time kinetic elastic external total target branch\n");
    for (int frame = 1; frame <= frames; ++frame) {
      const stabint::StepReport& r = sim->step();
      std::printf("%d %.4f %.6e %.6e %.6e %.6e %.6e %s\n", frame, r.time, r.energy.kinetic, r.energy.elastic,
                  r.energy.external, r.energy.total(), r.target, stabint::blendBranchName(r.branch));
    }
  } catch (const stabint::Error& e) {
    std::fprintf(stderr, "cloth_energy: %s\n", e.what());
    return 1;
  }
  return 0;
}
