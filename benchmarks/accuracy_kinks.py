"""Accuracy of the smoothed kinks of PiecewiseLinearSpring (issue 18): period and monodromy of a
bilinear oscillator against closed forms, for several kink widths eps and Newmark step counts.

x'' + k x + f(x) = 0, f bilinear (slope k0 = 0.5 N/m for |x| < d1 = 0.1 m, k1 = 2 N/m beyond), k = 1
N/m, amplitudes 1.5-1.8 d1.  Printed per (steps per period, eps):
- period: the largest relative error of the branch's periods against the closed form
  (tests/test_elements.py::_bilinear_period: sums of quarter-period arcs of the linear pieces);
- monodromy: the relative error of dv(T)/dx0 at the middle point against T'(A) F(A), the monodromy
  entry of the nonsmooth flow (the force is continuous, so the switching instants have no saltation
  jump);
- |M - FD|: the exact monodromy against central finite differences of the discrete map (step 1e-7);
- |M00 - 1|: the departure of the trivial Floquet pair from 1.

    python benchmarks/accuracy_kinks.py
"""
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import nnm_solver as nnm  # noqa: E402
from test_elements import _bilinear_period, _monodromy_and_fd  # noqa: E402

K, K0, K1, D1 = 1.0, 0.5, 2.0, 0.1


def main():
    print(f"{'steps':>5} {'eps':>6} {'period':>9} {'monodromy':>9} {'|M - FD|':>9} {'|M00 - 1|':>9} {'time (s)':>8}")
    for spp in (500, 2000, 8000):
        for eps in (3e-2, 1e-2, 3e-3, 1e-3, 1e-4):
            pw = nnm.PiecewiseLinearSpring(dof=0, stiffnesses=[K0, K1], breakpoints=[D1], eps=eps)
            m = nnm.Model(np.eye(1), K * np.eye(1), [pw])
            t0 = time.perf_counter()
            b = nnm.continue_nnm(m, 1, 0.2, energy_min=0.5 * (K + K0) * (1.5 * D1) ** 2, steps_per_period=spp,
                                 max_points=12)
            elapsed = time.perf_counter() - t0
            A = np.abs(b.x0[:, 0])
            T = np.array([_bilinear_period(a, K, K0, K1, D1) for a in A])
            i = len(b) // 2
            Mo, fd = _monodromy_and_fd(m, b, i)
            a = A[i]
            dT = (_bilinear_period(a + 1e-6, K, K0, K1, D1) - _bilinear_period(a - 1e-6, K, K0, K1, D1)) / 2e-6
            mono = abs(Mo[1, 0] / (dT * (K * a + float(pw.exact_force(a)))) - 1)
            print(f"{spp:5d} {eps:6.0e} {np.max(np.abs(b.period / T - 1)):9.1e} {mono:9.1e} "
                  f"{np.abs(Mo - fd).max() / np.abs(Mo).max():9.1e} {abs(Mo[0, 0] - 1):9.1e} {elapsed:8.1f}", flush=True)


if __name__ == "__main__":
    main()
