"""A stiffness-by-step-size sweep on a local Dask cluster: a cloth hanging from one corner (it
swings, undamped) for each stretch stiffness, time step and integrator (backward Euler and the
energy-tracking blend), printed as a table of the energy drift (H(T) - H(0)) / H(0) at time T.
Backward Euler loses energy, more for a larger step; the blend keeps H on its target H* (here
H(0): nothing does work on the cloth).

Cells with the same time step and integrator share options, so each such group steps as one
BatchSimulator task (stabint.distributed.sweep groups them); the grid runs on 2 worker processes.
The same code runs on a multi-machine cluster: pass Client("tcp://scheduler:8786") instead.

Usage: python sweep_stiffness_step.py [--nx 12] [--time 2.0] [--workers 2]
Needs: pip install stabint[distributed]"""
import argparse

import numpy as np
from distributed import Client, LocalCluster

import stabint
from stabint.distributed import BuiltinScene, grid, sweep

STIFFNESSES = [1e2, 1e3, 1e4]
STEPS = [1 / 30, 1 / 60, 1 / 120]
INTEGRATORS = ["BackwardEuler", "EnergyBlend"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=12, help="cloth resolution (nx by nx particles)")
    parser.add_argument("--time", type=float, default=2.0, help="simulated seconds T")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()

    cloth = BuiltinScene("cloth", {"nx": args.nx, "ny": args.nx, "pinned": [0]})  # fixed parameters
    cells = grid(cloth, stretch_stiffness=STIFFNESSES, time_step=STEPS, integrator=INTEGRATORS)  # the axes
    # One frame count for every cell (the smallest step's): each cell is read at its own frame
    # round(T / h), so every column compares the same simulated time.
    frames = round(args.time / min(STEPS))
    with LocalCluster(n_workers=args.workers, processes=True, threads_per_worker=1, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        results = sweep(cells, stabint.SimulatorOptions(iterations=10), frames, stride=frames, client=client)

    print(f"energy drift (H(T) - H(0)) / H(0) at T = {args.time:g} s, {args.nx} x {args.nx} cloth")
    print(f"{'stiffness':>10} {'h':>8} " + " ".join(f"{name:>14}" for name in INTEGRATORS))
    drift = {}
    for r in results:
        at = round(args.time / r.key["time_step"])
        total = r.reports["total"]
        drift[r.key["stretch_stiffness"], r.key["time_step"], r.key["integrator"]] = (total[at] - total[0]) / total[0]
    for k in STIFFNESSES:
        for h in STEPS:
            row = " ".join(f"{drift[k, h, name]:>14.3e}" for name in INTEGRATORS)
            print(f"{k:>10.0e} {h:>8.5f} {row}")
    assert np.isfinite(list(drift.values())).all()


if __name__ == "__main__":
    main()
