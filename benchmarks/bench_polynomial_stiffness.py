"""PolynomialStiffness (issue 55): the springs' kernels unchanged, and what the general kernels cost.

Usage (from the repository root)::

    python benchmarks/bench_polynomial_stiffness.py --other /work/main     # this tree against another one
    python benchmarks/bench_polynomial_stiffness.py                        # this tree only

1. Springs path (the aircraft, assets/paris.h5, mode 20 at its linear period, 200 Newmark / 100 gauss6 steps):
   a state sweep and an exact-sensitivity sweep (n columns, as the symmetric shooting takes them) of each
   integrator, in a separate process per tree (alternating, ``--rounds`` each), medians printed with the load.
2. General kernels (this tree): NLvib's example 06 (2 DOF, one element) and a chain of n masses with one
   2-coordinate PolynomialStiffness per link (n - 1 elements with the same exponents: one group), sweep and
   sensitivity per period, and one HB Jacobian.
"""
from __future__ import annotations

import os

# single-threaded BLAS for both parts (set before numpy loads it): with other jobs on the machine, OpenBLAS's threads
# made the general gauss6 sensitivity at n = 60 take 42 s instead of 0.75 s (threadpoolctl's limit did not reach
# the BLAS numba calls)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: modal amplitude of mode 20 of the aircraft's orbit (sqrt(kg) m): 2.4 J, the springs 3 % of the potential
AMPLITUDE = 0.01

CHILD = r"""
import json, sys, time
import numpy as np
import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.integrators.registry import get_integrator
model = nnm.load_model(sys.argv[1])
s = modal_system(model)
k = 19
q0 = np.zeros(s.n); q0[k] = float(sys.argv[2]); v0 = np.zeros(s.n)
out = {}
for name in ("newmark", "gauss6"):
    it = get_integrator(name)
    T = it.linear_period(np.sqrt(s.omega2[k]), it.steps)
    h = T / it.steps
    assert it.state(s, q0, v0, h, it.steps)[-1] and it.sensitivity(s, q0, v0, h, it.steps // 2, False, False)[-1]
    for what, fn in (("state", lambda: it.state(s, q0, v0, h, it.steps)),
                     ("sensitivity", lambda: it.sensitivity(s, q0, v0, h, it.steps // 2, False, False))):
        ts = []
        for _ in range(20):
            t = time.perf_counter(); fn(); ts.append(time.perf_counter() - t)
        out[f"{name} {what}"] = min(ts)
print(json.dumps(out))
"""


def springs_path(tree, rounds):
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    res = subprocess.run([sys.executable, "-c", CHILD, str(ROOT / "assets" / "paris.h5"), str(AMPLITUDE)], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def chain(n, k3=1.0):
    """n unit masses in a chain with unit springs, each link also a geometric-like polynomial stiffness on
    (u, w) = (x[i+1] - x[i], x[i]) with V = k3 (u^2 w^2 / 2 + w^4 / 4)."""
    import numpy as np
    import nnm_solver as nnm
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    els = [nnm.PolynomialStiffness([[1, 2], [2, 1], [0, 3]], [[k3, 0], [0, k3], [0, k3]], dofs=[i, i + 1],
                                   directions=[[-1, 1], [1, 0]]) for i in range(n - 1)]
    return nnm.Model(np.eye(n), K, els)


def general_path():
    import numpy as np
    import nnm_solver as nnm
    from nnm_solver.model.modal import ModalSystem
    from nnm_solver.integrators.registry import get_integrator
    from nnm_solver.orbits.harmonic_balance import HBProblem
    from nnm_solver.orbits.hb_basis import HBBasis
    sys.path.insert(0, str(ROOT / "tests"))
    from test_polynomial_stiffness import example06
    rows = []
    for label, model in (("example 06 (n = 2)", example06()), ("chain n = 20, 19 elements", chain(20)),
                         ("chain n = 60, 59 elements", chain(60))):
        s = ModalSystem(model)
        q0 = np.zeros(s.n); q0[0] = 0.1; v0 = np.zeros(s.n)
        row = {"model": label}
        for name in ("newmark", "gauss6"):
            it = get_integrator(name)
            h = it.linear_period(np.sqrt(s.omega2[0]), it.steps) / it.steps
            it.sensitivity(s, q0, v0, h, 2)
            for what, fn in (("state", lambda: it.state(s, q0, v0, h, it.steps)),
                             ("sensitivity", lambda: it.sensitivity(s, q0, v0, h, it.steps))):
                ts = []
                for _ in range(3):
                    t = time.perf_counter(); fn(); ts.append(time.perf_counter() - t)
                row[f"{name} {what}"] = min(ts)
        P = HBProblem(s, 0, HBBasis(7, "full"))
        u = P.pack(np.vstack([np.zeros(s.n), q0, np.zeros((len(P.basis) - 2, s.n))]), np.sqrt(s.omega2[0]))
        ts = []
        for _ in range(3):
            t = time.perf_counter(); P.jacobian(u); ts.append(time.perf_counter() - t)
        row["HB Jacobian (H = 7)"] = min(ts)
        rows.append(row)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--other", help="another tree (e.g. /work/main) to time the springs path against")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args(argv)
    print(f"load average before: {os.getloadavg()}")
    trees = [("this tree", ROOT)] + ([("other", Path(a.other))] if a.other else [])
    runs = {name: [] for name, _ in trees}
    for _ in range(a.rounds):
        for name, tree in trees:
            runs[name].append(springs_path(tree, a.rounds))
    print("\n1. springs path, aircraft mode 20 (548 DOF, 3 springs), best of 20 per process, median over "
          f"{a.rounds} processes (s)")
    keys = list(runs[trees[0][0]][0])
    print(f"{'':26s}" + "".join(f"{name:>12s}" for name, _ in trees) + ("      ratio" if a.other else ""))
    for key in keys:
        med = [statistics.median(r[key] for r in runs[name]) for name, _ in trees]
        print(f"{key:26s}" + "".join(f"{m:12.4f}" for m in med) + (f"{med[0] / med[1]:11.3f}" if a.other else ""))
    print("\n2. general kernels (this tree, BLAS single-threaded), best of 3 (s): one period (newmark 200 / gauss6 100 "
          "steps)")
    for row in general_path():
        print("  " + ", ".join(f"{k}: {v:.4g}" if isinstance(v, float) else str(v) for k, v in row.items()))
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
