"""The cost of one shooting point on the aircraft (assets/paris.h5: 548 modes, 4 cubic springs, gauss6 at 100 steps a
period, quarter-period shooting), piece by piece (issue 52): CPU time of each call, median of ``--repeats``, the load
average printed.

Pieces, at an orbit of NNM 20 near 2 J (converged by a short continuation first, not timed):

* ``state``: a state sweep over a quarter period (25 steps: a corrector iterate's residual, and again for its error);
* ``d/dh sweep``: the same steps recording the stage tangents and d[q; v]/dh (the Jacobian's integration);
* ``jacobian``: the quarter-period Jacobian J = [dq(T/4)/dq0, dq(T/4)/dT] (ShootingProblem.jacobian);
* ``LU``: the corrector's factorisation of [J; row] (continuation.linalg.LeastSquares);
* ``A11 reversible`` / ``A11 sweep``: the multipliers' half-period block at the accepted point, from the quarter map
  (orbits.settings.ORBITS.half_map = "reversible") or by a sweep over T/2 ("sweep").

``--other TREE`` runs the same pieces in another solver tree (e.g. ``git worktree add --detach /tmp/base <commit>``),
in turn with this one; a piece the other tree does not have is skipped there.  Usage::

    python benchmarks/bench_shooting_point.py --repeats 21
    python benchmarks/bench_shooting_point.py --repeats 21 --rounds 3 --other /tmp/base
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

_CHILD = r"""
import dataclasses, json, os, sys, time
import numpy as np
model_file, repeats = sys.argv[1], int(sys.argv[2])
import nnm_solver as nnm
from nnm_solver.threads import blas_limited
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.shooting import ShootingProblem
from nnm_solver.orbits import shooting_stability
from nnm_solver.continuation.linalg import LeastSquares, stacked
from nnm_solver.integrators import gauss

def median_ms(f):
    f()
    times = []
    for _ in range(repeats):
        c = time.process_time()
        f()
        times.append(time.process_time() - c)
    return 1e3 * sorted(times)[len(times) // 2]

out = {}
with blas_limited():
    model = nnm.load_model(model_file)
    b = nnm.continue_nnm(model, 20, 2.0, tongues="skip", floquet=False, locate_events=False)
    ms = modal_system(model)
    prob = ShootingProblem(ms, 19, 100, integrator="gauss6")
    u = prob.pack(ms.to_modal(b.x0[-1]), np.zeros(ms.n), 1.0 / b.frequency_hz[-1])
    q0, v0, T = prob.unpack(u)
    h = prob._h(T)
    k = gauss.constants(ms, h, 3)
    args = (q0, v0, h, prob.nsteps, *ms.kernel, k.C1, k.Cc, k.F, k.G, k.b, k.bbar, k.c)
    out["state"] = median_ms(lambda: gauss.sweep_state(*args))
    out["d/dh sweep"] = median_ms(lambda: gauss._sweep_with_h(*args, k.Abar, k.Minv))
    out["jacobian"] = median_ms(lambda: prob.jacobian(u))
    r, J = prob.jacobian(u)
    row = np.ones(J.shape[1])
    out["LU"] = median_ms(lambda: LeastSquares(stacked(J, row)))
    prob.accept(u, J)

    def half_map():
        prob._accepted_maps = None
        prob.stability_maps()
    base = shooting_stability.ORBITS
    routes = ("reversible", "sweep") if hasattr(base, "half_map") else ("sweep",)
    for route in routes:
        if hasattr(base, "half_map"):
            shooting_stability.ORBITS = dataclasses.replace(base, half_map=route)
        out["A11 " + route] = median_ms(half_map)
    shooting_stability.ORBITS = base
print(json.dumps(dict(ms=out, load=os.getloadavg()[0], source=nnm.__file__)))
"""


def run(tree, repeats):
    env = dict(os.environ, PYTHONPATH=str(tree))
    res = subprocess.run([sys.executable, "-c", _CHILD, str(ROOT / "assets" / "paris.h5"), str(repeats)], env=env,
                         cwd=str(tree), capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=21, help="calls per piece (the median is printed)")
    ap.add_argument("--rounds", type=int, default=1, help="runs of each tree, in turn")
    ap.add_argument("--other", help="another solver tree to run beside this one")
    args = ap.parse_args()
    trees = [("this", ROOT)] + ([("other", Path(args.other))] if args.other else [])
    results = {name: [] for name, _ in trees}
    for _ in range(args.rounds):
        for name, tree in trees:
            r = run(tree, args.repeats)
            results[name].append(r)
            print(f"{name}: load {r['load']:.2f} {r['source']}", flush=True)
    pieces = list(dict.fromkeys(p for rs in results.values() for r in rs for p in r["ms"]))
    print("| piece (ms CPU, median) | " + " | ".join(name for name, _ in trees) + " |")
    print("|---|" + "---|" * len(trees))
    for p in pieces:
        cells = []
        for name, _ in trees:
            vals = [r["ms"][p] for r in results[name] if p in r["ms"]]
            cells.append(f"{statistics.median(vals):.2f}" if vals else "-")
        print(f"| {p} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
