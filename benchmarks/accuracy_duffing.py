"""Accuracy of the shooting backbone against the exact Duffing period (complete elliptic integral).

x'' + x + k x^3 = 0 released from rest at amplitude A has period T = 4 K(m) / sqrt(1 + k A^2),
m = k A^2 / (2 (1 + k A^2)).  Prints the largest relative frequency error along the backbone up to
energy_max for several numbers of Newmark steps per period, and the observed order.

    python benchmarks/accuracy_duffing.py
"""
import time

import numpy as np
from scipy.special import ellipk

import nnm_solver as nnm


def exact_frequency(E, k):
    A = np.sqrt((-1 + np.sqrt(1 + 4 * k * E)) / k) if k else np.sqrt(2 * E)
    return np.sqrt(1 + k * A ** 2) / (4 * ellipk(k * A ** 2 / (2 * (1 + k * A ** 2))))


def main():
    print(f"{'k':>5} {'steps/period':>12} {'points':>6} {'max rel. freq. error':>21} {'order':>6} {'time (s)':>8}")
    for k, emax in ((1.0, 2.0), (-0.2, 0.6)):
        model = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=k)])
        prev = None
        for spp in (100, 200, 400, 1000):
            nnm.continue_nnm(model, 1, energy_max=emax, steps_per_period=spp, max_points=3)  # warm-up (JIT)
            t0 = time.perf_counter()
            b = nnm.continue_nnm(model, 1, energy_max=emax, steps_per_period=spp, tol=1e-10)
            dt = time.perf_counter() - t0
            err = np.max(np.abs(b.frequency_hz / exact_frequency(b.energy, k) - 1))
            order = "" if prev is None else f"{np.log(prev[1] / err) / np.log(spp / prev[0]):6.2f}"
            print(f"{k:>5} {spp:>12} {len(b):>6} {err:>21.3e} {order:>6} {dt:>8.2f}")
            prev = (spp, err)


if __name__ == "__main__":
    main()
