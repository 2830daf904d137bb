"""Condensed harmonic balance against the uncondensed HB and shooting, side by side in one run.

    python benchmarks/bench_condensed.py            # aircraft (assets/paris.h5) and the 10,000-DOF lattice
    python benchmarks/bench_condensed.py --quick     # one repetition

Prints, with the machine's load: the Paris-like aircraft's mode-20 backbone to E_max (default 30 J) at H = 9
by condensed HB (full and Ritz bases), the uncondensed HB at H = 9 and Newmark-200 / gauss6-100 shooting over
the first energies (time per point and the frequency at a common energy), and a 100 x 100 lattice
(10,000 DOFs, sparse) by condensed HB in the Ritz basis (basis and branch times, the first frequency against
the closed form).  Medians of 3 runs.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import nnm_solver as nnm  # noqa: E402
from nnm_solver.model import ritz  # noqa: E402


def timed(fn, reps):
    out, times = None, []
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return out, statistics.median(times)


def lattice(N=100, k=1e4, m=0.5, k3=1e9):
    T = sp.diags([-np.ones(N - 1), 2 * np.ones(N), -np.ones(N - 1)], [-1, 0, 1])
    I = sp.identity(N)
    K = (k * (sp.kron(T, I) + sp.kron(I, T))).tocsr()
    return nnm.Model(m * sp.identity(N * N, format="csr"), K, [nnm.CubicSpring(dof=(N // 2) * N + N // 2, k3=k3)])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--energy-max", type=float, default=30.0)
    args = ap.parse_args(argv)
    reps = 1 if args.quick else 3
    print(f"load average at the start {os.getloadavg()}")
    model = nnm.load_model(ROOT / "assets" / "paris.h5")
    f20 = model.linear_modes()[0][19]
    E = args.energy_max
    hb = dict(method="hb", harmonics=9, condensed=True, floquet=False)
    for kw in (hb, dict(steps_per_period=200, floquet=False), dict(integrator="gauss6", steps_per_period=100,
                                                                  floquet=False)):
        nnm.continue_nnm(model, 20, 0.05, **kw)          # warm: compiled kernels and caches, not in the timings
    full, t_full = timed(lambda: nnm.continue_nnm(model, 20, E, modal_basis="full", **hb), reps)
    ritz._cache.clear()
    rz, t_ritz = timed(lambda: (ritz._cache.clear(), nnm.continue_nnm(model, 20, E, modal_basis="ritz", **hb))[1], reps)
    print(f"\naircraft mode 20 ({f20:.4f} Hz) to {E:g} J, H = 9, condensed HB:")
    print(f"  full basis: {len(full)} points in {t_full:.2f} s ({1e3 * t_full / len(full):.1f} ms a point), "
          f"{full.status}, drop {100 * (full.frequency_hz.min() / f20 - 1):.3f} %")
    print(f"  Ritz basis (cutoff {rz.settings.cutoff_hz:.0f} Hz, basis included): {len(rz)} points in {t_ritz:.2f} s; "
          f"frequency at {E:g} J vs the full basis {rz.frequency_hz[-1] / full.frequency_hz[-1] - 1:.2e}")
    E0 = 1.0            # a common energy the slow methods reach quickly
    short = lambda **kw: nnm.continue_nnm(model, 20, E0, **kw)  # noqa: E731
    c1, t_c1 = timed(lambda: short(**hb), reps)
    u1, t_u1 = timed(lambda: short(method="hb", harmonics=9, floquet=False), 1)
    nm, t_nm = timed(lambda: short(steps_per_period=200, floquet=False), 1)
    g6, t_g6 = timed(lambda: short(integrator="gauss6", steps_per_period=100, floquet=False), 1)
    print(f"\nto {E0:g} J (the end point is at exactly {E0:g} J in each):")
    rows = [("condensed HB, H = 9", c1, t_c1), ("uncondensed HB, H = 9", u1, t_u1),
            ("Newmark shooting, 200 steps", nm, t_nm), ("gauss6 shooting, 100 steps", g6, t_g6)]
    for name, b, t in rows:
        print(f"  {name:<30} {len(b):4d} points {t:8.2f} s  {1e3 * t / len(b):9.1f} ms a point  "
              f"f(E0) = {b.frequency_hz[-1]:.10f} Hz  rel. to condensed {b.frequency_hz[-1] / c1.frequency_hz[-1] - 1:+.2e}")
    print(f"  per point: Newmark-200 / condensed = {(t_nm / len(nm)) / (t_c1 / len(c1)):.0f}x, "
          f"uncondensed / condensed = {(t_u1 / len(u1)) / (t_c1 / len(c1)):.0f}x")

    lat = lattice()
    N, k, m = 100, 1e4, 0.5
    f1 = np.sqrt(k / m * 8 * np.sin(np.pi / (2 * (N + 1))) ** 2) / (2 * np.pi)
    ritz._cache.clear()
    t = time.perf_counter()
    system = ritz.ritz_system(lat, 1, 5)
    t_basis = time.perf_counter() - t
    lb, t_lb = timed(lambda: nnm.continue_nnm(lat, 1, 2e-2, method="hb", harmonics=5, condensed=True, floquet=False),
                     reps)
    print(f"\n100 x 100 lattice, {lat.n} DOFs: Ritz basis {system.exact_modes} modes + {system.n - system.exact_modes} "
          f"in {t_basis:.1f} s; branch {len(lb)} points in {t_lb:.2f} s (basis cached); first linear frequency "
          f"{np.sqrt(system.omega2[0]) / (2 * np.pi) / f1 - 1:+.1e} from the closed form; total {t_basis + t_lb:.1f} s")
    print(f"load average at the end {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
