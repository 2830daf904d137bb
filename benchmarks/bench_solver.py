"""Side-by-side benchmark: dense textbook baseline vs the project's solver.

Usage (from the repository root)::

    python benchmarks/bench_solver.py                  # both cases
    python benchmarks/bench_solver.py --case 2dof      # 2-DOF benchmark only (a few seconds)
    python benchmarks/bench_solver.py --case paris     # 548-DOF aircraft, mode 20 (minutes)
    python benchmarks/bench_solver.py --no-memory      # skip the peak-memory subprocesses

For each case, in this one process and with the same model, steps per period and
tolerance, it runs (a) ``dense_baseline.dense_continue`` and (b) ``nnm_solver.continue_nnm``
and prints: converged points, median time per converged point, total time, peak memory
(measured in a separate subprocess per run: tracemalloc peak and the subprocess's
ru_maxrss), the ratio (b)/(a), and the agreement of the two frequency-energy curves:

* ``freq. diff``: the baseline's points vs the solver's branch interpolated (PCHIP in
  log energy) at the same energies, max relative difference over the baseline points
  inside the solver's energy range (where the solver's curve crosses an energy more than
  once, e.g. on a tongue, the closest crossing is used) -- includes interpolation error;
* ``residual``: the solver's orbits (x0, v0, T) plugged into the baseline's own discrete
  shooting function, max ||H|| / ||z0||, and its displacement and velocity parts scaled by
  ||x0|| and omega ||x0||: small when both compute the same discrete orbits.

Cases:

* ``2dof``: M = I, K = [[2, -1], [-1, 2]], grounded cubic spring k3 = 0.5 on DOF 0,
  NNM1 up to ``--energy-2dof`` J (default 1e4: the complete FEP with the 3:1 tongue, whose
  top is at ~4.7e3 J and tip at ~286 J).  The baseline's step is capped at
  ``--dense-step-max`` (default 2 in (z0, T) units): with the textbook unbounded step
  doubling it jumps over the tongue.  With its single-velocity phase condition v0[0] = 0
  the baseline then goes around the tongue more than once (phase-shifted copies of the
  same orbits) before it reaches the energy limit; all its points are timed.
* ``paris``: ``assets/paris.h5`` mode 20.  The solver runs until the frequency has moved by
  5 % from its first point, or the energy turns back (top of a first tongue), or
  ``--energy-paris``, whichever comes first; the dense baseline only runs
  ``--paris-points`` points (its cost per point is what matters) -- time per point
  is compared.

Numba-compiled solver kernels are warmed up on a tiny problem before timing, so compile
time is excluded (it is cached on disk after the first run anyway).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
if str(ROOT) not in sys.path:
    sys.path.insert(1, str(ROOT))

import dense_baseline  # noqa: E402


# ---------------------------------------------------------------------- cases
def load_case(name, args):
    """Return (model, springs_tuples, mode, label)."""
    import nnm_solver
    if name == "2dof":
        M = np.eye(2)
        K = np.array([[2.0, -1.0], [-1.0, 2.0]])
        model = nnm_solver.Model(M, K, springs=[nnm_solver.CubicSpring(dof=0, k3=0.5)], name="2dof")
        return model, 1, "2-DOF, NNM1"
    if name == "paris":
        path = Path(args.paris_file)
        if not path.exists():
            raise FileNotFoundError(f"{path} not found")
        model = nnm_solver.load_model(str(path))
        return model, args.paris_mode, f"paris.h5 ({model.n} DOF), mode {args.paris_mode}"
    raise ValueError(name)


def springs_of(model):
    return [(int(s.dof), None if s.other is None else int(s.other), float(s.k3)) for s in model.springs]


def dense(a):
    return a.toarray() if hasattr(a, "toarray") else np.asarray(a, dtype=float)


# ---------------------------------------------------------------------- runners
def run_baseline(name, model, mode, args, max_points=None):
    energy_max = args.energy_2dof if name == "2dof" else args.energy_paris
    if max_points is None:
        max_points = args.max_points if name == "2dof" else args.paris_points
    step_max = args.dense_step_max if name == "2dof" and args.dense_step_max > 0 else None
    t0 = time.perf_counter()
    r = dense_baseline.dense_continue(dense(model.M), dense(model.K), springs_of(model), mode,
                                      energy_max=energy_max, steps_per_period=args.steps, tol=args.tol,
                                      max_points=max_points, step_max=step_max)
    total = time.perf_counter() - t0
    return dict(energy=r["energy"], frequency_hz=r["frequency_hz"], period=r["period"],
                x0=r["x0"], v0=r["v0"], seconds_per_point=r["seconds_per_point"], total=total,
                stop=r["stop_reason"])


def run_solver(name, model, mode, args):
    import nnm_solver
    stop = threading.Event()
    times, f_first, energies = [], [], []
    t_begin = time.perf_counter()

    def on_point(row):
        times.append(time.perf_counter())
        energies.append(row["energy"])
        if not f_first:
            f_first.append(row["frequency_hz"])
        if name == "paris":
            # stop at a 5 % frequency change from the first point, or at the first energy fold
            # (top of a tongue), or at energy_paris
            if abs(row["frequency_hz"] / f_first[0] - 1.0) >= args.freq_change:
                stop.set()
            if len(energies) > 2 and energies[-1] < energies[-2]:
                stop.set()
        if times[-1] - t_begin > args.solver_time_limit:
            stop.set()

    t0 = time.perf_counter()
    b = nnm_solver.continue_nnm(model, mode=mode, energy_max=(args.energy_2dof if name == "2dof"
                                                               else args.energy_paris),
                                steps_per_period=args.steps, tol=args.tol, max_points=args.max_points,
                                on_point=on_point, stop=stop)
    total = time.perf_counter() - t0
    sp = np.diff(np.concatenate([[t0], times])) if times else np.array([])
    return dict(energy=np.asarray(b.energy), frequency_hz=np.asarray(b.frequency_hz),
                period=np.asarray(b.period), x0=np.asarray(b.x0), v0=np.asarray(b.v0),
                seconds_per_point=sp, total=total, stop=f"{b.status}: {b.message}",
                events=[f"{e['kind']} at E={e['energy']:.4g} J, f={e['frequency_hz']:.6g} Hz ({e['detail']})"
                        for e in getattr(b, "events", [])])


def warm_up():
    """Compile/cache the solver's kernels on a tiny problem (excluded from timings)."""
    import nnm_solver
    model = nnm_solver.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]),
                             springs=[nnm_solver.CubicSpring(dof=0, k3=0.5)])
    nnm_solver.continue_nnm(model, mode=1, energy_max=1.0, max_points=3)


# ---------------------------------------------------------------------- comparison
def frequency_agreement(a, b):
    """Max relative difference of a's frequencies vs b's curve at a's energies.

    b's curve is split into runs where its energy is monotone; on each run f is interpolated
    in log energy (PCHIP, linear for two points), and extrapolated by at most 2 % in energy
    beyond a run's ends (a point of ``a`` right at a fold may lie just outside ``b``'s samples);
    where several runs cover an energy (a fold or a tongue), the closest value is used.
    """
    from scipy.interpolate import PchipInterpolator
    Eb, fb = np.log(b["energy"]), b["frequency_hz"]
    runs, start = [], 0
    for i in range(1, len(Eb)):
        if i == len(Eb) - 1 or (Eb[i + 1] - Eb[i]) * (Eb[i] - Eb[i - 1]) <= 0:
            runs.append(slice(start, i + 1))
            start = i
    interps = []
    for r in runs:
        x, y = Eb[r], fb[r]
        if len(x) < 2:
            continue
        if x[0] > x[-1]:
            x, y = x[::-1], y[::-1]
        if np.any(np.diff(x) <= 0):
            continue
        interps.append((x[0], x[-1], PchipInterpolator(x, y)))
    diffs = []
    for E, f in zip(np.log(a["energy"]), a["frequency_hz"]):
        margin = np.log(1.02)
        cand = [abs(float(p(E)) / f - 1.0) for lo, hi, p in interps if lo - margin <= E <= hi + margin]
        if cand:
            diffs.append(min(cand))
    return (max(diffs) if diffs else float("nan")), len(diffs)


def residual_in_baseline(model, b, steps, max_checks):
    """The solver's orbits in the baseline's discrete shooting function H = z(T) - z0.

    Returns (max ||H||/||z0||, max ||H_x||/||x0||, max ||H_v||/(omega ||x0||), checks), with
    omega = 2 pi / T: ||H||/||z0|| (seed eq. 11) mixes m and m/s and is dominated by the
    velocities for a high-frequency mode, so the two parts are reported separately too.
    """
    M, K = dense(model.M), dense(model.K)
    B, k3 = dense_baseline.spring_arrays(springs_of(model), model.n)
    n = model.n
    N = len(b["energy"])
    idx = np.unique(np.linspace(0, N - 1, min(N, max_checks)).round().astype(int)) if N else []
    worst = [0.0, 0.0, 0.0]
    for i in idx:
        z0 = np.concatenate([b["x0"][i], b["v0"][i]])
        T = b["period"][i]
        zT = dense_baseline.newmark_shoot(M, K, B, k3, z0, T, steps, sensitivity=False)["zT"]
        H = zT - z0
        nx = np.linalg.norm(z0[:n]) + 1e-300
        parts = (np.linalg.norm(H) / np.linalg.norm(z0), np.linalg.norm(H[:n]) / nx,
                 np.linalg.norm(H[n:]) / (2 * np.pi / T * nx))
        worst = [max(w, p) for w, p in zip(worst, parts)]
    return (*worst, len(idx))


# ---------------------------------------------------------------------- memory (subprocess)
def memory_worker(args):
    """Run one method on one case under tracemalloc; print a JSON line with the peaks."""
    import tracemalloc
    model, mode = load_case(args.case, args)[:2]
    if args.worker == "solver":
        warm_up()
    tracemalloc.start()
    if args.worker == "dense":
        # the corrector of every point allocates the same arrays: a short run shows the peak
        run_baseline(args.case, model, mode, args, max_points=args.memory_points)
    else:
        run_solver(args.case, model, mode, args)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    print(json.dumps(dict(traced_mb=peak / 2 ** 20,
                          maxrss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))


def measure_memory(method, case, args):
    cmd = [sys.executable, __file__, "--worker", method, "--case", case, "--steps", str(args.steps),
           "--tol", str(args.tol), "--energy-2dof", str(args.energy_2dof), "--energy-paris",
           str(args.energy_paris), "--paris-file", args.paris_file, "--paris-mode", str(args.paris_mode),
           "--max-points", str(args.max_points), "--memory-points", str(args.memory_points),
           "--dense-step-max", str(args.dense_step_max), "--blas-threads", str(args.blas_threads), "--solver-time-limit", str(args.solver_time_limit),
           "--freq-change", str(args.freq_change)]
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=str(ROOT))
    if out.returncode != 0:
        return dict(traced_mb=float("nan"), maxrss_mb=float("nan"), error=out.stderr.strip()[-300:])
    return json.loads(out.stdout.strip().splitlines()[-1])


# ---------------------------------------------------------------------- report
def fmt(x, spec=".3g"):
    if x is None or (isinstance(x, float) and np.isnan(x)):
        width = spec.split(".")[0]
        return "-".rjust(int(width) if width.isdigit() else 1)
    return format(x, spec)


def bench_case(case, args):
    model, mode, label = load_case(case, args)
    print(f"\n=== {label}: steps/period {args.steps}, tol {args.tol:g} ===", flush=True)
    res = {}
    res["solver"] = run_solver(case, model, mode, args)
    print(f"solver done: {len(res['solver']['energy'])} points in {res['solver']['total']:.2f} s", flush=True)
    res["dense"] = run_baseline(case, model, mode, args)
    print(f"dense baseline done: {len(res['dense']['energy'])} points in {res['dense']['total']:.2f} s",
          flush=True)
    if args.save:
        np.savez(f"{args.save}_{case}.npz", **{f"{m}_{k}": res[m][k] for m in res
                                               for k in ("energy", "frequency_hz", "period", "x0", "v0",
                                                         "seconds_per_point")})
    mem = {m: (measure_memory(m, case, args) if args.memory else {}) for m in ("dense", "solver")}

    rows = []
    for m, title in (("dense", "(a) dense baseline"), ("solver", "(b) nnm_solver")):
        r = res[m]
        spp = np.median(r["seconds_per_point"]) if len(r["seconds_per_point"]) else float("nan")
        r["median"] = spp
        rows.append((title, len(r["energy"]), spp, r["total"], r["energy"][-1] if len(r["energy"]) else np.nan,
                     mem[m].get("traced_mb"), mem[m].get("maxrss_mb")))
    print(f"{'method':22s} {'points':>6s} {'s/point (median)':>17s} {'total s':>9s} {'last E (J)':>11s} "
          f"{'peak traced MB':>15s} {'maxrss MB':>10s}")
    for t, npnt, spp, tot, E, tr, rss in rows:
        print(f"{t:22s} {npnt:6d} {fmt(spp, '17.4g')} {tot:9.3f} {fmt(E, '11.4g')} "
              f"{fmt(tr, '15.3g')} {fmt(rss, '10.1f')}")
    ratio = res["solver"]["median"] / res["dense"]["median"]
    print(f"ratio (b)/(a), time per converged point: {ratio:.4g}  (speed-up {1 / ratio:.1f}x)")
    if case == "2dof":
        print(f"ratio (b)/(a), total time: {res['solver']['total'] / res['dense']['total']:.4g}")
    for m in ("dense", "solver"):
        if mem[m].get("error"):
            print(f"memory run of {m} failed: {mem[m]['error']}")
    d, nd = frequency_agreement(res["dense"], res["solver"])
    print(f"freq. diff: max |f_b/f_a - 1| = {fmt(d, '.2e')} over {nd} baseline points inside the solver's range")
    rmax, rx, rv, nr = residual_in_baseline(model, res["solver"], args.steps, 40 if case == "2dof" else 3)
    print(f"residual: {nr} solver orbits in the baseline's shooting function: max ||H||/||z0|| = {rmax:.2e}; "
          f"displacement part ||H_x||/||x0|| = {rx:.2e}, velocity part ||H_v||/(omega ||x0||) = {rv:.2e}")
    print(f"stop (a): {res['dense']['stop']};  stop (b): {res['solver']['stop']}")
    ev = res["solver"].get("events", [])
    if ev:
        print("solver events: " + "; ".join(ev[:6]) + (" ..." if len(ev) > 6 else ""))
    for m, title in (("dense", "(a)"), ("solver", "(b)")):
        E = res[m]["energy"]
        d = np.diff(E)
        idx = np.where(d[1:] * d[:-1] < 0)[0] + 1
        if len(idx):
            print(f"energy folds {title}: " + ", ".join(
                f"{'max' if d[i - 1] > 0 else 'min'} {E[i]:.4g} J @ {res[m]['frequency_hz'][i]:.5g} Hz"
                for i in idx[:8]) + (" ..." if len(idx) > 8 else ""))
        else:
            print(f"energy folds {title}: none")
    Eb, fb = res["solver"]["energy"], res["solver"]["frequency_hz"]
    if len(Eb):
        print(f"solver branch: E {Eb.min():.4g}..{Eb.max():.4g} J, f {fb.min():.6g}..{fb.max():.6g} Hz; "
              f"baseline: E {res['dense']['energy'].min():.4g}..{res['dense']['energy'].max():.4g} J")
    return res


def machine():
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", choices=["2dof", "paris", "all"], default="all")
    ap.add_argument("--steps", type=int, default=200, help="Newmark steps per period (both methods)")
    ap.add_argument("--tol", type=float, default=1e-6, help="corrector tolerance ||H||/||z0|| (both)")
    ap.add_argument("--energy-2dof", type=float, default=1e4,
                    help="energy_max of the 2-DOF case (J); the 3:1 tongue tops at ~4.7e3 J")
    ap.add_argument("--dense-step-max", type=float, default=2.0,
                    help="2-DOF case: cap on the baseline's arclength step in (z0, T); with the textbook "
                         "unbounded doubling (use 0 for none) it jumps over the 3:1 tongue")
    ap.add_argument("--energy-paris", type=float, default=1e6,
                    help="energy_max of the paris case (J); the solver also stops at --freq-change")
    ap.add_argument("--freq-change", type=float, default=0.05,
                    help="paris: the solver stops once |f/f_first - 1| reaches this")
    ap.add_argument("--solver-time-limit", type=float, default=600.0,
                    help="stop the solver's continuation after this many seconds (safety net)")
    ap.add_argument("--paris-file", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--paris-mode", type=int, default=20)
    ap.add_argument("--paris-points", type=int, default=3, help="points of the dense baseline on paris")
    ap.add_argument("--memory-points", type=int, default=2,
                    help="points of the dense baseline's memory runs (its peak is the same at every point)")
    ap.add_argument("--max-points", type=int, default=500)
    ap.add_argument("--blas-threads", type=int, default=0,
                    help="limit BLAS threads (threadpoolctl) for both methods; 0: leave as is. "
                         "1 is much faster for the baseline on a loaded machine")
    ap.add_argument("--save", default="", help="save both branches to <SAVE>_<case>.npz")
    ap.add_argument("--no-memory", dest="memory", action="store_false", help="skip the memory subprocesses")
    ap.add_argument("--worker", choices=["dense", "solver"], help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.blas_threads > 0:
        try:
            from threadpoolctl import threadpool_limits
            threadpool_limits(args.blas_threads)
        except ImportError:
            print("threadpoolctl is not installed: --blas-threads ignored (set OPENBLAS_NUM_THREADS)")
    if args.worker:
        memory_worker(args)
        return
    print(f"machine: {machine()}")
    try:
        from threadpoolctl import threadpool_info
        print("BLAS threads: " + ", ".join(f"{i['internal_api']} {i['num_threads']}" for i in threadpool_info()))
    except ImportError:
        pass
    print(f"load average: {os.getloadavg()[0]:.2f} (other jobs share the machine)")
    print(f"date: {time.strftime('%Y-%m-%d %H:%M %Z')}")
    t = time.perf_counter()
    warm_up()
    print(f"solver warm-up (compilation / cache load, not timed below): {time.perf_counter() - t:.2f} s")
    cases = ["2dof", "paris"] if args.case == "all" else [args.case]
    for case in cases:
        try:
            bench_case(case, args)
        except FileNotFoundError as exc:
            print(f"\n=== {case}: skipped ({exc}) ===")


if __name__ == "__main__":
    main()
