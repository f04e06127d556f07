"""Interactive viewer for stabint scenes, on polyscope (pip install -r requirements-viewer.txt).

Runs a scene file (.json), an OBJ cloth (.obj) or a built-in scene by name with any integrator.
Hold Shift and drag the body with the left mouse button: the nearest particle is grabbed
(Simulator.grab), follows the mouse in the plane facing the camera (set_pin_target every frame)
and is let go when the button is released (release). The panel switches the integrator, shows
H and the blend's target H* live, and pauses, steps or resets the run.

Switching the integrator keeps the simulation: the running simulator's checkpoint (time, state,
H*, the grabbed handle) is restored into a new Simulator with the other integrator, so the body
goes on from where it was and a drag in progress continues.

Usage: python viewer.py [SCENE] [--integrator blend] [--backend auto]
       python viewer.py [SCENE] --screenshot out.png [--frames 90]
The second form needs no user input: it plays a scripted drag (grab, move, switch integrator)
for the given number of frames, writes a screenshot and exits. Without a display ($DISPLAY unset:
a server, CI, a container) it renders off screen through EGL, out of the box.
"""
import argparse
import os
import sys

import numpy as np
import polyscope as ps
import polyscope.imgui as psim
import stabint

HISTORY = 300  # frames of H and H* in the plots


def load_scene(spec):
    if spec.endswith(".json"):
        return stabint.load_scene_file(spec)
    if spec.endswith(".obj"):
        return stabint.load_obj_cloth(spec)
    return stabint.builtin_scene(spec)


class Viewer:
    def __init__(self, scene, options, grab_stiffness):
        self.scene = scene
        self.options = options
        self.grab_stiffness = grab_stiffness
        self.integrators = stabint.all_integrators()
        self.reset()
        self.register_geometry()

    # ---- simulation ------------------------------------------------------------------------------
    def reset(self):
        self.sim = stabint.Simulator(self.scene, self.options)
        self.handle = None  # pin index of the grabbed particle while dragging
        self.vertex = None
        self.paused = False
        self.message = ""
        self.h = np.full(HISTORY, np.nan, dtype=np.float32)
        self.target = np.full(HISTORY, np.nan, dtype=np.float32)

    def switch_integrator(self, integrator):
        checkpoint = self.sim.checkpoint()
        previous = self.options.integrator
        self.options.integrator = integrator
        try:
            sim = stabint.Simulator(self.scene, self.options)
            sim.restore(checkpoint)  # time, state, H*, handles: the run goes on
        except stabint.Error as e:  # e.g. a system this integrator cannot factor: keep the old one
            self.options.integrator = previous
            self.message = f"cannot switch to {stabint.integrator_name(integrator)}: {e}"
            return
        self.sim = sim
        self.message = ""

    def step(self):
        try:
            report = self.sim.step()
        except stabint.NonFiniteStateError as e:  # a blow-up (FE, SE): refused, state kept
            self.paused = True
            self.message = f"step refused: {e}\nReset, or switch to another integrator."
            return
        self.h = np.roll(self.h, -1)
        self.target = np.roll(self.target, -1)
        self.h[-1] = report.energy.total
        self.target[-1] = report.target

    def grab(self, vertex):
        self.vertex = vertex
        self.handle = self.sim.grab(vertex, self.grab_stiffness)

    def drag_to(self, point):
        self.sim.set_pin_target(self.handle, np.asarray(point, dtype=np.float64))

    def let_go(self):
        self.sim.release(self.handle)
        self.handle = None
        self.vertex = None

    # ---- drawing ---------------------------------------------------------------------------------
    def register_geometry(self):
        x = self.sim.positions
        s = self.scene
        if len(s.triangles):
            self.body = ps.register_surface_mesh("body", x, s.triangles, edge_width=1.0)
        elif len(s.tets):
            tets = np.array([t.vertices for t in s.tets], dtype=np.int64)
            self.body = ps.register_volume_mesh("body", x, tets=tets)
        else:
            edges = np.array([[sp.a, sp.b] for sp in s.springs], dtype=np.int64).reshape(-1, 2)
            self.body = ps.register_curve_network("body", x, edges, radius=0.004)
            ps.register_point_cloud("particles", x, radius=0.008)
        # Mesh colliders, drawn where they are (their vertices move with the collider's center).
        self.meshes = [(i, c) for i, c in enumerate(s.colliders) if c.shape == stabint.ColliderShape.Mesh]
        for i, c in self.meshes:
            ps.register_surface_mesh(f"collider {i}", c.mesh_vertices, c.mesh_triangles, color=(0.6, 0.6, 0.65))

    def draw(self):
        x = self.sim.positions
        if isinstance(self.body, ps.CurveNetwork):
            self.body.update_node_positions(x)
        else:
            self.body.update_vertex_positions(x)
        if ps.has_point_cloud("particles"):
            ps.get_point_cloud("particles").update_point_positions(x)
        for i, c in self.meshes:
            shift = np.asarray(self.sim.collider_position(i)) - np.asarray(c.center)
            ps.get_surface_mesh(f"collider {i}").update_vertex_positions(c.mesh_vertices + shift)
        # The rubber band from the grabbed particle to the mouse.
        if self.handle is not None:
            nodes = np.array([x[self.vertex], self.sim.pin_target(self.handle)])
            ps.register_curve_network("grab", nodes, np.array([[0, 1]]), radius=0.006, color=(0.9, 0.2, 0.1))
        elif ps.has_curve_network("grab"):
            ps.remove_curve_network("grab")

    def panel(self):
        names = [stabint.integrator_name(i) for i in self.integrators]
        current = self.integrators.index(self.options.integrator)
        psim.PushItemWidth(160)  # a narrow panel leaves the body in view
        changed, chosen = psim.Combo("integrator", current, names)
        if changed and chosen != current:
            self.switch_integrator(self.integrators[chosen])
        _, self.paused = psim.Checkbox("pause", self.paused)
        psim.SameLine()
        if psim.Button("step"):
            self.step()
        psim.SameLine()
        if psim.Button("reset"):  # the scene's initial state, with the integrator chosen now
            self.reset()
        _, self.grab_stiffness = psim.SliderFloat("grab stiffness", self.grab_stiffness, 1.0, 1e4,
                                                  flags=psim.ImGuiSliderFlags_Logarithmic)
        psim.PopItemWidth()
        r = self.sim.last_report
        psim.TextWrapped(self.sim.backend_description)
        psim.TextUnformatted(f"t = {self.sim.time:.2f} s   step {self.sim.step_count}")
        psim.TextUnformatted(f"H  = {r.energy.total:10.4f} J")
        psim.TextUnformatted(f"  kinetic {r.energy.kinetic:.4f}, elastic {r.energy.elastic:.4f}, "
                             f"external {r.energy.external:.4f}")
        psim.TextUnformatted(f"H* = {r.target:10.4f} J   H - H* = {r.energy.total - r.target:+.4f} J")
        psim.TextUnformatted(f"blend: {stabint.blend_branch_name(r.branch)}, alpha {r.alpha:.3f}, "
                             f"scale {r.velocity_scale:.3f}")
        both = np.concatenate([self.h, self.target])
        both = both[np.isfinite(both)]
        lo, hi = (float(both.min()), float(both.max())) if both.size else (0.0, 1.0)
        pad = max(1e-6, 0.05 * (hi - lo))
        for label, values in (("H", self.h), ("H*", self.target)):
            psim.PlotLines(label, np.nan_to_num(values, nan=lo), overlay_text=label,
                           scale_min=lo - pad, scale_max=hi + pad, graph_size=(260, 60))
        psim.TextUnformatted("Shift + left drag: grab and pull the body")
        if self.message:
            psim.TextUnformatted(self.message)

    # ---- mouse -----------------------------------------------------------------------------------
    def mouse(self):
        io = psim.GetIO()
        if self.handle is None:
            if io.KeyShift and psim.IsMouseClicked(0) and not io.WantCaptureMouse:
                pick = ps.pick(screen_coords=io.MousePos)
                if pick.is_hit:
                    x = self.sim.positions
                    self.grab(int(np.argmin(np.linalg.norm(x - pick.position, axis=1))))
                    # Drag in the plane through the particle facing the camera; the camera
                    # stays still meanwhile.
                    self.plane_point = x[self.vertex].copy()
                    self.plane_normal = ps.get_view_camera_parameters().get_look_dir()
                    self.navigation = ps.get_navigation_style()
                    ps.set_navigation_style("none")
        elif psim.IsMouseDown(0):
            origin = ps.get_view_camera_parameters().get_position()
            ray = ps.screen_coords_to_world_ray(io.MousePos)
            denom = float(np.dot(ray, self.plane_normal))
            if abs(denom) > 1e-9:
                t = float(np.dot(self.plane_point - origin, self.plane_normal)) / denom
                self.drag_to(origin + t * ray)
        else:
            self.let_go()
            ps.set_navigation_style(self.navigation)

    def frame(self):
        self.mouse()
        if not self.paused:
            self.step()
        self.draw()
        self.panel()


def scripted(viewer, frames):
    """A drag without user input for --screenshot: grab the particle farthest from the pins,
    pull it sideways and up, switch to another integrator and back on the way, keep holding it."""
    chosen = viewer.options.integrator
    other = stabint.Integrator.BackwardEuler if chosen != stabint.Integrator.BackwardEuler \
        else stabint.Integrator.EnergyBlend
    x = viewer.sim.positions
    pinned = [p.vertex for p in viewer.scene.pins]
    far = int(np.argmax(np.min(np.linalg.norm(x[:, None, :] - x[pinned][None, :, :], axis=2), axis=1))) \
        if pinned else 0
    start = frames // 3
    for f in range(frames):
        if f == start:
            viewer.grab(far)
            origin = viewer.sim.positions[far].copy()
        if f > start:
            s = min(1.0, (f - start) / (frames / 3))
            viewer.drag_to(origin + s * np.array([0.4, 0.3, 0.2]))
        if f == start + 5:
            viewer.switch_integrator(other)
        if f == start + 10:
            viewer.switch_integrator(chosen)
        viewer.step()
        viewer.draw()
        ps.frame_tick()  # draws the panel through the user callback too


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="cloth",
                        help="scene file (.json), OBJ cloth (.obj) or built-in name "
                             f"({', '.join(stabint.builtin_scene_names())}); default: cloth")
    parser.add_argument("--integrator", default="blend", help="FE, SE, BE, BDF2, IM or blend")
    parser.add_argument("--backend", default="auto", help="cpu, opencl or auto")
    parser.add_argument("--grab-stiffness", type=float, default=300.0, help="N/m of the mouse handle")
    parser.add_argument("--screenshot", metavar="PNG", help="run a scripted drag, save a screenshot, exit")
    parser.add_argument("--frames", type=int, default=90, help="frames before the screenshot")
    args = parser.parse_args()

    options = stabint.SimulatorOptions(integrator=stabint.parse_integrator(args.integrator),
                                       backend=stabint.parse_backend(args.backend))
    scene = load_scene(args.scene)

    ps.set_program_name("stabint viewer")
    ps.set_up_dir("y_up")
    ps.set_ground_plane_mode("none")
    if args.screenshot:
        # No window is needed for a screenshot: on a machine without a display (a server, CI, a
        # container) polyscope renders off screen through EGL (Mesa's llvmpipe, or a GPU's driver).
        ps.set_allow_headless_backends(True)
    ps.init("openGL3_egl" if args.screenshot and not os.environ.get("DISPLAY") else "auto")
    viewer = Viewer(scene, options, args.grab_stiffness)
    if args.screenshot:
        ps.set_user_callback(viewer.panel)
        scripted(viewer, args.frames)
        ps.screenshot(os.path.abspath(args.screenshot), transparent_bg=False, include_UI=True)
        sim = viewer.sim
        print(f"{args.screenshot}: {sim.step_count} steps, H = {sim.last_report.energy.total:.4f} J, "
              f"H* = {sim.target:.4f} J ({stabint.integrator_name(viewer.options.integrator)})")
        return 0
    ps.set_user_callback(viewer.frame)
    ps.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
