"""Accuracy of the shooting backbone against the exact Duffing period (complete elliptic integral),
for every time integrator (nnm.INTEGRATORS), against steps per period and against time.

x'' + x + k x^3 = 0 released from rest at amplitude A has period T = 4 K(m) / sqrt(1 + k A^2),
m = k A^2 / (2 (1 + k A^2)).  For each integrator and number of steps per period it prints the
largest relative frequency error along the backbone up to energy_max, the observed order between
successive step counts, the wall time of the branch (median of 3, after a warm-up), the largest ratio of
the per-point error estimate (branch.freq_error) to the true error, and finally the steps per period each
integrator needs for an error of 1e-8 (from its measured order and constant).

    python benchmarks/accuracy_duffing.py
"""
import os
import time

import numpy as np
from scipy.special import ellipk

import nnm_solver as nnm

STEPS = {"newmark": (50, 100, 200, 400, 1000), "gauss4": (25, 50, 100, 200), "gauss6": (13, 25, 50, 100)}


def exact_frequency(E, k):
    A = np.sqrt((-1 + np.sqrt(1 + 4 * k * E)) / k) if k else np.sqrt(2 * E)
    return np.sqrt(1 + k * A ** 2) / (4 * ellipk(k * A ** 2 / (2 * (1 + k * A ** 2))))


def median_time(fn, repeat=3):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main():
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores)")
    print(f"{'k':>5} {'integrator':>10} {'steps':>6} {'points':>6} {'max rel. freq. error':>21} {'order':>6} "
          f"{'time (s)':>8} {'estimate/true':>14}")
    needed = {}
    for k, emax in ((1.0, 2.0), (-0.2, 0.6)):
        model = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=k)])
        for name in nnm.INTEGRATORS:
            prev = None
            for spp in STEPS[name]:
                nnm.continue_nnm(model, 1, energy_max=emax, steps_per_period=spp, max_points=3, integrator=name)
                dt, b = median_time(lambda: nnm.continue_nnm(model, 1, energy_max=emax, steps_per_period=spp,
                                                             tol=1e-12, integrator=name))
                true = np.abs(b.frequency_hz / exact_frequency(b.energy, k) - 1)
                err = float(np.max(true))
                order = "" if prev is None else f"{np.log(prev[1] / err) / np.log(spp / prev[0]):6.2f}"
                ok = true > 1e-12
                ratio = f"{np.max(b.freq_error[ok] / true[ok]):14.2f}" if ok.any() else f"{'(round-off)':>14}"
                print(f"{k:>5} {name:>10} {spp:>6} {len(b):>6} {err:>21.3e} {order:>6} {dt:>8.3f} {ratio}")
                if err > 1e-12:
                    prev = (spp, err)
            if prev is not None:       # error = C N^-p with the scheme's order p
                p = {"newmark": 2, "gauss4": 4, "gauss6": 6}[name]
                C = prev[1] * prev[0] ** p
                needed[(k, name)] = (C, int(np.ceil((C / 1e-8) ** (1 / p))))
    print("\nsteps per period for a frequency error of 1e-8 (error = C N^-p, C from the finest step above):")
    for (k, name), (C, N) in needed.items():
        print(f"  k = {k:>5}  {name:>8}: C = {C:9.3g}, N = {N}")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
