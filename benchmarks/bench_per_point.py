"""Cost per converged point of condensed harmonic balance on the aircraft (issue 52: the lean per-point path).

The case: ``continue_nnm(load_model("assets/paris.h5"), 20, 3.0, method="hb", condensed=True, harmonics=9)``
(548 modes, 4 springs: 22 unknowns), at the defaults and with the cheapest honest option (``error_estimate=False``:
no truncation estimate, freq_error NaN), each run in its own process (BLAS 1 thread), trees in turn, ``--repeats``
times, after one warm-up run per process (compiled kernels, the skeleton's cache).  Printed: the median milliseconds
per point of each tree and variant, wall and CPU time of the process (the CPU time is the steadier on a shared
machine), with the load average before and after, the points and status; with
``--sections`` the time per point of each part of the driver's work (this tree only: CPU time of the thread inside
each method, nested parts included in their callers; the total is the process's CPU time).  Usage::

    git archive e655183 | (mkdir -p /tmp/base && tar -x -C /tmp/base)
    python benchmarks/bench_per_point.py --before /tmp/base --repeats 5 --sections

``--compare`` (with ``--before``) checks that the two trees give the same branches: the aircraft's NNM 20 to 3 J with
and without the estimate and, skipping tongues, to 6 J, the 2-DOF benchmark's NNM 1 to 50 J and, skipping tongues, to
200 J (condensed HB): every column (energy, frequency, freq_error, fundamental share, x0, v0, coefficients,
stability), labels, statuses, messages, events and tongues, printed as the largest relative differences::

    python benchmarks/bench_per_point.py --before /tmp/base --repeats 0 --compare

``--calls`` counts the function calls (Python functions and C functions, numpy's included: each costs ~0.1-5 us) made
in each part per point, this tree and ``--before``'s side by side (a profile hook; no times)::

    python benchmarks/bench_per_point.py --before /tmp/base --repeats 0 --calls
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
VARIANTS = {"defaults": {}, "no estimate": {"error_estimate": False}}

_CHILD = r"""
import collections, json, sys, time
kw, E, sections = json.loads(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
calls = sections == "calls"
import nnm_solver as nnm
from nnm_solver.threads import blas_limited
acc = collections.Counter()
if calls:     # Python and C function calls (numpy's included) made in each part, innermost part counted
    from nnm_solver.driver import iterator as it_, refinement as rf
    from nnm_solver.continuation import engine_driver as ed
    from nnm_solver.results import stops, branch as br
    parts = {ed.EngineDriver.next.__code__: "engine: predictor, corrector (continuation/)",
             it_.NNMIterator._record.__code__: "record the point (candidate.py)",
             rf.StepRefinement.estimate.__code__: "truncation error estimate (hb_error.py)",
             it_.NNMIterator._decide.__code__: "label and policy (backbone/)",
             it_.NNMIterator._locate.__code__: "step check and events (stability/locator.py)",
             stops.LoopDetector.add.__code__: "loop detector (stops.py)",
             br.Branch.from_points.__code__: "the Branch (physical states, results/point.py)"}
    inside = ["the iterator and the rest"]
    def counter(frame, event, arg):
        if event == "call" or event == "c_call":
            acc[inside[-1]] += 1
            if event == "call" and frame.f_code in parts:
                inside.append(parts[frame.f_code])
        elif event == "return" and frame.f_code in parts and inside[-1] == parts[frame.f_code]:
            inside.pop()
elif sections == "1":
    from nnm_solver.driver import iterator as it_, refinement as rf
    from nnm_solver.continuation import engine_driver as ed
    from nnm_solver.results import stops, branch as br
    from nnm_solver.backbone import labels as lb
    from nnm_solver.driver import candidate as cd
    def wrap(obj, name, key):
        f = getattr(obj, name)
        def g(*a, **k):
            t = time.thread_time()
            try:
                return f(*a, **k)
            finally:
                acc[key] += time.thread_time() - t
        setattr(obj, name, g)
    for obj, name, key in [(ed.EngineDriver, "next", "engine: predictor, corrector (continuation/)"),
                           (it_.NNMIterator, "_record", "record the point (candidate.py)"),
                           (rf.StepRefinement, "estimate", "truncation error estimate (hb_error.py)"),
                           (it_.NNMIterator, "_decide", "label and policy (backbone/)"),
                           (lb.FamilyLabels, "verdict", "  of which the skeleton's verdict"),
                           (it_.NNMIterator, "_locate", "step check and events (stability/locator.py)"),
                           (stops.LoopDetector, "add", "loop detector (stops.py)"),
                           (br.Branch, "from_points", "the Branch (physical states, results/point.py)")]:
        wrap(obj, name, key)
model = nnm.load_model(sys.argv[4])
with blas_limited():
    nnm.continue_nnm(model, 20, E, **kw)                 # warm-up
    acc.clear()
    if calls:
        sys.setprofile(counter)
    t, c = time.perf_counter(), time.process_time()
    b = nnm.continue_nnm(model, 20, E, **kw)
    dt, dc = time.perf_counter() - t, time.process_time() - c
    sys.setprofile(None)
print(json.dumps(dict(seconds=dt, cpu=dc, points=len(b), status=b.status, sections={k: v for k, v in acc.items()},
                 source=nnm.__file__)))
"""


_DUMP = r"""
import json, pickle, sys
import numpy as np
import nnm_solver as nnm
from nnm_solver.threads import blas_limited
air = nnm.load_model(sys.argv[1])
two = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
cases = {"aircraft NNM 20 to 3 J": (air, 20, 3.0, dict(harmonics=9)),
         "aircraft NNM 20 to 3 J, no estimate": (air, 20, 3.0, dict(harmonics=9, error_estimate=False)),
         "aircraft NNM 20 to 6 J, skip": (air, 20, 6.0, dict(harmonics=9, tongues="skip")),
         "2-DOF NNM 1 to 50 J": (two, 1, 50.0, {}),
         "2-DOF NNM 1 to 200 J, skip": (two, 1, 200.0, dict(tongues="skip"))}
out = {}
with blas_limited():
    for name, (m, mode, E, kw) in cases.items():
        b = nnm.continue_nnm(m, mode, E, method="hb", condensed=True, **kw)
        out[name] = dict({k: np.array(getattr(b, k)) for k in ("energy", "frequency_hz", "freq_error",
                                                                "fundamental_share", "x0", "v0", "coefficients",
                                                                "stable")},
                         labels=list(b.labels), status=b.status, message=b.message,
                         events=[(e["kind"], e["located"], float(e["energy"])) for e in b.events],
                         tongues=[repr((t.order, t.partner_mode, t.entry_index, t.landings, t.skipped, t.entry_energy,
                                        t.exit_energy)) for t in b.tongues])
sys.stdout.buffer.write(pickle.dumps((nnm.__file__, out)))
"""


def branches(tree):
    """The comparison branches of ``tree`` (``_DUMP``, run in its own process)."""
    import pickle
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", _DUMP, str(ROOT / "assets" / "paris.h5")], env=env,
                         capture_output=True, check=True, cwd=tree)
    source, res = pickle.loads(out.stdout)
    if not Path(source).resolve().is_relative_to(Path(tree).resolve()):
        raise RuntimeError(f"the run of {tree} imported {source}")
    return res


def compare(a, b):
    """Print the largest relative differences between the branches a (this tree) and b (the other), case by case."""
    import numpy as np

    def rel(x, y):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if x.shape != y.shape or not np.array_equal(np.isfinite(x), np.isfinite(y)):
            return float("inf")
        ok = np.isfinite(y)
        return float(np.max(np.abs(x[ok] - y[ok]) / np.maximum(np.abs(y[ok]), 1e-300), initial=0.0))

    for name, x in a.items():
        y = b[name]
        if len(x["energy"]) != len(y["energy"]):
            print(f"  {name}: {len(x['energy'])} points against {len(y['energy'])}: DIFFERENT")
            continue
        same = [k for k in ("labels", "status", "message", "tongues") if x[k] != y[k]]
        same += ["stable"] if not np.array_equal(x["stable"], y["stable"]) else []
        same += ["events"] if [e[:2] for e in x["events"]] != [e[:2] for e in y["events"]] else []
        ev = max([abs(e[2] / f[2] - 1) for e, f in zip(x["events"], y["events"])], default=0.0)
        vec = {k: float(np.max(np.abs(x[k] - y[k]), initial=0.0) / max(float(np.max(np.abs(y[k]), initial=0.0)), 1e-300))
               for k in ("x0", "v0", "coefficients")}
        print(f"  {name}: {len(x['energy'])} points; relative differences: energy {rel(x['energy'], y['energy']):.1e}, "
              f"frequency {rel(x['frequency_hz'], y['frequency_hz']):.1e}, freq_error "
              f"{rel(x['freq_error'], y['freq_error']):.1e}, share {rel(x['fundamental_share'], y['fundamental_share']):.1e}, "
              + ", ".join(f"{k} {v:.1e}" for k, v in vec.items()) + f", events' energies {ev:.1e}; "
              + (f"DIFFERENT: {', '.join(same)}" if same else "labels, stability, status, message, events, tongues "
                                                              "the same"))


def run(tree, kw, energy, sections):
    """One timed branch of ``tree`` in its own process; sections : False, True (CPU time per part) or "calls" (the
    function calls per part, counted by a profile hook: its times are not the run's)."""
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    before = os.getloadavg()[0]
    flag = "calls" if sections == "calls" else ("1" if sections else "0")
    out = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(kw), str(energy), flag,
                          str(ROOT / "assets" / "paris.h5")], env=env, capture_output=True, text=True, check=True,
                         cwd=tree)        # (the child's sys.path starts with its working directory)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    if not Path(res["source"]).resolve().is_relative_to(Path(tree).resolve()):
        raise RuntimeError(f"the run of {tree} imported {res['source']}")
    res["load"] = (before, os.getloadavg()[0])
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="another solver tree to run side by side (e.g. the commit before issue 52)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--energy-max", type=float, default=3.0)
    ap.add_argument("--sections", action="store_true", help="time per point of each part of the work (this tree)")
    ap.add_argument("--compare", action="store_true", help="with --before: compare the two trees' branches")
    ap.add_argument("--calls", action="store_true", help="the function calls (Python and C, numpy's included) per "
                                                          "point in each part, this tree and --before's (defaults)")
    args = ap.parse_args(argv)
    if args.compare and args.before:
        print("this tree's branches against the other's (condensed HB):")
        compare(branches(ROOT), branches(Path(args.before)))
    trees = [("this tree", ROOT)] + ([("before", Path(args.before))] if args.before else [])
    if args.calls:
        kw_all = dict(method="hb", condensed=True, harmonics=9)
        counted = {tname: run(tree, kw_all, args.energy_max, "calls") for tname, tree in trees}
        print("function calls a point (Python and C, numpy's included; defaults), by part: "
              + ", ".join(f"{t}" for t in counted))
        keys = list(dict.fromkeys(k for r in counted.values() for k in r["sections"]))
        for key in keys + ["total"]:
            vals = [(sum(r["sections"].values()) if key == "total" else r["sections"].get(key, 0)) / r["points"]
                    for r in counted.values()]
            print(f"    {key:48s} " + "  ".join(f"{v:8.0f}" for v in vals))
    print(f"aircraft NNM 20 to {args.energy_max:g} J, condensed HB H = 9; load average at the start "
          f"{tuple(round(x, 2) for x in os.getloadavg())}")
    results = {}
    for _ in range(args.repeats):
        for vname, kw in VARIANTS.items():
            for tname, tree in trees:
                kw_all = dict(method="hb", condensed=True, harmonics=9, **kw)
                results.setdefault((vname, tname), []).append(run(tree, kw_all, args.energy_max, False))
    for (vname, tname), rs in results.items():
        ms = statistics.median(1e3 * r["seconds"] / r["points"] for r in rs)
        cpu = statistics.median(1e3 * r["cpu"] / r["points"] for r in rs)
        loads = ", ".join(f"{a:.1f}->{b:.1f}" for a, b in (r["load"] for r in rs))
        print(f"  {vname:12s} {tname:10s} {ms:7.2f} ms a point wall, {cpu:7.2f} ms CPU (medians of {len(rs)}; "
              f"{rs[0]['points']} points, {rs[0]['status']}; load {loads})")
    if args.sections:
        for vname, kw in VARIANTS.items():
            rs = [run(ROOT, dict(method="hb", condensed=True, harmonics=9, **kw), args.energy_max, True)
                  for _ in range(args.repeats)]
            N = rs[0]["points"]
            print(f"\n  {vname}, this tree, per point (median of {len(rs)}; CPU time in each part, "
                  f"load {os.getloadavg()[0]:.1f}):")
            print(f"    {'total':48s} {statistics.median(1e3 * r['cpu'] / N for r in rs):7.3f} ms")
            for key in rs[0]["sections"]:
                print(f"    {key:48s} {statistics.median(1e3 * r['sections'].get(key, 0) / N for r in rs):7.3f} ms")


if __name__ == "__main__":
    main()
