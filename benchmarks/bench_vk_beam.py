"""The full von Karman hinged beam (issue 55's independent check) with continue_nnm's defaults: time and accuracy.

Usage (from the repository root)::

    python benchmarks/bench_vk_beam.py                          # 8 and 16 elements, defaults (tongues followed)
    python benchmarks/bench_vk_beam.py --elements 8 --tongues skip --rounds 3
    python benchmarks/bench_vk_beam.py --elements 16 --kernel dense      # the old kernel (dense modal stage LU)
    python benchmarks/bench_vk_beam.py --sweeps 8 16 32 64               # one period's sweeps, dense vs band

Each run is a separate process: ``nnm_fem.von_karman_beam(1, 0.01, 0.02, 210e9, 7800, elements, "hinged")``, NNM 1
by ``nnm.continue_nnm(model, 1, energy_max)`` with energy_max the closed form's energy at a midspan amplitude of two
thicknesses (23.87 J), every other setting the default.  Printed per run: wall and CPU time (s), the time to the first
point (the skeleton), points, status, the largest relative frequency error against the closed form
(``nnm_fem.vk_beam.hinged_backbone``, at each point's midspan amplitude) of the points labelled backbone up to
a = h and a = 2 h, the largest amplitude on the backbone and the first point off it (its label); medians over
``--rounds`` and the load average before and after.  Wall times vary 2-5x with the load of a shared machine; the CPU
time (one BLAS thread while the branch is computed) less.

``--kernel`` picks the general Gauss kernel's stage solver: ``auto`` (the code's choice, integrators/settings.py:
the band LU in physical coordinates for these beams, general_band.py) or ``dense`` (the modal kernel with a dense LU
of the 3n x 3n stage system, forced by a KERNELS whose band_min_dofs no model reaches).  ``--sweeps`` times one
period of gauss6 (100 steps) at a = h, state and sensitivity (2n + 1 columns), with both solvers on beams of the
given element counts and (``--plate``) the clamped 6 x 6 plate (342 DOFs), CPU time with one BLAS thread.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
import numpy as np
import nnm_solver as nnm, nnm_fem
from nnm_fem.vk_beam import hinged_backbone
L, h, b, E, rho = 1.0, 0.01, 0.02, 210e9, 7800.0
N, tongues, kernel = int(sys.argv[1]), sys.argv[2], sys.argv[3]
if kernel == "dense":
    import dataclasses
    from nnm_solver.integrators import general_band
    general_band.KERNELS = dataclasses.replace(general_band.KERNELS, band_min_dofs=10 ** 9)
model = nnm_fem.von_karman_beam(L, h, b, E, rho, elements=N, ends="hinged")
mid = model.dof_labels.index(f"node {N + 1} uz")
energy_max = float(hinged_backbone(2 * h, L, h, E, rho)[1]) * b
t0, c0 = time.perf_counter(), time.process_time()
first = None
it = nnm.iter_nnm(model, 1, energy_max, tongues=tongues)
for p in it:
    if first is None:
        first = time.perf_counter() - t0
branch = it.branch()
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
a = np.abs(branch.x0[:, mid]) / h
err = branch.frequency_hz / hinged_backbone(a * h, L, h, E, rho)[0] - 1
on = np.array([str(x) == "backbone" for x in branch.labels])
off = np.flatnonzero(~on)
def worst(limit):
    sel = on & (a <= limit)
    return float(np.abs(err[sel]).max()) if sel.any() else float("nan")
print(json.dumps(dict(elements=N, tongues=tongues, kernel=kernel, dofs=model.n, wall=wall, cpu=cpu, first_point=first,
                      points=len(branch.energy), status=branch.status, err_1h=worst(1.0), err_2h=worst(2.0),
                      backbone_a_max=float(a[on].max()), first_off_a=float(a[off[0]]) if off.size else None,
                      first_off_label=str(branch.labels[off[0]]) if off.size else None,
                      labels=sorted(set(map(str, branch.labels))), message=branch.message[:300])))
"""


SWEEPS = r"""
import json, sys, time
import numpy as np
from threadpoolctl import threadpool_limits
import nnm_fem
from nnm_solver.model.modal import modal_system
from nnm_solver.integrators import general, general_band
N = int(sys.argv[1])
if N > 0:
    model = nnm_fem.von_karman_beam(1.0, 0.01, 0.02, 210e9, 7800.0, elements=N, ends="hinged")
    amplitude = 0.01
else:
    model = nnm_fem.von_karman_plate(0.3, 0.3, 0.001, 70e9, 0.3, 2700.0, elements=-N, edges="clamped")
    amplitude = 0.001
s = modal_system(model)
lay = general_band.layout(s)
x = s.Phi[:, 0] / np.abs(s.Phi[:, 0]).max() * amplitude
q0, v0 = s.to_modal(x), np.zeros(s.n)
h = 2 * np.pi / np.sqrt(s.omega2[0]) / 100
out = dict(dofs=s.n, w=lay.w, auto=general.stage_solver(s, 3))
res = {}
with threadpool_limits(1):
    for solver in ("dense", "band"):
        general.sweep(s, 3, q0, v0, h, 2, ncols=2 * s.n, solver=solver)          # compile
        t = time.process_time()
        res[solver, "state"] = general.sweep(s, 3, q0, v0, h, 100, solver=solver)
        out[solver + "_state"] = time.process_time() - t
        t = time.process_time()
        res[solver, "sens"] = general.sweep(s, 3, q0, v0, h, 100, ncols=2 * s.n, solver=solver)
        out[solver + "_sens"] = time.process_time() - t
d, b = res["dense", "sens"], res["band", "sens"]
out["q_diff"] = float(np.abs(b[0] - d[0]).max() / np.abs(d[0]).max())
out["monodromy_diff"] = float(max(np.abs(b[i] - d[i]).max() / np.abs(d[i]).max() for i in (4, 5)))
print(json.dumps(out))
"""


def _child(code, *args):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True,
                         env=env, cwd=ROOT, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run(elements, tongues, kernel="auto"):
    return _child(CHILD, elements, tongues, kernel)


def sweeps(elements, plate):
    """One period's sweeps, dense vs band, per beam (and the plate): CPU seconds and their differences."""
    for N in list(elements) + ([-6] if plate else []):
        r = _child(SWEEPS, N)
        name = f"{N} elements" if N > 0 else f"plate {-N} x {-N}"
        print(f"{name} ({r['dofs']} DOFs, half-bandwidth {r['w']}, auto: {r['auto']}): state {r['dense_state']:.2f} "
              f"-> {r['band_state']:.2f} s, sensitivity {r['dense_sens']:.2f} -> {r['band_sens']:.2f} s CPU (dense "
              f"-> band); band vs dense: state {r['q_diff']:.1e}, sensitivity {r['monodromy_diff']:.1e}", flush=True)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--elements", type=int, nargs="+", default=[8, 16])
    p.add_argument("--tongues", default="follow", choices=["follow", "skip"])
    p.add_argument("--rounds", type=int, default=1)
    p.add_argument("--kernel", default="auto", choices=["auto", "dense"])
    p.add_argument("--sweeps", type=int, nargs="*", default=None, help="time single sweeps on these beams instead")
    p.add_argument("--plate", action="store_true", help="with --sweeps: the clamped 6 x 6 plate too")
    args = p.parse_args(argv)
    print(f"load average before: {os.getloadavg()}")
    if args.sweeps is not None:
        sweeps(args.sweeps, args.plate)
        print(f"load average after: {os.getloadavg()}")
        return
    for n in args.elements:
        rows = [run(n, args.tongues, args.kernel) for _ in range(args.rounds)]
        for r in rows:
            print(json.dumps(r))
        med = {k: statistics.median(r[k] for r in rows) for k in ("wall", "cpu", "first_point")}
        r = rows[-1]
        print(f"{n} elements ({r['dofs']} DOFs), tongues={args.tongues}, kernel {args.kernel}: median wall {med['wall']:.0f} s, cpu "
              f"{med['cpu']:.0f} s, first point {med['first_point']:.0f} s; {r['points']} points, {r['status']}; "
              f"backbone points vs closed form: {r['err_1h']:.1e} to a = h, {r['err_2h']:.1e} to 2 h (backbone up to "
              f"a = {r['backbone_a_max']:.3f} h); first point off it: {r['first_off_label']} at a = "
              f"{r['first_off_a'] if r['first_off_a'] is None else round(r['first_off_a'], 3)} h")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
