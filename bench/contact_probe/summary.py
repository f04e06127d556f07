"""Summarises a contact probe run (sweep.py's JSON lines): per integrator the runs and how many
break a promise, and every blend run over the contact target, worst first.
Usage: python summary.py results/contact_probe.jsonl"""
import json
import sys

TARGET = 0.05  # max(H - H*) / largest kinetic energy, the contact issue's target for the blend


def main(path):
    rows = [json.loads(line) for line in open(path)]
    by = {}
    for r in rows:
        c, res = r['case'], r['res']
        s = by.setdefault(c['integ'], dict(runs=0, over=0, deep=0, through=0, broken=0))
        s['runs'] += 1
        if res.get('err') or res.get('nonfinite') or res.get('refused'):
            s['broken'] += 1
            continue
        s['over'] += c['integ'] == 'blend' and res['ratio'] > TARGET
        s['deep'] += res['deepest'] > res['tol'] + 1e-9
        s['through'] += res.get('through', 0) > 0
    print(f"{len(rows)} runs; per integrator: runs, blend over {TARGET} of K_max, deeper than the tolerance, "
          "vertices through a thin collider, errors / non-finite / refused")
    for integ, s in sorted(by.items()):
        print(f"  {integ:6s} {s['runs']:5d} {s['over']:5d} {s['deep']:5d} {s['through']:5d} {s['broken']:5d}")
    blend = [r for r in rows if r['case']['integ'] == 'blend' and not r['res'].get('err')]
    default = [r for r in blend if 'h' not in r['case'] and 'it' not in r['case']]
    print(f"blend within {TARGET}: {sum(r['res']['ratio'] <= TARGET for r in blend)} of {len(blend)} runs, "
          f"{sum(r['res']['ratio'] <= TARGET for r in default)} of {len(default)} at the default options")
    for r in sorted((r for r in blend if r['res']['ratio'] > TARGET), key=lambda r: -r['res']['ratio']):
        c = r['case']
        extra = f" h={c['h']:.4f} it={c['it']}" if 'h' in c else ''
        print(f"  {r['res']['ratio']:.3f}  {c['body']} {c['E']:g} Pa {c['v']:g} m/s onto {c['col']}, "
              f"friction {c['fr']}, restitution {c['e']}{extra}")


if __name__ == '__main__':
    main(sys.argv[1] if len(sys.argv) > 1 else 'results/contact_probe.jsonl')
