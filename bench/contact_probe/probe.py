"""The contact probe's bodies, colliders and run loop (bench/contact_probe/sweep.py runs the grid):
drops on scenes the test suite does not build, each measured for the contact issue's promises:
max(H - H*) over the run's largest kinetic energy, the deepest vertex inside a collider after a
step, vertices that pass through a thin collider, and non-finite or refused steps. Needs only
numpy and the installed stabint package."""
import math
import os
import numpy as np
import stabint

CS = stabint.ColliderShape
SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir, 'scenes')
G = 9.81


# ----------------------------------------------------------------------------- geometry helpers
def rot_matrix(axis, deg):
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    t = math.radians(deg)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def lump_tet_masses(x, tets, density):
    m = np.zeros(len(x))
    for t in tets:
        a, b, c, d = x[t]
        vol = abs(np.linalg.det(np.array([b - a, c - a, d - a]))) / 6.0
        m[list(t)] += density * vol / 4.0
    return m


def orient_tets(x, tets):
    out = []
    for t in tets:
        a, b, c, d = x[t]
        if np.linalg.det(np.array([b - a, c - a, d - a])) < 0:
            t = [t[0], t[2], t[1], t[3]]
        out.append(list(t))
    return np.array(out)


# ----------------------------------------------------------------------------- bodies
def place(scene, lift, speed, R=None, shift=(0, 0, 0), vel_dir=(0, -1, 0)):
    """Rotate (positions and rest), put lowest point at y=lift, give uniform velocity."""
    p = scene.positions
    if R is not None:
        c = p.mean(0)
        p = (p - c) @ R.T + c
        scene.rest_positions = p.copy()
    p = p + np.asarray(shift, float)
    p[:, 1] += lift - p[:, 1].min()
    scene.positions = p
    rp = scene.rest_positions
    scene.rest_positions = rp - rp.mean(0) + p.mean(0)  # rest shape moves with it (no effect on elastic energy)
    v = np.zeros_like(p)
    v[:] = speed * np.asarray(vel_dir, float)
    scene.velocities = v
    return scene


def bar(E=1e5, n=(16, 4, 4), lift=0.05, speed=3.0, R=None, damping=0.0, shift=(0, 0, 0)):
    s = stabint.tet_bar(nx=n[0], ny=n[1], nz=n[2], stiffness=E, damping=damping)
    s.pins.clear()
    # center in x/z around origin
    p = s.positions
    p[:, 0] -= 0.5
    p[:, 2] -= 0.125
    s.positions = p
    s.rest_positions = p.copy()
    return place(s, lift, speed, R, shift)


def medit_body(E=1e5, scale=1.0, R=None, lift=0.05, speed=3.0):
    s = stabint.load_medit(os.path.join(SCENES, 'bar.mesh'), stabint.SolidMaterial(density=1000.0, stiffness=E))
    p = s.positions * scale
    p -= p.mean(0)
    s = stabint.scene_from_arrays(p, lump_tet_masses(p, np.array([list(t.vertices) for t in s.tets]), 1000.0),
                                  tets=np.array([list(t.vertices) for t in s.tets]), tet_stiffness=E,
                                  name='medit')
    return place(s, lift, speed, R)


def tet_ball(E=1e5, radius=0.2, n=6, lift=0.05, speed=3.0, density=1000.0):
    """A cube tet grid (tet_bar connectivity) mapped onto a ball (cube->sphere map)."""
    s = stabint.tet_bar(nx=n, ny=n, nz=n, length=1.0, width=1.0)
    p = s.positions.copy()
    q = (p - p.min(0)) / (p.max(0) - p.min(0)) * 2 - 1  # [-1,1]^3
    x, y, z = q[:, 0], q[:, 1], q[:, 2]
    sx = x * np.sqrt(1 - y * y / 2 - z * z / 2 + y * y * z * z / 3)
    sy = y * np.sqrt(1 - z * z / 2 - x * x / 2 + z * z * x * x / 3)
    sz = z * np.sqrt(1 - x * x / 2 - y * y / 2 + x * x * y * y / 3)
    P = np.stack([sx, sy, sz], 1) * radius
    tets = orient_tets(P, np.array([list(t.vertices) for t in s.tets]))
    sc = stabint.scene_from_arrays(P, lump_tet_masses(P, tets, density), tets=tets, tet_stiffness=E, name='ball')
    return place(sc, lift, speed)


def cloth(n=20, height=0.4, speed=5.0, stretch=1e3, R=None, model='springs'):
    s = stabint.cloth_grid(nx=n, ny=n, model=model) if model != 'springs' else stabint.cloth_grid(nx=n, ny=n, stretch_stiffness=stretch)
    s.pins.clear()
    p = s.positions
    q = np.zeros_like(p)
    q[:, 0] = p[:, 0] - 0.5
    q[:, 1] = height
    q[:, 2] = p[:, 1] - 0.5
    s.positions = q
    s.rest_positions = q.copy()
    v = np.zeros_like(q)
    v[:, 1] = -speed
    s.velocities = v
    if R is not None:
        q2 = q @ R.T
        q2[:, 1] += height - q2[:, 1].min()
        s.positions = q2
        s.rest_positions = q2.copy()
    return s


# ----------------------------------------------------------------------------- colliders
def plane(y=0.0, normal=(0, 1, 0), friction=0.0, restitution=1.0, center=None):
    n = np.asarray(normal, float)
    n /= np.linalg.norm(n)
    c = np.array([0, y, 0.0]) if center is None else np.asarray(center, float)
    return stabint.Collider(shape=CS.Plane, center=c, normal=n, friction=friction, restitution=restitution)


def sphere(center, r, friction=0.0, restitution=1.0):
    return stabint.Collider(shape=CS.Sphere, center=np.asarray(center, float), radius=r, friction=friction,
                            restitution=restitution)


def box(center, half, friction=0.0, restitution=1.0):
    return stabint.Collider(shape=CS.Box, center=np.asarray(center, float), half_extents=np.asarray(half, float),
                            friction=friction, restitution=restitution)


def capsule(a, b, r, friction=0.0, restitution=1.0):
    return stabint.Collider(shape=CS.Capsule, center=np.asarray(a, float), end=np.asarray(b, float), radius=r,
                            friction=friction, restitution=restitution)


def icosphere(sub=2):
    t = (1.0 + 5 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(sub):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[k] = len(v) - 1
            return mid[k]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return np.array(v), np.array(f)


def box_mesh(half):
    V = np.array([[(1 if i & 1 else -1), (1 if i & 2 else -1), (1 if i & 4 else -1)] for i in range(8)], float)
    V *= np.asarray(half, float)
    F = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                  [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    return V, F


def mesh_collider(V, F, center=(0, 0, 0), R=None, friction=0.0, restitution=1.0):
    V = np.asarray(V, float)
    if R is not None:
        V = V @ R.T
    V = V + np.asarray(center, float)
    return stabint.Collider(shape=CS.Mesh, center=np.asarray(center, float), mesh_vertices=np.asfortranarray(V),
                            mesh_triangles=[list(map(int, t)) for t in F], friction=friction, restitution=restitution)


def tet_surface_mesh(scene):
    F = np.asarray(stabint.tet_surface(scene))
    used = np.unique(F)
    remap = -np.ones(scene.num_particles, int)
    remap[used] = np.arange(len(used))
    return scene.positions[used], remap[F]


# ----------------------------------------------------------------------------- depth (>0 inside)
def depth(col, x, t=0.0):
    c = np.asarray(col.center) + t * np.asarray(col.velocity)
    sh = col.shape
    if sh == CS.Plane:
        n = np.asarray(col.normal) / np.linalg.norm(col.normal)
        return -(x - c) @ n
    if sh == CS.Sphere:
        return col.radius - np.linalg.norm(x - c, axis=1)
    if sh == CS.Capsule:
        e = np.asarray(col.end) + t * np.asarray(col.velocity)
        d = e - c
        s = np.clip(((x - c) @ d) / (d @ d), 0, 1)
        return col.radius - np.linalg.norm(x - (c + s[:, None] * d), axis=1)
    if sh == CS.Box:
        h = np.asarray(col.half_extents)
        q = np.abs(x - c) - h
        inside = (q < 0).all(1)
        return np.where(inside, -q.max(1), -np.linalg.norm(np.maximum(q, 0), axis=1))
    if sh == CS.Mesh:  # convex meshes only: depth = min over face planes of distance inward
        V = np.asarray(col.mesh_vertices) + t * np.asarray(col.velocity)
        F = np.asarray(col.mesh_triangles)
        a, b, cc = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        n = np.cross(b - a, cc - a)
        n /= np.linalg.norm(n, axis=1)[:, None]
        s = (x @ n.T) - np.sum(n * a, 1)[None, :]  # signed distance to each face plane (>0 outside)
        return -s.max(1)
    raise ValueError(sh)


# ----------------------------------------------------------------------------- run
INTEG = dict(blend=stabint.Integrator.EnergyBlend, BE=stabint.Integrator.BackwardEuler,
             BDF2=stabint.Integrator.BDF2, IM=stabint.Integrator.ImplicitMidpoint)


def make_options(integrator='blend', h=1 / 30, iters=10, backend='cpu', precision='double', **kw):
    o = stabint.SimulatorOptions(**kw)
    o.integrator = INTEG[integrator]
    o.time_step = h
    o.iterations = iters
    if backend == 'opencl':
        o.backend = stabint.BackendKind.OpenCL
        oc = stabint.OpenCLOptions()
        oc.precision = stabint.Precision.Float if precision == 'float' else stabint.Precision.Double
        o.opencl = oc
    return o


def run(scene, options, frames=60, through=None, keep_traj=False):
    """through: list of (collider_index, direction d, reach, half_thickness) — a vertex that starts
    before the collider (x0-c).d < 0 within `reach` of the axis passes through if (x-c).d > half_thickness."""
    res = dict(frames=0, refused=None, err=None, excess=0.0, Kmax=0.0, deepest=0.0, deepest_frame=-1,
               deepest_col=-1, nonfinite=False, Hmax=-1e300, H0=None, vmax=0.0, through=0.0, min_excess=0.0,
               trajectory=[])
    cols = list(scene.colliders)
    x0 = scene.positions
    v0 = scene.velocities
    res['vmax0'] = float(np.linalg.norm(v0, axis=1).max())
    try:
        sim = stabint.Simulator(scene, options)
    except stabint.Error as e:
        res['err'] = f'ctor {type(e).__name__}: {e}'
        return res
    E0 = sim.energy()
    res['H0'] = E0.total
    masks = []
    if through:
        for spec in through:
            ci, d, reach, half = spec[:4]
            ign = np.asarray(spec[4], float) if len(spec) > 4 and spec[4] is not None else None
            c = np.asarray(cols[ci].center, float)
            d = np.asarray(d, float)
            d = d / np.linalg.norm(d)
            if ign is not None:
                ign = ign / np.linalg.norm(ign)
            rel = x0 - c
            along = rel @ d
            latv = rel - along[:, None] * d
            if ign is not None:
                latv = latv - (latv @ ign)[:, None] * ign
            side0 = np.where(np.linalg.norm(latv, axis=1) < reach, np.where(along < -half, -1, np.where(along > half, 1, 0)), 0)
            masks.append([c, d, reach, half, ign, side0])
    for i in range(frames):
        try:
            r = sim.step()
        except stabint.Error as e:
            res['refused'] = f'step {i}: {type(e).__name__}: {str(e)[:200]}'
            break
        res['frames'] = i + 1
        x = sim.positions
        v = sim.velocities
        H, Hs, K = r.energy.total, r.target, r.energy.kinetic
        if not (np.isfinite(x).all() and np.isfinite(v).all() and math.isfinite(H) and math.isfinite(Hs)):
            res['nonfinite'] = True
            res['nonfinite_frame'] = i
            break
        res['excess'] = max(res['excess'], H - Hs)
        res['min_excess'] = min(res['min_excess'], H - Hs)
        res['Kmax'] = max(res['Kmax'], K)
        res['Hmax'] = max(res['Hmax'], H)
        res['vmax'] = max(res['vmax'], float(np.linalg.norm(v, axis=1).max()))
        for ci, col in enumerate(cols):
            d = float(depth(col, x, sim.time).max())
            if d > res['deepest']:
                res['deepest'], res['deepest_frame'], res['deepest_col'] = d, i, ci
        for mk in masks:
            c, d, reach, half, ign, side = mk
            rel = x - c
            along = rel @ d
            latv = rel - along[:, None] * d
            if ign is not None:
                latv = latv - (latv @ ign)[:, None] * ign
            inside_fp = np.linalg.norm(latv, axis=1) < reach
            new = np.where(along < -half, -1, np.where(along > half, 1, side))
            crossed = inside_fp & (side == -1) & (new == 1)
            res['through'] += int(crossed.sum())
            if crossed.any() and res.get('through_frame') is None:
                res['through_frame'] = i
            mk[5] = np.where(inside_fp, new, 0)
        if keep_traj:
            res['trajectory'].append(x.copy())
    res['tol'] = options.contact_tolerance
    res['ratio'] = res['excess'] / res['Kmax'] if res['Kmax'] > 0 else float('nan')
    return res


def fmt(res):
    if res.get('err'):
        return res['err']
    s = (f"fr={res['frames']} exc/K={res['ratio']:.4f} Kmax={res['Kmax']:.3g} deep={res['deepest']*1000:.2f}mm"
         f"(f{res['deepest_frame']},c{res['deepest_col']}) H0={res['H0']:.4g} Hmax={res['Hmax']:.4g} vmax={res['vmax']:.3g}"
         f" thr={res['through']}")
    if res['refused']:
        s += ' REFUSED ' + res['refused']
    if res['nonfinite']:
        s += f" NONFINITE@{res['nonfinite_frame']}"
    return s
