// The simulator's classes: the options (from their field list, stabint/options_table.h), the
// reports (from their tables, stabint/types.hpp), Checkpoint and Simulator.
#include "fields.hpp"

#include <nanobind/stl/shared_ptr.h>

#include <memory>
#include <string>
#include <utility>

namespace stabint::py {

using namespace nb::literals;

// What the reports have beyond their fields (see bindExtras).
template <>
void bindExtras(nb::class_<EnergyReport>& c) {
  c.def_prop_ro("total", &EnergyReport::total, "H = kinetic + elastic + external.");
}
template <>
void bindExtras(nb::class_<PhaseTimes>& c) {
  c.def_prop_ro("total", &PhaseTimes::total, "The sum of the phases.");
}

namespace {

// A Python callable as a reporter: called with the GIL (Simulator.step releases it), with the
// simulator's own Python object and a copy of the report. What it raises leaves the library as a
// ReporterError whose cause() is the nb::python_error; the translator (module.cpp) raises the
// Python exception again, traceback and all.
class PyCallbackReporter : public Reporter {
 public:
  PyCallbackReporter(nb::callable function, int every) : Reporter(every), function_(std::move(function)) {
    name_ = nb::repr(function_).c_str();
  }
  ~PyCallbackReporter() override {
    nb::gil_scoped_acquire gil;  // the last reference may go where the GIL is released
    function_.reset();
  }
  void report(const Simulator& simulator, const StepReport& report) override {
    nb::gil_scoped_acquire gil;
    function_(nb::cast(&simulator, nb::rv_policy::reference), report);
  }
  std::string name() const override { return name_; }
  const nb::callable& function() const { return function_; }

 private:
  nb::callable function_;
  std::string name_;
};

void bindReporters(nb::module_& m) {
  nb::class_<Reporter>(m, "Reporter",
                       "Base of the per-frame reporters Simulator.add_reporter attaches: called after every "
                       "`every`-th accepted step (when step_count is a multiple of it); a refused step reports "
                       "nothing.")
      .def_prop_ro("every", &Reporter::every, "Reports after the steps whose step_count is a multiple of this.")
      .def_prop_ro("name", &Reporter::name, "The reporter as error messages name it.")
      .def("__repr__", [](const Reporter& r) { return r.name() + " every " + std::to_string(r.every()); });
  nb::class_<CsvReporter, Reporter>(
      m, "CsvReporter",
      "Writes one CSV row per reported step (stabint-run --csv's columns: frame = report.step + 1, time, "
      "energies, target, energy book, branch, alpha, velocity scale, iterations, energy evaluations, phase "
      "timings), 17 significant digits, each row flushed. Attach it with Simulator.add_reporter.")
      .def(nb::init<const std::string&, int>(), "path"_a, "every"_a = 1,
           "Creates or truncates `path` and writes the header; raises FileFormatError when it cannot be written.")
      .def("initial_row", &CsvReporter::initialRow, "simulator"_a,
           "Writes the row of the simulator's current state (frame step_count, its energy and target): call it "
           "before the first step for frame 0, the reference of every drift.")
      .def("row", &CsvReporter::row, "frame"_a, "report"_a, "Writes one row labelled `frame`.");
  nb::class_<PyCallbackReporter, Reporter>(
      m, "CallbackReporter",
      "A Python callable `function(sim, report)` as a reporter; Simulator.add_reporter(function, every) makes one.")
      .def(nb::init<nb::callable, int>(), "function"_a, "every"_a = 1)
      .def_prop_ro("function", &PyCallbackReporter::function);
}

}  // namespace

void bindSimulator(nb::module_& m) {
  // The options from their table (stabint/options_table.h, through FieldTable): a keyword per
  // field with the C++ default, a property per field, repr, pickling and ==; OpenCLOptions comes
  // with SimulatorOptions::opencl.
  bindStruct<SimulatorOptions>(m);
  bindStruct<OpenCLDeviceInfo>(m);
  m.def("list_opencl_devices", &listOpenCLDevices, "Every OpenCL device; empty when none is installed.");

  // The reports from their tables; StepReport's energy and times bring EnergyReport and PhaseTimes.
  bindStruct<StepReport>(m);

  nb::class_<Checkpoint>(m, "Checkpoint",
                         "A snapshot of a running simulation (Simulator.checkpoint()): time, step count, state, BDF2 "
                         "history, H* and the per-frame forcing (pin targets, external forces), not the options. "
                         "Simulator.restore() of it, into a Simulator of the same scene, options and backend, "
                         "continues bit for bit. Its bytes are a versioned format of this library version and "
                         "byte order. Immutable; picklable (through its bytes).")
      .def_prop_ro("time", &Checkpoint::time, "Simulation time of the snapshot.")
      .def_prop_ro("step_count", &Checkpoint::stepCount, "Steps taken before the snapshot.")
      .def_prop_ro(
          "bytes", [](const Checkpoint& c) { return nb::bytes(c.bytes().data(), c.bytes().size()); },
          "The serialized form (what save() writes), as a new bytes object.")
      .def_static(
          "from_bytes",
          [](nb::bytes data, const std::string& origin) {
            return Checkpoint::fromBytes(std::string(data.c_str(), data.size()), origin);
          },
          "data"_a, "origin"_a = "checkpoint",
          "A checkpoint from its bytes. Raises FileFormatError naming `origin` and the problem when "
          "they are malformed.")
      .def("save", &Checkpoint::save, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
           "Writes the bytes to a file. Raises FileFormatError when it cannot be written completely.")
      .def_static("load", &Checkpoint::load, "path"_a, nb::call_guard<nb::gil_scoped_release>(),
                  "Reads a file written by save(). Raises FileFormatError (file) when missing or malformed.")
      .def("__getstate__", [](const Checkpoint& c) { return nb::bytes(c.bytes().data(), c.bytes().size()); })
      .def("__setstate__",
           [](Checkpoint& c, nb::bytes data) {
             new (&c) Checkpoint(Checkpoint::fromBytes(std::string(data.c_str(), data.size()), "pickled checkpoint"));
           })
      .def("__repr__", [](const Checkpoint& c) {
        return "Checkpoint(step_count=" + std::to_string(c.stepCount()) + ", time=" + std::to_string(c.time()) + ", " +
               std::to_string(c.bytes().size()) + " bytes)";
      });

  bindReporters(m);

  nb::class_<Simulator>(m, "Simulator",
                        "Steps a scene with one integrator. The scene is validated and copied at construction.")
      .def(nb::init<const Scene&, const SimulatorOptions&>(), "scene"_a, "options"_a = SimulatorOptions(),
           "Raises InvalidInputError for a bad scene or option, OpenCLError subtypes for the OpenCL backend.")
      .def(
          "step", [](Simulator& s) { return s.step(); }, nb::call_guard<nb::gil_scoped_release>(),
          "Advances one step and returns its report. Raises NonFiniteStateError (EnergyLimitError) when the "
          "step is refused; the simulator then keeps the last accepted state. The GIL is released while it "
          "runs, so simulators may step in parallel threads; one Simulator must not be used by two threads at once. "
          "After an accepted step the reporters due are called (add_reporter); what a Python reporter raises "
          "propagates from here as that exception, another reporter's failure as ReporterError, and the step "
          "stays accepted either way.")
      .def(
          "add_reporter",
          [](Simulator& s, std::shared_ptr<Reporter> reporter) {
            s.addReporter(reporter);
            return reporter;
          },
          "reporter"_a, "Attaches a Reporter (e.g. a CsvReporter) and returns it.")
      .def(
          "add_reporter",
          [](Simulator& s, nb::callable function, int every) {
            std::shared_ptr<Reporter> reporter = std::make_shared<PyCallbackReporter>(std::move(function), every);
            s.addReporter(reporter);
            return reporter;
          },
          "function"_a, "every"_a = 1,
          "Calls `function(sim, report)` after every `every`-th accepted step (when step_count is a multiple of "
          "it), after the reporters attached before; a refused step reports nothing. Returns the CallbackReporter "
          "(for remove_reporter). An exception the function raises propagates from step() as itself, with the "
          "step accepted; the reporters after it are skipped for that step. The function must not step the "
          "simulator.")
      .def("remove_reporter", &Simulator::removeReporter, "reporter"_a,
           "Detaches a reporter add_reporter returned; False when it was not attached.")
      .def("clear_reporters", &Simulator::clearReporters, "Detaches every reporter.")
      .def_prop_ro("reporters", &Simulator::reporters, "The attached reporters, in the order they are called.")
      .def_prop_ro(
          "positions", [](const Simulator& s) { return rowsCopy(s.positions()); }, nb::rv_policy::move,
          "(n, 3) current positions, a C-contiguous float64 copy (x y z per particle).")
      .def_prop_ro(
          "velocities", [](const Simulator& s) { return rowsCopy(s.velocities()); }, nb::rv_policy::move,
          "(n, 3) current velocities, a C-contiguous float64 copy.")
      .def_prop_ro("time", &Simulator::time)
      .def_prop_ro("step_count", &Simulator::stepCount)
      .def_prop_ro("target", &Simulator::target, "H*, the energy the blend tracks.")
      .def("energy", &Simulator::energy, "Energies of the current state.")
      .def_prop_ro("energy_scale", &Simulator::energyScale, "E_scale of the blend tolerance.")
      .def_prop_ro(
          "scene", [](const Simulator& s) { return s.scene(); }, "A copy of the simulated scene.")
      .def_prop_ro(
          "options", [](const Simulator& s) { return s.options(); }, "A copy of the options.")
      .def_prop_ro(
          "last_report", [](const Simulator& s) { return s.lastReport(); },
          "Report of the last completed step (a copy; zeros before the first).")
      .def_prop_ro("backend_description", &Simulator::backendDescription)
      // Per-frame input (docs/method.md, "Per-frame input"): every call validates first and a
      // rejected one (InvalidInputError naming the problem) changes nothing.
      .def("set_pin_target", &Simulator::setPinTarget, "pin"_a, "target"_a,
           "Pin `pin` (an index into scene.pins) moves linearly from its current target to `target` (3,) over the "
           "next step and stays there; its scripted law is no longer used. Call it every frame with the hand's "
           "position to drag; the work is booked in H* like a scripted pin's. Raises InvalidInputError for a pin "
           "out of range or a non-finite target.")
      .def(
          "set_pin_target",
          [](Simulator& s, int pin, const std::array<double, 3>& target) {
            s.setPinTarget(pin, Eigen::Vector3d(target[0], target[1], target[2]));
          },
          "pin"_a, "target"_a, "The same with the target as a sequence of three numbers, e.g. (x, y, z).")
      .def("pin_target", &Simulator::pinTarget, "pin"_a,
           "(3,) current target of pin `pin` (its law's or the last set value at the current time), a copy.")
      .def("set_collider_position", &Simulator::setColliderPosition, "collider"_a, "position"_a,
           "Collider `collider` (an index into scene.colliders) translates linearly from where it is to "
           "`position` (3,) over the next step and stays there; `position` is where its reference point "
           "(Collider.center) goes, the rest of its shape moves with it. Call it every frame with a tool's or the "
           "mouse's position; the collider's work is booked in H* like a dragged pin's. Raises InvalidInputError "
           "for a collider out of range or a position that is not finite (nothing changes).")
      .def(
          "set_collider_position",
          [](Simulator& s, int collider, const std::array<double, 3>& p) {
            s.setColliderPosition(collider, Eigen::Vector3d(p[0], p[1], p[2]));
          },
          "collider"_a, "position"_a, "The same with the position as a sequence of three numbers.")
      .def("set_collider_velocity", &Simulator::setColliderVelocity, "collider"_a, "velocity"_a,
           "Collider `collider` translates with `velocity` (3,) m/s (zeros stop it) from where it is now on, "
           "until the next set_collider_position or set_collider_velocity. Booked as set_collider_position.")
      .def(
          "set_collider_velocity",
          [](Simulator& s, int collider, const std::array<double, 3>& v) {
            s.setColliderVelocity(collider, Eigen::Vector3d(v[0], v[1], v[2]));
          },
          "collider"_a, "velocity"_a, "The same with the velocity as a sequence of three numbers.")
      .def("collider_position", &Simulator::colliderPosition, "collider"_a,
           "(3,) where collider `collider`'s reference point (Collider.center) is now, a copy.")
      .def("collider_velocity", &Simulator::colliderVelocity, "collider"_a,
           "(3,) the collider's velocity over the last step (its set or scene velocity when it moves on), a copy.")
      .def("set_external_forces", &Simulator::setExternalForces, "forces"_a,
           "(n, 3) per-particle forces in newtons, on top of gravity and force fields: they ramp from their "
           "current value to `forces` over the next step and persist until the next call (pass zeros to remove "
           "them). Booked in H* by the forcing rule.")
      .def("set_state", &Simulator::setState, "positions"_a, "velocities"_a,
           "Replaces positions and velocities ((n, 3) each, finite): teleport, reset. H* moves by the jump of H "
           "(the next report's event_energy) and BDF2 restarts from this state, as a fresh simulator would.")
      .def("set_positions", &Simulator::setPositions, "positions"_a,
           "Replaces the positions ((n, 3), finite), keeping the velocities; booked as set_state.")
      .def("set_velocities", &Simulator::setVelocities, "velocities"_a,
           "Replaces the velocities ((n, 3), finite), keeping the positions; booked as set_state.")
      .def("set_iterations", &Simulator::setIterations, "iterations"_a,
           "Local/global iteration budget of every later step (>= 1); time, state and H* are kept, "
           "options.iterations follows.")
      .def("grab", &Simulator::grab, "vertex"_a, "stiffness"_a,
           "Attaches a handle to particle `vertex`: a new pin of `stiffness` (> 0) whose target is the particle's "
           "current position (no energy jump). Returns its pin index, for set_pin_target and release. The global "
           "factors get a rank-1 update instead of a refactorization.")
      .def("release", &Simulator::release, "pin"_a,
           "Detaches pin `pin` (a handle or a scene pin): its stiffness becomes 0 and its index stays valid; the "
           "pin's energy leaves H and H* alike (the next report's event_energy).")
      .def("set_element_stiffness",
           nb::overload_cast<ElementKind, const std::vector<int>&, double>(&Simulator::setElementStiffness), "kind"_a,
           "indices"_a, "stiffness"_a,
           "Elements `indices` of `kind` get `stiffness` (finite, >= 0; kept by disabled elements). A discontinuous "
           "event: the energy jump enters H and H* alike (the next report's event_energy); the global factors get "
           "rank updates. All indices are checked first: InvalidInputError changes nothing.")
      .def("set_element_stiffness", nb::overload_cast<ElementKind, int, double>(&Simulator::setElementStiffness),
           "kind"_a, "index"_a, "stiffness"_a, "One element; see the list form.")
      .def("set_element_enabled",
           nb::overload_cast<ElementKind, const std::vector<int>&, bool>(&Simulator::setElementEnabled), "kind"_a,
           "indices"_a, "enabled"_a,
           "Disables (weight 0, stiffness kept) or enables elements `indices` of `kind`; booked as "
           "set_element_stiffness.")
      .def("set_element_enabled", nb::overload_cast<ElementKind, int, bool>(&Simulator::setElementEnabled), "kind"_a,
           "index"_a, "enabled"_a, "One element; see the list form.")
      .def("element_enabled", &Simulator::elementEnabled, "kind"_a, "index"_a)
      .def("checkpoint", &Simulator::checkpoint, nb::call_guard<nb::gil_scoped_release>(),
           "A Checkpoint of the current simulation (the GIL is released while it is written).")
      .def("restore", &Simulator::restore, "checkpoint"_a, nb::call_guard<nb::gil_scoped_release>(),
           "Continues from a Checkpoint of a Simulator of the same scene: time, step count, state, H* and the "
           "per-frame forcing come back; options stay this simulator's. Raises InvalidInputError (nothing "
           "changed) when it belongs to another scene (particle or pin count, masses or rest shape differ).");
}

}  // namespace stabint::py
