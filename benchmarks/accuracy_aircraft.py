"""Aircraft accuracy table: where mode 20 of assets/paris.h5 meets its first energy fold, per integrator
and steps per period, and what it costs (one process, side by side, machine load printed).

Each run continues NNM 20 from low energy and stops at its first located energy fold (a turning point in
energy: the entrance of an internal-resonance tongue).  For each integrator and step count it prints the
fold's energy and frequency, the largest estimated frequency error on the way (branch.freq_error), the
points and the wall time.  Two step counts of one integrator agree on the fold when the scheme resolves
the tongue's partner harmonic; Newmark at 200 steps per period does not (its 9th/11th harmonics have
22/18 steps per cycle: (2 pi k / N)^2 / 12 = 0.7-1 % frequency error on the partner mode).  With too few
steps even a 6th-order scheme lets the backbone be captured by another, higher tongue (gauss6 at 70 steps:
a 15:1 tongue whose partner harmonic has under 5 steps per cycle).

    python benchmarks/accuracy_aircraft.py [--quick]
"""
import os
import sys
import time
from pathlib import Path

import numpy as np

import nnm_solver as nnm

ROOT = Path(__file__).resolve().parents[1]
RUNS = [("newmark", 200), ("newmark", 400), ("gauss6", 100), ("gauss6", 140), ("gauss6", 70)]


def first_fold(model, integrator, spp, energy_max=3000.0, max_points=120):
    it = nnm.iter_nnm(model, 20, energy_max, steps_per_period=spp, integrator=integrator, max_points=max_points)
    t0 = time.perf_counter()
    for _ in it:
        if any(e["kind"] == "fold" for e in it.events):
            break
    dt = time.perf_counter() - t0
    b = it.branch()
    folds = [e for e in b.events if e["kind"] == "fold"]
    return b, (folds[0] if folds else None), dt


def main():
    quick = "--quick" in sys.argv
    model = nnm.load_model(ROOT / "assets" / "paris.h5")
    nnm.continue_nnm(model, 20, 1e-3, max_points=3, integrator="gauss6", steps_per_period=20)   # compile
    nnm.continue_nnm(model, 20, 1e-3, max_points=3, steps_per_period=20)
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores)")
    print(f"{'integrator':>10} {'steps':>5} {'fold E (J)':>12} {'fold f (Hz)':>12} {'max est. error':>14} "
          f"{'points':>6} {'time (s)':>8}")
    rows = {}
    for name, spp in RUNS[:2] + RUNS[2:4] if quick else RUNS:
        b, fold, dt = first_fold(model, name, spp)
        if fold is None:
            print(f"{name:>10} {spp:>5}  no fold ({b.status}: {b.message[:60]})  {len(b):>6} {dt:>8.1f}")
            continue
        est = np.nanmax(b.freq_error[:fold["index"] + 1])
        rows[(name, spp)] = (fold, dt)
        print(f"{name:>10} {spp:>5} {fold['energy']:>12.5g} {fold['frequency_hz']:>12.7f} {est:>14.1e} "
              f"{len(b):>6} {dt:>8.1f}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")
    for name, (a, b) in (("newmark", (200, 400)), ("gauss6", (100, 140)), ("gauss6", (70, 100))):
        if (name, a) in rows and (name, b) in rows:
            fa, fb = rows[(name, a)][0], rows[(name, b)][0]
            print(f"{name} {a} vs {b}: fold frequency differs by {abs(fa['frequency_hz'] / fb['frequency_hz'] - 1):.1e}"
                  f" (relative), energy by {abs(fa['energy'] / fb['energy'] - 1):.1e}")
    if ("newmark", 200) in rows and ("gauss6", 100) in rows and ("gauss6", 140) in rows:
        t_ref = rows[("newmark", 200)][1]
        t_g = rows[("gauss6", 100)][1] + rows[("gauss6", 140)][1]
        print(f"time of the gauss6 100 and 140 runs / newmark 200 run: {t_g / t_ref:.2f}")


if __name__ == "__main__":
    main()
