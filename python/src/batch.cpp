// BatchSimulator (include/stabint/batch.hpp): many independent scenes stepped together. One
// method per .def below, in the order of batch.hpp: a new method of the batch is one more .def.
#include "common.hpp"

#include <array>

namespace stabint::py {

using namespace nb::literals;

void bindBatch(nb::module_& m) {
  nb::class_<BatchStepReport>(m, "BatchStepReport", "What one BatchSimulator.step did, scene by scene.")
      .def_ro("scenes", &BatchStepReport::scenes,
              "One StepReport per scene, as its own Simulator.step would report it (a refused or inactive "
              "scene's describes its kept state).")
      .def_ro("refusals", &BatchStepReport::refusals,
              "Per scene: '' when it stepped, else why its step was refused (the message its own Simulator "
              "would have raised) or that it is inactive since a refused step.")
      .def_ro("times", &BatchStepReport::times,
              "Wall-clock seconds per phase of the whole batch's step (the scenes share every pass, so "
              "their own reports' times are zero).");
  nb::class_<BatchCheckpoint>(
      m, "BatchCheckpoint",
      "A snapshot of every scene of a batch (BatchSimulator.checkpoint()): the batch's time and "
      "one Checkpoint per scene, each restorable into a Simulator of that scene. "
      "BatchSimulator.restore() of it, into a batch of the same scenes and options, continues bit "
      "for bit when that batch has the checkpoint's pins and element stiffnesses (the same "
      "batch, or a new one when none were changed), else to round-off. Its bytes are one file: "
      "a versioned header, the time and the scenes' checkpoints. Immutable; picklable.")
      .def_prop_ro("time", &BatchCheckpoint::time, "The batch's time at the snapshot.")
      .def("__len__", &BatchCheckpoint::size)
      .def_prop_ro("size", &BatchCheckpoint::size, "Number of scenes.")
      .def("scene", &BatchCheckpoint::scene, "scene"_a, "The Checkpoint of one scene (a copy).")
      .def_prop_ro(
          "bytes",
          [](const BatchCheckpoint& c) {
            const std::string b = c.bytes();
            return nb::bytes(b.data(), b.size());
          },
          "The serialized form (what save() writes), as a new bytes object.")
      .def_static(
          "from_bytes",
          [](nb::bytes data, const std::string& origin) {
            return BatchCheckpoint::fromBytes(std::string(data.c_str(), data.size()), origin);
          },
          "data"_a, "origin"_a = "batch checkpoint",
          "A batch checkpoint from its bytes. Raises FileFormatError naming `origin` and the problem when they are "
          "malformed.")
      .def("save", &BatchCheckpoint::save, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
           "Writes the bytes to one file. Raises FileFormatError when it cannot be written completely.")
      .def_static("load", &BatchCheckpoint::load, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
                  "Reads a file written by save(). Raises FileFormatError when missing or malformed.")
      .def("__getstate__",
           [](const BatchCheckpoint& c) {
             const std::string b = c.bytes();
             return nb::bytes(b.data(), b.size());
           })
      .def("__setstate__",
           [](BatchCheckpoint& c, nb::bytes data) {
             new (&c) BatchCheckpoint(
                 BatchCheckpoint::fromBytes(std::string(data.c_str(), data.size()), "pickled batch checkpoint"));
           })
      .def("__repr__", [](const BatchCheckpoint& c) {
        return "BatchCheckpoint(size=" + std::to_string(c.size()) + ", time=" + std::to_string(c.time()) + ")";
      });
  nb::class_<BatchSimulator>(m, "BatchSimulator",
                             "Steps many independent scenes with one set of options: one solve and one block-diagonal "
                             "factor for all, and per scene its own energies, target, blend decisions and refusals "
                             "(docs/method.md, \"Batches\"). The scenes are validated and copied at construction.")
      .def(nb::init<const std::vector<Scene>&, const SimulatorOptions&>(), "scenes"_a, "options"_a = SimulatorOptions(),
           "Raises InvalidInputError naming the scene (\"scene 3: ...\") for a bad scene, scenes with different "
           "gravity, or bad option values (every solver option runs per scene: each acceleration and its "
           "stops by accuracy, and CG on each scene's block).")
      .def(
          "step", [](BatchSimulator& b) { return b.step(); }, nb::call_guard<nb::gil_scoped_release>(),
          "Advances every active scene one step and returns the BatchStepReport. Never raises for a scene that "
          "blows up: its step is refused (report.refusals), its state kept, and it stays inactive until set_state.")
      .def("__len__", &BatchSimulator::size)
      .def_prop_ro("size", &BatchSimulator::size, "Number of scenes.")
      .def("active", &BatchSimulator::active, "scene"_a, "False once a step of the scene was refused.")
      .def(
          "positions", [](const BatchSimulator& b, int s) { return rowsCopy(b.positions(s)); }, "scene"_a,
          nb::rv_policy::move, "(n_s, 3) positions of one scene (a copy).")
      .def(
          "velocities", [](const BatchSimulator& b, int s) { return rowsCopy(b.velocities(s)); }, "scene"_a,
          nb::rv_policy::move, "(n_s, 3) velocities of one scene (a copy).")
      .def_prop_ro(
          "all_positions", [](const BatchSimulator& b) { return rowsCopy(b.allPositions()); }, nb::rv_policy::move,
          "Every scene's positions one after another (a copy); scene s's rows start at first_particle(s).")
      .def("first_particle", &BatchSimulator::firstParticle, "scene"_a)
      .def("num_particles", &BatchSimulator::numParticles, "scene"_a)
      .def_prop_ro("time", nb::overload_cast<>(&BatchSimulator::time, nb::const_), "The batch's time.")
      .def("scene_time", nb::overload_cast<int>(&BatchSimulator::time, nb::const_), "scene"_a,
           "Time of the scene's last accepted state.")
      .def("step_count", &BatchSimulator::stepCount, "scene"_a)
      .def("target", &BatchSimulator::target, "scene"_a, "H* of the scene.")
      .def("energy", &BatchSimulator::energy, "scene"_a, "Energies of the scene's current state.")
      .def("energy_scale", &BatchSimulator::energyScale, "scene"_a, "E_scale of the scene alone.")
      .def_prop_ro(
          "options", [](const BatchSimulator& b) { return b.options(); }, "A copy of the options.")
      .def_prop_ro("backend_description", &BatchSimulator::backendDescription)
      .def("set_state", &BatchSimulator::setState, "scene"_a, "positions"_a, "velocities"_a,
           "Replaces one scene's positions and velocities ((n_s, 3) each, finite), booked in that scene's H* "
           "only; a refused scene steps again. Raises InvalidInputError naming the scene for bad input.")
      .def("set_states", &BatchSimulator::setStates, "scenes"_a, "positions"_a, "velocities"_a,
           "set_state of several scenes at once (a list of scene indices, each at most once, with one (n_s, 3) "
           "array of positions and of velocities per scene): the same events bit for bit, with one wait on a "
           "device. Everything is checked first; on InvalidInputError no scene changes.")
      .def("set_iterations", &BatchSimulator::setIterations, "iterations"_a,
           "Local/global iteration budget of every later step of every scene (>= 1); time, states and "
           "targets are kept, options.iterations follows.")
      .def(
          "set_pin_target",
          [](BatchSimulator& b, int scene, int pin, const std::array<double, 3>& target) {
            b.setPinTarget(scene, pin, Eigen::Vector3d(target[0], target[1], target[2]));
          },
          "scene"_a, "pin"_a, "target"_a,
          "Pin `pin` of scene `scene` (an index into that scene's pins) moves linearly to `target` (x, y, z) over "
          "the next step and stays there, as Simulator.set_pin_target: its work is booked in that scene's H* only.")
      .def("pin_target", &BatchSimulator::pinTarget, "scene"_a, "pin"_a, "(3,) current target of a pin of the scene.")
      .def("set_external_forces", &BatchSimulator::setExternalForces, "scene"_a, "forces"_a,
           "(n_s, 3) per-particle forces of one scene, as Simulator.set_external_forces (booked in its H* only).")
      .def(
          "set_collider_position",
          [](BatchSimulator& b, int scene, int collider, const std::array<double, 3>& p) {
            b.setColliderPosition(scene, collider, Eigen::Vector3d(p[0], p[1], p[2]));
          },
          "scene"_a, "collider"_a, "position"_a, "As Simulator.set_collider_position, for one scene's collider.")
      .def(
          "set_collider_velocity",
          [](BatchSimulator& b, int scene, int collider, const std::array<double, 3>& v) {
            b.setColliderVelocity(scene, collider, Eigen::Vector3d(v[0], v[1], v[2]));
          },
          "scene"_a, "collider"_a, "velocity"_a, "As Simulator.set_collider_velocity, for one scene's collider.")
      .def("collider_position", &BatchSimulator::colliderPosition, "scene"_a, "collider"_a)
      .def("collider_velocity", &BatchSimulator::colliderVelocity, "scene"_a, "collider"_a)
      .def("grab", &BatchSimulator::grab, "scene"_a, "vertex"_a, "stiffness"_a,
           "As Simulator.grab, in one scene; returns the new pin's index in that scene's pins.")
      .def("release", &BatchSimulator::release, "scene"_a, "pin"_a, "As Simulator.release, in one scene.")
      .def("set_element_stiffness",
           nb::overload_cast<int, ElementKind, const std::vector<int>&, double>(&BatchSimulator::setElementStiffness),
           "scene"_a, "kind"_a, "indices"_a, "stiffness"_a, "As Simulator.set_element_stiffness, in one scene.")
      .def("set_element_stiffness",
           nb::overload_cast<int, ElementKind, int, double>(&BatchSimulator::setElementStiffness), "scene"_a, "kind"_a,
           "index"_a, "stiffness"_a)
      .def("set_element_enabled",
           nb::overload_cast<int, ElementKind, const std::vector<int>&, bool>(&BatchSimulator::setElementEnabled),
           "scene"_a, "kind"_a, "indices"_a, "enabled"_a, "As Simulator.set_element_enabled, in one scene.")
      .def("set_element_enabled", nb::overload_cast<int, ElementKind, int, bool>(&BatchSimulator::setElementEnabled),
           "scene"_a, "kind"_a, "index"_a, "enabled"_a)
      .def("element_enabled", &BatchSimulator::elementEnabled, "scene"_a, "kind"_a, "index"_a)
      .def("checkpoint", nb::overload_cast<int>(&BatchSimulator::checkpoint, nb::const_), "scene"_a,
           "Snapshot of one scene as a Checkpoint: it restores into a Simulator of that scene (same options), or "
           "into that scene of a batch of the same scenes (restore(scene, checkpoint)).")
      .def("checkpoint", nb::overload_cast<>(&BatchSimulator::checkpoint, nb::const_),
           "Snapshot of every scene as a BatchCheckpoint (restore(checkpoint)).")
      .def("restore", nb::overload_cast<int, const Checkpoint&>(&BatchSimulator::restore), "scene"_a, "checkpoint"_a,
           "Continues one scene from a Checkpoint of it (this batch's or its own Simulator's) taken at the batch's "
           "time: the scenes share the batch's time. Raises InvalidInputError naming the scene, with nothing "
           "changed, for a checkpoint of another scene, time or BDF2 history.")
      .def("restore", nb::overload_cast<const BatchCheckpoint&>(&BatchSimulator::restore), "checkpoint"_a,
           "Continues every scene from a BatchCheckpoint of a batch of the same scenes and options. Raises "
           "InvalidInputError, with nothing changed, for another number of scenes or a checkpoint of another scene "
           "(naming it).");
}

}  // namespace stabint::py
