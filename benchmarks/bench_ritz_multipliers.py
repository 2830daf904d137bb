"""The multipliers of the unreduced aircraft's condensed HB branch by the monodromy route (orbits/hill_monodromy.py;
issue 52): their cost a point and their convergence in the Gauss steps, from a file with a stored Ritz basis.

    python examples/build_paris_full.py --no-check --store-basis --out stored.h5
    python benchmarks/bench_ritz_multipliers.py stored.h5 [--energy 3]

Prints, with the load: the branch of mode 20 at H = 9 to --energy J with the default multipliers (the route, the
multiplier calls and their CPU time), then at every point the route's largest |mu| and stability flag at the default
steps and at twice as many, and the largest change of the multipliers of the modes below the basis cutoff and of
all of them (the Ritz pairs above the cutoff, up to 1.7 kHz, take Gauss steps of h omega ~ 2: their places on the
unit circle move with the step; the flags do not).
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

import nnm_solver as nnm
from nnm_solver.model.ritz import ritz_system
from nnm_solver.orbits import hill
from nnm_solver.orbits.hill_monodromy import monodromy_multipliers, monodromy_steps


def matched(a, b):
    """The pairing of the multipliers a, b (closest one to one): (index pairs, distances)."""
    D = np.abs(np.asarray(a)[:, None] - np.asarray(b)[None, :])
    i, j = linear_sum_assignment(D)
    return i, j, D[i, j]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("file")
    ap.add_argument("--energy", type=float, default=3.0)
    args = ap.parse_args(argv)
    print(f"load {os.getloadavg()[0]:.2f}")
    model = nnm.load_model(args.file)
    system = ritz_system(model, 20, 9)
    print(f"Ritz system: {system.n} coordinates ({system.exact_modes} modes below {system.cutoff_hz:.1f} Hz), "
          f"auto route {hill.auto_route(system.n, 9)}")
    calls, orbits = [], []
    real = hill.monodromy_multipliers

    def counting(s, basis, A, w, **kw):
        t = time.process_time()
        mu = real(s, basis, A, w, **kw)
        calls.append(time.process_time() - t)
        orbits.append((basis, np.array(A), float(w)))
        return mu
    hill.monodromy_multipliers = counting
    t = time.process_time()
    b = nnm.continue_nnm(model, 20, args.energy, method="hb", harmonics=9, condensed=True)
    total = time.process_time() - t
    hill.monodromy_multipliers = real
    print(f"branch to {args.energy} J: {len(b)} points, {b.status}, floquet {b.settings.floquet}, "
          f"multipliers_of {b.multipliers_of}; {total:.1f} s CPU, {len(calls)} multiplier calls, "
          f"{np.median(calls):.2f} s CPU each (median), events {[e['kind'] for e in b.events]}; "
          f"load {os.getloadavg()[0]:.2f}")
    low = np.sqrt(system.omega2) / (2 * np.pi) <= system.cutoff_hz
    worst_low = worst_all = 0.0
    same = 0
    seen = set()
    for basis, A, w in orbits:
        key = (round(w, 12), A.tobytes())
        if key in seen:
            continue
        seen.add(key)
        a = monodromy_multipliers(system, basis, A, w)
        c = monodromy_multipliers(system, basis, A, w, steps=2 * monodromy_steps(9))
        i, j, d = matched(a, c)
        # a multiplier belongs to a mode below the cutoff when it is within 0.05 of that mode's linear exp(+-i w T)
        lin = np.exp(1j * np.sqrt(system.omega2[low]) * 2 * np.pi / w)
        lin = np.r_[lin, lin.conj()]
        near = np.min(np.abs(a[i][:, None] - lin[None, :]), axis=1) < 0.05
        worst_low = max(worst_low, float(d[near].max()) if near.any() else 0.0)
        worst_all = max(worst_all, float(d.max()))
        fa, fc = np.abs(a).max() <= 1 + 1e-6, np.abs(c).max() <= 1 + 1e-6
        same += fa == fc
        print(f"  f {w / 2 / np.pi:.6f} Hz  max|mu| {np.abs(a).max():.9f} (2x steps {np.abs(c).max():.9f})  "
              f"stable {fa} / {fc}")
    print(f"{len(seen)} orbits: flags equal at {same}; largest change with twice the steps: {worst_low:.2e} (modes "
          f"below the cutoff), {worst_all:.2e} (all); load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
