"""The contact probe's grid (docs/method.md, "The contact targets"): groups A (the blend: bars of
1e4-1e7 Pa at 0.5-20 m/s onto every collider kind, friction 0 and 0.5), B (restitution 0,
friction 1), C (BE, BDF2, IM), D (h = 1/60 and 1/120; 5 and 30 iterations), E (a tet ball, Medit
bodies and a rotated bar) and F2 (cloths): 1,038 runs, 10-20 minutes on two cores.
Usage: .venv/bin/python bench/contact_probe/sweep.py [GROUP ...] [--out FILE], then summary.py FILE."""
import json, os, sys, time, traceback
from probe import *

R_mesh = rot_matrix((0, 1, 0), 30) @ rot_matrix((1, 0, 0), 15)


def colliders_for_bar(kind, fr=0.0, e=1.0):
    """returns (list of colliders, through spec)"""
    if kind == 'plane':
        return [plane(0, friction=fr, restitution=e)], None
    if kind == 'tiltplane':
        n = rot_matrix((0, 0, 1), 30) @ np.array([0, 1, 0.0])
        return [plane(normal=n, center=(0, -0.35, 0), friction=fr, restitution=e)], None
    if kind == 'sphere':
        return [sphere((0, -0.3, 0), 0.3, fr, e)], [(0, (0, -1, 0), 0.25, 0.0)]
    if kind == 'thinbox':
        return [box((0, -0.01, 0), (0.3, 0.01, 0.3), fr, e)], [(0, (0, -1, 0), 0.25, 0.01)]
    if kind == 'capsule':
        return [capsule((0, -0.03, -0.5), (0, -0.03, 0.5), 0.03, fr, e)], [(0, (0, -1, 0), 0.027, 0.0, (0, 0, 1))]
    if kind == 'meshico':
        V, F = icosphere(3)
        return [mesh_collider(V * 0.3, F, center=(0, -0.3, 0), friction=fr, restitution=e)], [(0, (0, -1, 0), 0.25, 0.0)]
    if kind == 'meshplate':
        V, F = box_mesh((0.3, 0.01, 0.3))
        return [mesh_collider(V, F, center=(0, -0.01, 0), friction=fr, restitution=e)], [(0, (0, -1, 0), 0.25, 0.01)]
    if kind == 'meshplate_rot':
        V, F = box_mesh((0.3, 0.01, 0.3))
        return [mesh_collider(V, F, center=(0, -0.12, 0), R=rot_matrix((1, 0, 0), 20), friction=fr, restitution=e)], [(0, tuple(rot_matrix((1, 0, 0), 20) @ np.array([0, -1.0, 0])), 0.1, 0.01)]
    if kind == 'meshtet':
        b = stabint.tet_bar(nx=8, ny=2, nz=2)
        V, F = tet_surface_mesh(b)
        V = V - np.array([0.5, 0.125, 0.125])  # center at origin
        Rm = R_mesh
        top = (V @ Rm.T)[:, 1].max()
        return [mesh_collider(V, F, center=(0, -top, 0), R=Rm, friction=fr, restitution=e)], [(0, (0, -1, 0), 0.05, 0.0)]
    raise ValueError(kind)


BARCOLS = ['plane', 'tiltplane', 'sphere', 'thinbox', 'capsule', 'meshico', 'meshplate', 'meshplate_rot', 'meshtet']


def cases(group):
    if group == 'A':  # blend, bar, E x speed x collider x friction
        for E in (1e4, 1e5, 1e6, 1e7):
            for v in (0.5, 3.0, 10.0, 20.0):
                for col in BARCOLS:
                    for fr in (0.0, 0.5):
                        yield dict(body='bar', E=E, v=v, col=col, fr=fr, e=1.0, integ='blend')
    if group == 'B':  # restitution 0 and friction 1
        for E in (1e4, 1e5, 1e7):
            for v in (3.0, 20.0):
                for col in BARCOLS:
                    yield dict(body='bar', E=E, v=v, col=col, fr=0.5, e=0.0, integ='blend')
                    yield dict(body='bar', E=E, v=v, col=col, fr=1.0, e=1.0, integ='blend')
    if group == 'C':  # integrators
        for integ in ('BE', 'BDF2', 'IM'):
            for E in (1e4, 1e5, 1e7):
                for v in (3.0, 20.0):
                    for col in BARCOLS:
                        yield dict(body='bar', E=E, v=v, col=col, fr=0.5, e=1.0, integ=integ)
    if group == 'D':  # options
        for h, it in ((1 / 60, 10), (1 / 120, 10), (1 / 30, 5), (1 / 30, 30)):
            for E in (1e5, 1e7):
                for v in (3.0, 20.0):
                    for col in BARCOLS:
                        yield dict(body='bar', E=E, v=v, col=col, fr=0.5, e=1.0, integ='blend', h=h, it=it)
    if group == 'E':  # other bodies
        for body in ('ball', 'medit_small_rot', 'medit_big_rot', 'bar_rot'):
            for E in (1e4, 1e6, 1e7):
                for v in (0.5, 5.0, 20.0):
                    for col in BARCOLS:
                        yield dict(body=body, E=E, v=v, col=col, fr=0.5, e=1.0, integ='blend')
    if group == 'F2':  # cloth, trimmed
        for n, k, v, col, integ in ((20, 1e3, 5.0, 'sphere_ground', 'blend'), (20, 1e3, 20.0, 'sphere_ground', 'blend'),
                                    (20, 1e2, 5.0, 'capsule', 'blend'), (20, 1e3, 20.0, 'thinbox', 'blend'),
                                    (20, 1e4, 5.0, 'tiltplane', 'blend'), (20, 1e3, 5.0, 'meshico', 'blend'),
                                    (20, 1e3, 20.0, 'smallsphere', 'blend'), (20, 1e3, 5.0, 'meshplate_rot', 'blend'),
                                    (30, 1e3, 5.0, 'sphere_ground', 'blend'), (30, 1e3, 20.0, 'thinbox', 'BE'),
                                    (20, 1e3, 20.0, 'smallsphere', 'BDF2'), (20, 1e3, 5.0, 'sphere_ground', 'IM')):
            yield dict(body='cloth', n=n, E=k, v=v, col=col, fr=0.5, e=1.0, integ=integ)
    if group == 'F':  # cloth
        for n, ks in ((20, (1e2, 1e3, 1e4)), (30, (1e3,))):
            for k in ks:
                for v in (1.0, 5.0, 20.0):
                    for col in ('sphere_ground', 'capsule', 'thinbox', 'tiltplane', 'meshico', 'smallsphere', 'meshplate_rot'):
                        for integ in ('blend', 'BE'):
                            yield dict(body='cloth', n=n, E=k, v=v, col=col, fr=0.5, e=1.0, integ=integ)


def build(c):
    body = c['body']
    E, v = c['E'], c['v']
    if body == 'bar':
        s = bar(E=E, speed=v)
    elif body == 'bar_rot':
        s = bar(E=E, speed=v, R=rot_matrix((1, 1, 1), 35), n=(12, 3, 3))
    elif body == 'ball':
        s = tet_ball(E=E, radius=0.2, n=7, speed=v)
    elif body == 'medit_small_rot':
        s = medit_body(E=E, scale=0.4, R=rot_matrix((0, 0, 1), 40), speed=v)
    elif body == 'medit_big_rot':
        s = medit_body(E=E, scale=1.5, R=rot_matrix((1, 0, 1), 60), speed=v)
    elif body == 'cloth':
        s = cloth(c['n'], height=0.4 if c['col'] != 'tiltplane' else 0.5, speed=v, stretch=E)
    if body == 'cloth':
        col = c['col']
        fr = c['fr']
        thr = None
        if col == 'sphere_ground':
            cols = [sphere((0, 0, 0), 0.25, fr), plane(-0.3, friction=fr)]
            thr = [(0, (0, -1, 0), 0.2, 0.0)]
        elif col == 'capsule':
            cols = [capsule((-0.6, 0.2, 0), (0.6, 0.2, 0.1), 0.04, fr)]
            thr = [(0, (0, -1, 0), 0.03, 0.0, (1, 0, 0.1))]
        elif col == 'thinbox':
            cols = [box((0, 0.3, 0), (0.3, 0.01, 0.3), fr)]
            thr = [(0, (0, -1, 0), 0.25, 0.01)]
        elif col == 'tiltplane':
            n = rot_matrix((1, 0, 0), 25) @ np.array([0, 1, 0.0])
            cols = [plane(normal=n, center=(0, 0, 0), friction=fr)]
        elif col == 'meshico':
            V, F = icosphere(3)
            cols = [mesh_collider(V * 0.25, F, center=(0, 0, 0), friction=fr), plane(-0.3, friction=fr)]
            thr = [(0, (0, -1, 0), 0.2, 0.0)]
        elif col == 'smallsphere':
            cols = [sphere((0, 0.25, 0), 0.05, fr)]
            thr = [(0, (0, -1, 0), 0.04, 0.0)]
        elif col == 'meshplate_rot':
            V, F = box_mesh((0.3, 0.01, 0.3))
            cols = [mesh_collider(V, F, center=(0, 0.2, 0), R=rot_matrix((0, 0, 1), 20), friction=fr)]
            thr = [(0, tuple(rot_matrix((0, 0, 1), 20) @ np.array([0, -1.0, 0])), 0.1, 0.01)]
        for cc in cols:
            s.colliders.append(cc)
        return s, thr
    cols, thr = colliders_for_bar(c['col'], c['fr'], c['e'])
    for cc in cols:
        s.colliders.append(cc)
    return s, thr


def main(group, out='results.jsonl', frames=60):
    done = set()
    try:
        for line in open(out):
            done.add(json.loads(line)['key'])
    except FileNotFoundError:
        pass
    f = open(out, 'a')
    for c in cases(group):
        key = group + ':' + json.dumps(c, sort_keys=True)
        if key in done:
            continue
        t = time.time()
        try:
            s, thr = build(c)
            o = make_options(c['integ'], h=c.get('h', 1 / 30), iters=c.get('it', 10))
            nfr = int(round(frames * (1 / 30) / o.time_step)) if 'h' in c else frames
            nfr = min(nfr, 90)
            r = run(s, o, nfr, through=thr)
        except Exception as ex:
            r = dict(err='PYEXC ' + traceback.format_exc()[-400:])
        r.pop('trajectory', None)
        r['dt'] = time.time() - t
        rec = dict(key=key, group=group, case=c, res=r)
        f.write(json.dumps(rec, default=float) + '\n')
        f.flush()
        print(group, c, fmt(r) if not r.get('err') else r['err'], f"{r['dt']:.1f}s", flush=True)


if __name__ == '__main__':
    # python sweep.py [GROUP ...] [--out FILE]: appends each case's result to FILE (default
    # results/contact_probe.jsonl), skipping those already there; summary.py reads it.
    args = sys.argv[1:]
    out = 'results/contact_probe.jsonl'
    if '--out' in args:
        i = args.index('--out')
        out = args[i + 1]
        del args[i:i + 2]
    os.makedirs(os.path.dirname(out) or '.', exist_ok=True)
    for group in args or ['A', 'B', 'C', 'D', 'E', 'F2']:
        main(group, out)
