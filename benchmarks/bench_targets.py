"""The end-to-end speed targets of issue 17, with a check that the answers did not change.

Two runs, each repeated (median of ``--repeats``, default 3) in one process, BLAS limited to one thread (the
Floquet eigenproblems of the aircraft run in the solver's worker threads beside the next steps: both cores;
NNM_SPECTRUM_WORKERS=0 for one), numba kernels warmed up first, the load average printed before and after every
run:

* ``2dof``: the 2-DOF benchmark (assets/two_dof.h5: M = I, K = [[2, -1], [-1, 2]], grounded cubic spring
  k3 = 0.5 on DOF 0), NNM 1 from low energy to 1e4 J: the complete FEP through the 3:1 tongue
  (target <= 0.5 s);
* ``paris``: the aircraft (assets/paris.h5 or ``--paris-file``), NNM 20, 200 Newmark steps per period,
  Floquet multipliers at every point, events located, until the frequency has moved 5 % from the
  first point or the energy turns back for the first time (the first fold; target <= 5 s).

``--save-reference FILE`` writes every point's energy, frequency and stability flag and the located events
of one run; ``--reference FILE`` compares a run with such a file (written e.g. by an older version of the
solver): the largest relative difference of frequency and energy point by point, the stability flags that
differ, and the events (kind and relative energy difference).  Usage::

    python benchmarks/bench_targets.py                       # both cases, 3 runs each (~1-2 min)
    python benchmarks/bench_targets.py --case 2dof --repeats 5
    python benchmarks/bench_targets.py --save-reference /tmp/ref.json   # with the old code
    python benchmarks/bench_targets.py --reference /tmp/ref.json        # with the new code
"""
from __future__ import annotations

import argparse
import importlib
import json
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def load():
    return os.getloadavg()[0]


def run_case(name, model, args):
    """One run: (seconds, branch)."""
    import nnm_solver as nnm
    if name == "2dof":
        t0 = time.perf_counter()
        b = nnm.continue_nnm(model, mode=1, energy_max=1e4)
        return time.perf_counter() - t0, b
    stop = threading.Event()
    E, F = [], []

    def on_point(p):
        E.append(p["energy"])
        F.append(p["frequency_hz"])
        if abs(F[-1] / F[0] - 1) >= 0.05 or (len(E) > 2 and E[-1] < E[-2]):
            stop.set()

    t0 = time.perf_counter()
    b = nnm.continue_nnm(model, mode=args.paris_mode, energy_max=1e6, steps_per_period=200, on_point=on_point,
                         stop=stop)
    return time.perf_counter() - t0, b


def summary(b):
    return dict(energy=np.asarray(b.energy).tolist(), frequency_hz=np.asarray(b.frequency_hz).tolist(),
                stable=np.asarray(b.stable).astype(bool).tolist(),
                events=[(e["kind"], float(e["energy"])) for e in b.events])


def on_curve(cur, ref):
    """How far the points of one run are from the other run's curve: for each point of ``cur``, the distance to
    the nearest segment of ``ref``'s polyline in (log10 E, f / f_first) -- the FEP, with the frequency in
    relative units -- and whether its stability flag is that of the nearest reference point on that segment,
    for points more than 1e-3 (in those units) from the segment's ends.  A text line."""
    def xy(s):
        return np.column_stack([np.log10(np.asarray(s["energy"])), np.asarray(s["frequency_hz"]) / s["frequency_hz"][0]])
    P, R = xy(cur), xy(ref)
    worst, flags, judged = 0.0, 0, 0
    for k, x in enumerate(P):
        a, b = R[:-1], R[1:]
        d = b - a
        t = np.clip(np.einsum("ij,ij->i", x - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
        dist = np.linalg.norm(a + t[:, None] * d - x, axis=1)
        j = int(np.argmin(dist))
        worst = max(worst, float(dist[j]))
        if min(np.linalg.norm(x - a[j]), np.linalg.norm(x - b[j])) > 1e-3 and ref["stable"][j] == ref["stable"][j + 1]:
            judged += 1
            flags += int(cur["stable"][k] != ref["stable"][j])
    return (f"distance of every point to the reference curve (log10 E, f/f0): max {worst:.2e}; stability flags "
            f"that differ from the reference segment's: {flags} of {judged}")


def compare(cur, ref):
    """Text lines comparing two summaries point by point."""
    n = min(len(cur["energy"]), len(ref["energy"]))
    lines = [f"points: {len(cur['energy'])} (reference {len(ref['energy'])})"]
    if n:
        dF = np.max(np.abs(np.asarray(cur["frequency_hz"][:n]) / np.asarray(ref["frequency_hz"][:n]) - 1))
        dE = np.max(np.abs(np.asarray(cur["energy"][:n]) / np.asarray(ref["energy"][:n]) - 1))
        flags = int(np.sum(np.asarray(cur["stable"][:n]) != np.asarray(ref["stable"][:n])))
        lines.append(f"point by point: max |df/f| {dF:.2e}, max |dE/E| {dE:.2e}, stability flags that differ: {flags}")
        if dE > 1e-3:
            lines.append("  (the runs placed their points differently) " + on_curve(cur, ref))
    ev_c, ev_r = cur["events"], ref["events"]
    lines.append(f"events: {len(ev_c)} (reference {len(ev_r)})")
    for (k, e) in ev_c:
        same = [er for (kr, er) in ev_r if kr == k]
        if same:
            er = min(same, key=lambda x: abs(x - e))
            lines.append(f"  {k:15s} {e:.7g} J   nearest reference {er:.7g} J ({e / er - 1:+.1e})")
        else:
            lines.append(f"  {k:15s} {e:.7g} J   (no {k} in the reference)")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", choices=["2dof", "paris", "all"], default="all")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--paris-file", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--paris-mode", type=int, default=20)
    ap.add_argument("--save-reference", default=None, metavar="FILE")
    ap.add_argument("--reference", default=None, metavar="FILE")
    args = ap.parse_args(argv)
    from threadpoolctl import threadpool_limits
    threadpool_limits(1)
    import nnm_solver as nnm
    nnm.continue_nnm(nnm.load_model(str(ROOT / "assets" / "two_dof.h5")), mode=1, energy_max=1.0)   # warm-up
    cases = ["2dof", "paris"] if args.case == "all" else [args.case]
    out, ref = {}, (json.loads(Path(args.reference).read_text()) if args.reference else {})
    threads = importlib.import_module("nnm_solver.threads")
    print(f"bench_targets: {os.cpu_count()} cores, numpy {np.__version__}, BLAS 1 thread, "
          f"{getattr(threads, 'WORKERS', 0)} worker threads for the multipliers (NNM_SPECTRUM_WORKERS); "
          f"{time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())}")
    for name in cases:
        model = nnm.load_model(str(ROOT / "assets" / "two_dof.h5") if name == "2dof" else args.paris_file)
        times, loads = [], []
        for _ in range(args.repeats):
            l0 = load()
            t, b = run_case(name, model, args)
            times.append(t)
            loads.append((l0, load()))
        print(f"\n{name}: {len(b.energy)} points, status {b.status}; E {b.energy[0]:.4g} -> {b.energy[-1]:.4g} J, "
              f"f {b.frequency_hz[0]:.6g} -> {b.frequency_hz[-1]:.6g} Hz")
        print(f"  seconds: {', '.join(f'{t:.3f}' for t in times)}; median {np.median(times):.3f} s "
              f"({np.median(times) / max(len(b.energy), 1) * 1e3:.1f} ms/point)")
        print(f"  load average per run: {', '.join(f'{a:.2f}->{c:.2f}' for a, c in loads)}")
        print(f"  events: {', '.join(f'{k} {e:.6g} J' for k, e in summary(b)['events']) or '-'}")
        out[name] = summary(b)
        if name in ref:
            print("  against the reference:")
            for line in compare(out[name], ref[name]):
                print("    " + line)
    if args.save_reference:
        Path(args.save_reference).write_text(json.dumps(out))
        print(f"\nreference written to {args.save_reference}")


if __name__ == "__main__":
    main()
