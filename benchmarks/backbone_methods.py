"""One backbone, whatever the method (issue 51): the aircraft's mode 20 with tongues skipped, per method, side by side.

Each row continues NNM 20 of assets/paris.h5 with ``tongues=Skip()`` to ``--energy-max`` (default 10 J, no
multipliers) and prints how the branch ends (status, energy of its last backbone point), its softening (the last
backbone point's frequency against the linear one), the largest estimated frequency error on the backbone
(branch.freq_error), the points and the wall time.  Then every pair of rows is compared where both have backbone
points at the same energy (each branch interpolated in ln E between its backbone points, no jump between): the
largest relative frequency difference against the sum of the two estimates + 2e-4 (the issue's check; jumps past
tongues are not interpolated over: nnm.analysis.compare_backbones), and the end energies (within 3 %).

    python benchmarks/backbone_methods.py [--energy-max 10] [--rows default,hb9c,...]

Rows: default (Shooting(): gauss6, 100 steps, freq_tol 1e-4); gauss6-100 (the same steps, no accuracy target);
newmark-200 (with the target) and newmark-200-fixed (no target); hb9c (condensed, 9 harmonics, target on: raised
where needed); hb3c / hb5c / hb13c (condensed, fixed harmonics, no target).
"""
import argparse
import itertools
import os
import time
from pathlib import Path

import numpy as np

import nnm_solver as nnm

ROOT = Path(__file__).resolve().parents[1]
ROWS = {
    "default": nnm.Shooting(),
    "gauss6-100": nnm.Shooting(integrator="gauss6", steps_per_period=100, freq_tol=None),
    "newmark-200": nnm.Shooting(integrator="newmark", steps_per_period=200),
    "newmark-200-fixed": nnm.Shooting(integrator="newmark", steps_per_period=200, freq_tol=None),
    "hb9c": nnm.HarmonicBalance(harmonics=9, condensed=True),
    "hb3c": nnm.HarmonicBalance(harmonics=3, condensed=True, freq_tol=None),
    "hb5c": nnm.HarmonicBalance(harmonics=5, condensed=True, freq_tol=None),
    "hb13c": nnm.HarmonicBalance(harmonics=13, condensed=True, freq_tol=None),
}


def backbone(b):
    """(E, f, error) of the branch's backbone points, sorted in energy."""
    on = np.flatnonzero(b.labels == "backbone")
    o = np.argsort(b.energy[on])
    return b.energy[on][o], b.frequency_hz[on][o], b.freq_error[on][o]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--energy-max", type=float, default=10.0)
    ap.add_argument("--rows", default=",".join(ROWS))
    args = ap.parse_args()
    model = nnm.load_model(ROOT / "assets" / "paris.h5")
    nnm.continue_nnm(model, 20, 1e-3, nnm.Shooting(steps_per_period=20, freq_tol=None),
                     continuation=nnm.Continuation(max_points=3), floquet=False)      # compile the integrators first
    f_lin = None
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores)")
    print(f"{'row':>18} {'status':>8} {'end E (J)':>10} {'softening':>9} {'max est.':>9} {'points':>6} "
          f"{'time (s)':>8}")
    done = {}
    for name in args.rows.split(","):
        t0 = time.perf_counter()
        b = nnm.continue_nnm(model, 20, args.energy_max, ROWS[name], tongues=nnm.Skip(), floquet=False)
        dt = time.perf_counter() - t0
        E, f, e = backbone(b)
        f_lin = f_lin or b.frequency_hz[0]
        done[name] = b
        print(f"{name:>18} {b.status:>8} {E[-1]:>10.4g} {100 * (f[-1] / f_lin - 1):>8.2f}% {np.nanmax(e):>9.1e} "
              f"{len(b):>6} {dt:>8.1f}", flush=True)
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    print("pairs: largest |df/f| beyond the sum of the estimates (check: < 2e-4), end energies")
    for x, y in itertools.combinations(done, 2):
        c = nnm.analysis.compare_backbones(done[x], done[y])
        excess, d, E = c.excess, c.difference, c.energy
        Ex, Ey = backbone(done[x])[0][-1], backbone(done[y])[0][-1]
        print(f"{x:>18} vs {y:<18} excess {excess:9.1e} (|df/f| {d:.1e} at {E:.3g} J)   ends {Ex:.4g} / {Ey:.4g} J "
              f"({100 * abs(Ex / Ey - 1):.1f} %), status {done[x].status} / {done[y].status}")


if __name__ == "__main__":
    main()
