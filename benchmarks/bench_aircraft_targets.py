"""Issue 52's "Done when" numbers on the aircraft (assets/paris.h5: 548 DOFs, 4 cubic springs), side by side.

Three cases, each run in a process of its own (one BLAS thread per call, the solver's spectrum workers on, its
numba kernels loaded once by a warm-up run that is not timed), ``--repeats`` times in turn, medians printed with
the load average before and after each run:

* ``fep``: the four backbones of the paper, ``continue_nnm(model, mode, energy_max=200, tongues="skip")`` for modes
  10, 13, 19, 20 at the default settings (gauss6 shooting, multipliers and events): the seconds of each, their sum
  (target <= 20 s), status, points, events, and whether stability is known at every point (no NaN multiplier);
* ``fold``: mode 20 at the defaults (``iter_nnm``, tongues followed) until the energy turns back for the first time
  (the first energy fold) or the frequency has moved 5 % from the first point (bench_targets.py's rule; target
  <= 5 s);
* ``hb``: condensed harmonic balance of mode 20 to 3 J (``method="hb", condensed=True, harmonics=9``): milliseconds
  a point (target <= 1 ms), the warm-up being the same run (its skeleton cached, as in bench_per_point.py: the
  cost a point, not the skeleton's; the other two cases time their skeletons).

``--other TREE`` runs another solver tree beside this one (e.g. ``git worktree add /tmp/base main``);
``--dump DIR`` writes each branch's arrays (DIR/<tree>_<case>.npz: energy, frequency, stability, multipliers,
initial states, labels, events) for a point-by-point comparison of two trees (``--compare DIR``).  Usage::

    python benchmarks/bench_aircraft_targets.py --repeats 3
    python benchmarks/bench_aircraft_targets.py --case hb --other /tmp/base --repeats 5
    python benchmarks/bench_aircraft_targets.py --repeats 1 --dump /tmp/arrays --other /tmp/base --compare
    python benchmarks/bench_aircraft_targets.py --repeats 1 --dump /tmp/after --compare-with /tmp/before
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
CASES = ("fep", "fold", "hb")

_CHILD = r"""
import json, sys, time
import numpy as np
case, model_file, dump = sys.argv[1], sys.argv[2], sys.argv[3]
import nnm_solver as nnm
from nnm_solver.threads import blas_limited
model = nnm.load_model(model_file)

def arrays(b, extra=None):
    ev = [(e["kind"], float(e["energy"]), float(e.get("frequency_hz", np.nan))) for e in b.events]
    return dict(energy=b.energy, frequency_hz=b.frequency_hz, stable=b.stable, floquet=b.floquet, x0=b.x0, v0=b.v0,
                labels=np.asarray(b.labels, dtype=str), events=np.asarray(ev, dtype=object), status=b.status)

def fold(m=20, energy_max=1e6):
    # bench_targets.py's rule (issues 17, 52): until the energy turns back (the first fold) or the frequency has
    # moved 5 % from the first point
    it = nnm.iter_nnm(model, m, energy_max)
    E, F = [], []
    for p in it:
        E.append(p.energy)
        F.append(p.frequency_hz)
        if abs(F[-1] / F[0] - 1) >= 0.05 or (len(E) > 2 and E[-1] < E[-2]):
            it.cancel()
            break
    return it.branch()

def run(case, warm=False):
    t, c = time.perf_counter(), time.process_time()
    rows, branches = [], {}
    if case == "fep":
        for m in (10, 13, 19, 20):
            t1 = time.perf_counter()
            b = nnm.continue_nnm(model, m, 0.01 if warm else 200.0, tongues="skip")
            rows.append(dict(mode=m, seconds=time.perf_counter() - t1, points=len(b), status=b.status,
                             events=len(b.events), stability_known=bool(np.all(np.isfinite(b.floquet)))))
            branches[f"mode{m}"] = b
            if warm:
                break
    elif case == "fold":
        b = fold(energy_max=0.01 if warm else 1e6)
        rows.append(dict(mode=20, points=len(b), status=b.status, events=len(b.events),
                         last_energy=float(b.energy[-1]), stability_known=bool(np.all(np.isfinite(b.floquet)))))
        branches["mode20"] = b
    else:
        b = nnm.continue_nnm(model, 20, 3.0, method="hb", condensed=True, harmonics=9)   # (warm: its skeleton too)
        rows.append(dict(mode=20, points=len(b), status=b.status, events=len(b.events)))
        branches["mode20"] = b
    return time.perf_counter() - t, time.process_time() - c, rows, branches

run(case, warm=True)                      # numba kernels, the skeleton's cache: not timed
seconds, cpu, rows, branches = run(case)
if dump != "-":
    for name, b in branches.items():
        np.savez(f"{dump}_{case}_{name}.npz", **arrays(b))
print(json.dumps(dict(seconds=seconds, cpu=cpu, rows=rows, source=nnm.__file__)))
"""


def run(tree, case, dump):
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    before = os.getloadavg()[0]
    out = subprocess.run([sys.executable, "-c", _CHILD, case, str(ROOT / "assets" / "paris.h5"), dump], env=env,
                         capture_output=True, text=True, cwd=tree)
    if out.returncode:
        raise RuntimeError(f"the {case} run of {tree} failed:\n{out.stderr[-3000:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    if not Path(res["source"]).resolve().is_relative_to(Path(tree).resolve()):
        raise RuntimeError(f"the run of {tree} imported {res['source']}")
    res["load"] = (before, os.getloadavg()[0])
    return res


def report(case, tname, rs):
    loads = ", ".join(f"{a:.1f}->{b:.1f}" for a, b in (r["load"] for r in rs))
    wall, cpu = statistics.median(r["seconds"] for r in rs), statistics.median(r["cpu"] for r in rs)
    rows = rs[0]["rows"]
    if case == "fep":
        per = ", ".join(f"{row['mode']}: {statistics.median(r['rows'][k]['seconds'] for r in rs):.1f} s "
                        f"({row['points']} pts, {row['status']}, {row['events']} events"
                        f"{'' if row['stability_known'] else ', stability NOT known everywhere'})"
                        for k, row in enumerate(rows))
        print(f"  fep  {tname:10s} {wall:7.1f} s wall, {cpu:6.1f} s CPU in all (target 20 s); modes {per}; "
              f"medians of {len(rs)}, load {loads}")
    elif case == "fold":
        row = rows[0]
        print(f"  fold {tname:10s} {wall:7.2f} s wall, {cpu:6.2f} s CPU (target 5 s); {row['points']} points to "
              f"{row['last_energy']:.4g} J, {row['events']} events, stability "
              f"{'known' if row['stability_known'] else 'NOT known'} everywhere; medians of {len(rs)}, load {loads}")
    else:
        row = rows[0]
        print(f"  hb   {tname:10s} {1e3 * wall / row['points']:7.2f} ms a point wall, {1e3 * cpu / row['points']:6.2f} ms "
              f"CPU (target 1 ms); {row['points']} points, {row['status']}; medians of {len(rs)}, load {loads}")


def compare(dir_a, dir_b, a_name="this", b_name="other"):
    """Largest differences between the branches dumped in dir_a (by tree a_name) and dir_b (b_name), case by case."""
    import numpy as np
    for fa in sorted(Path(dir_a).glob(f"{a_name}_*.npz")):
        fb = Path(dir_b) / fa.name.replace(a_name + "_", b_name + "_", 1)
        if not fb.exists():
            continue
        A, B = np.load(fa, allow_pickle=True), np.load(fb, allow_pickle=True)
        what = fa.stem[len(a_name) + 1:]
        if len(A["energy"]) != len(B["energy"]):
            print(f"  {what}: {len(A['energy'])} points against {len(B['energy'])}")
            continue
        rel = lambda k: float(np.nanmax(np.abs(A[k] - B[k]) / np.maximum(np.abs(B[k]), 1e-300))) if len(A[k]) else 0.0  # noqa: E731
        x = float(np.max(np.abs(A["x0"] - B["x0"]))) / max(float(np.max(np.abs(B["x0"]))), 1e-300)
        mu = np.nan_to_num(A["floquet"] - B["floquet"])
        print(f"  {what}: {len(A['energy'])} points; max rel. diff energy {rel('energy'):.1e}, frequency "
              f"{rel('frequency_hz'):.1e}, x0 {x:.1e}, multipliers {float(np.max(np.abs(mu))) if mu.size else 0:.1e}; "
              f"stability flags differ at {int(np.sum(A['stable'] != B['stable']))}; labels differ at "
              f"{int(np.sum(A['labels'] != B['labels']))}; events {len(A['events'])} / {len(B['events'])}, kinds "
              f"{'equal' if [e[0] for e in A['events']] == [e[0] for e in B['events']] else 'DIFFER'}; "
              f"status {A['status']} / {B['status']}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", choices=CASES, action="append", help="one case (repeatable; default: all three)")
    ap.add_argument("--other", help="another solver tree run side by side")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dump", help="directory for each branch's arrays (one run's)")
    ap.add_argument("--compare", action="store_true", help="with --dump and --other: compare the two trees' arrays")
    ap.add_argument("--compare-with", help="with --dump: compare this tree's arrays with those dumped in this "
                                           "directory by an earlier run (e.g. before a change)")
    args = ap.parse_args(argv)
    trees = [("this", ROOT)] + ([("other", Path(args.other))] if args.other else [])
    cases = args.case or list(CASES)
    if args.dump:
        Path(args.dump).mkdir(parents=True, exist_ok=True)
    print(f"aircraft (assets/paris.h5), issue 52's targets; load average at the start "
          f"{tuple(round(x, 2) for x in os.getloadavg())}; trees: "
          + ", ".join(f"{n} = {t}" for n, t in trees))
    results = {}
    for k in range(args.repeats):
        for case in cases:
            for tname, tree in trees:
                dump = str(Path(args.dump) / tname) if args.dump and k == 0 else "-"
                results.setdefault((case, tname), []).append(run(tree, case, dump))
    for (case, tname), rs in results.items():
        report(case, tname, rs)
    if args.compare and args.dump and args.other:
        print("this tree against the other (first run of each):")
        compare(args.dump, args.dump)
    if args.compare_with and args.dump:
        print(f"this tree against the arrays in {args.compare_with}:")
        compare(args.dump, args.compare_with, "this", "this")


if __name__ == "__main__":
    main()
