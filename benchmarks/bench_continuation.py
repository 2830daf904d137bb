"""Continuation robustness benchmark: what ``nnm_solver.continue_nnm`` does on a fixed set of branches.

Usage (from the repository root)::

    python benchmarks/bench_continuation.py --no-paris          # cases a-d (a few minutes)
    python benchmarks/bench_continuation.py                     # + paris mode 20 (~1 min more)
    python benchmarks/bench_continuation.py --cases 2dof,duffing-soft
    PYTHONPATH=/tmp/old python benchmarks/bench_continuation.py # the same against another checkout

It runs, in one process and one after the other, ``continue_nnm`` with its defaults except where
said, and prints one table row per run: converged points, wall time, final status, energy and
frequency range reached, points flagged unstable, events by kind; then per run the message, the
folds (energy, frequency) with the tongue (``analysis.find_tongues``) they belong to, and the
tongues found.  The load average (``os.getloadavg``) is printed at the start of every run.

Cases (``--cases``, comma-separated names or letters):

a. ``2dof`` (a): M = I, K = [[2, -1], [-1, 2]], CubicSpring(dof=0, k3=0.5), mode 1, energy_max
   3e5 J, max_points 2000, steps_per_period 200 and 1000 (two rows).  Reference (docs/tutorial.md,
   200 steps): 3:1 tongue entry fold 4708 J @ 0.22344 Hz, tip 285.6 J @ 0.22397 Hz; 5:1 tongue entry
   fold 1.09e5 J @ 0.22424 Hz, tip 2361 J @ 0.22468 Hz.
b. ``beam`` (b): tests/reference_models.cantilever_beam() (steel strip, 12 Euler-Bernoulli elements,
   tip cubic spring k3 = 1e7 N/m^3), mode 1, energy_min = the linear energy of a 0.1 mm tip amplitude
   (``--beam-tip``), energy_max = 1000 x energy_min (``--beam-factor``), max_points 3000.  The default
   first point (springs holding 1e-5 of the energy) would reach only a ~1 % frequency change in 3
   decades of energy, whatever k3 (the shift depends on E / E_first only); this start reaches ~20 %.
c. ``beam-soft`` (c): the same beam with k3 = -1e7 N/m^3, default first point E0, energy_max =
   1e6 x E0 (``--soft-factor``; ~40 x the static saddle energy, printed), max_points 2000: the branch
   should end at its escape energy.
d. ``duffing-soft`` (d): x'' + x - x^3 = 0 (escape / separatrix energy 0.25 J), energy_max 1 J,
   max_points 2000.
e. ``paris`` (e): assets/paris.h5, mode 20, energy_max 100 J, max_points 150 (~1 min; ``--no-paris``).

The script uses only names an older ``nnm_solver`` also has (Model, CubicSpring, continue_nnm with
steps_per_period / max_points / energy_min, load_model, Branch columns and events, analysis.find_tongues
when present), so one copy measures any checkout.
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import platform
import subprocess
import time
from collections import Counter
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

CASES = ("2dof", "beam", "beam-soft", "duffing-soft", "paris")
LETTERS = dict(zip("abcde", CASES))


def _reference_models():
    """tests/reference_models.py, loaded by path (no sys.path change: PYTHONPATH decides nnm_solver)."""
    spec = importlib.util.spec_from_file_location("reference_models", ROOT / "tests" / "reference_models.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _git(path, *args):
    try:
        out = subprocess.run(["git", "-C", str(path), *args], capture_output=True, text=True, timeout=10)
        return out.stdout.strip() if out.returncode == 0 else ""
    except Exception:  # noqa: BLE001 - no git: the line just says so
        return ""


def load():
    try:
        return "%.2f %.2f %.2f" % os.getloadavg()
    except OSError:
        return "n/a"


def _ev(e, key):
    return e[key] if isinstance(e, dict) else getattr(e, key)


def first_point_energy(nnm, model, mode, energy_max=1e30, **kw):
    """Energy of the default first point (one-point run)."""
    return float(nnm.continue_nnm(model, mode, energy_max=energy_max, max_points=1, **kw).energy[0])


# ---------------------------------------------------------------------- cases
def build_runs(args, nnm, rm):
    """[(case, label, model, mode, kwargs, notes)] for the selected cases."""
    runs = []
    selected = args.cases
    if "2dof" in selected:
        model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)],
                          name="2dof")
        for spp in args.spp_2dof:
            runs.append(("2dof", f"a 2dof spp={spp}", model, 1,
                         dict(energy_max=3e5, steps_per_period=spp, max_points=2000), []))
    if "beam" in selected:
        beam = rm.cantilever_beam(k3=args.beam_k3)
        f, shapes = beam.linear_modes()
        tip = rm.tip_dof()
        w = 2 * np.pi * f[0]
        a = args.beam_tip / abs(shapes[tip, 0])              # mass-normalised modal amplitude
        e_min = 0.5 * w * w * a * a
        notes = [f"beam: {beam.n} DOF, k3={args.beam_k3:g} N/m^3, f_lin = {f[0]:.4f}, {f[1]:.4f}, {f[2]:.4f} Hz; "
                 f"energy_min = {e_min:.4g} J (linear, tip {args.beam_tip:g} m), energy_max = "
                 f"{args.beam_factor:g} x energy_min = {args.beam_factor * e_min:.4g} J; default first point "
                 f"would be {first_point_energy(nnm, beam, 1):.4g} J"]
        runs.append(("beam", "b beam hardening", beam, 1,
                     dict(energy_min=e_min, energy_max=args.beam_factor * e_min, max_points=3000), notes))
    if "beam-soft" in selected:
        k3 = -abs(args.beam_k3)
        beam = rm.cantilever_beam(k3=k3)
        E0 = first_point_energy(nnm, beam, 1)
        Es, ws = rm.softening_saddle_energy(beam, rm.tip_dof(), k3)
        notes = [f"softening beam: k3={k3:g} N/m^3, first point E0 = {E0:.4g} J, energy_max = {args.soft_factor:g} x E0"
                 f" = {args.soft_factor * E0:.4g} J; static saddle (escape) energy {Es:.4g} J at tip {ws:.3g} m"]
        runs.append(("beam-soft", "c beam softening", beam, 1,
                     dict(energy_max=args.soft_factor * E0, max_points=2000), notes))
    if "duffing-soft" in selected:
        duff = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=-1.0)], name="softening Duffing")
        runs.append(("duffing-soft", "d duffing softening", duff, 1, dict(energy_max=1.0, max_points=2000),
                     ["softening Duffing x'' + x - x^3 = 0: escape (separatrix) energy 0.25 J"]))
    if "paris" in selected:
        path = Path(args.paris_file)
        if not path.exists():
            print(f"paris: {path} not found, skipped")
        else:
            model = nnm.load_model(str(path))
            runs.append(("paris", "e paris mode 20", model, 20, dict(energy_max=100.0, max_points=150),
                         [f"paris: {path} ({model.n} DOF, {len(model.springs)} springs), mode 20"]))
    return runs


# ---------------------------------------------------------------------- one run
def run_one(nnm, label, model, mode, kwargs):
    ld = load()
    t = time.perf_counter()
    error = ""
    try:
        br = nnm.continue_nnm(model, mode, **kwargs)
    except Exception as exc:  # noqa: BLE001 - an exception is a result here
        br, error = None, f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t
    return dict(label=label, branch=br, wall=wall, load=ld, error=error, kwargs=kwargs)


def summarise(nnm, r, tongues=True):
    br = r["branch"]
    if br is None:
        r.update(points=0, status="error", message=r["error"], events=Counter(), folds=[], tongues=[],
                 unstable=0, E=(np.nan, np.nan, np.nan), f=(np.nan, np.nan, np.nan))
        return r
    E, f = np.asarray(br.energy), np.asarray(br.frequency_hz)
    r["points"] = len(E)
    r["status"], r["message"] = str(br.status), str(br.message)
    r["E"] = (E[0], E[-1], E.max()) if len(E) else (np.nan,) * 3
    r["f"] = (f[0], f[-1], f.min(), f.max()) if len(f) else (np.nan,) * 4
    r["unstable"] = int(np.count_nonzero(~np.asarray(br.stable, dtype=bool)))
    r["events"] = Counter(str(_ev(e, "kind")) for e in br.events)
    r["folds"] = [(int(_ev(e, "index")), float(_ev(e, "energy")), float(_ev(e, "frequency_hz")), str(_ev(e, "detail")))
                  for e in br.events if _ev(e, "kind") == "fold"]
    r["other_events"] = [(str(_ev(e, "kind")), int(_ev(e, "index")), float(_ev(e, "energy")),
                          float(_ev(e, "frequency_hz")), str(_ev(e, "detail")))
                         for e in br.events if _ev(e, "kind") != "fold"]
    r["tongues"] = []
    r["tongue_time"] = 0.0
    if tongues and len(E) >= 3:
        t = time.perf_counter()
        try:
            r["tongues"] = list(nnm.analysis.find_tongues(br))
        except Exception as exc:  # noqa: BLE001
            r["tongue_error"] = f"{type(exc).__name__}: {exc}"
        r["tongue_time"] = time.perf_counter() - t
    return r


def tongue_of(r, index):
    for t in r["tongues"]:
        if t.start <= index <= t.end:
            return t.label
    return "-"


# ---------------------------------------------------------------------- printing
def print_table(results):
    head = (f"{'case':<22}{'points':>7}{'wall s':>9}{'ms/pt':>8}  {'load (1/5/15 min)':<17}  {'status':<12}"
            f"{'E first':>11}{'E last':>11}{'E max':>11}  {'f first':>9}{'f last':>9}  {'unstable':>8}  events")
    print(head)
    print("-" * len(head))
    for r in results:
        ev = ", ".join(f"{k} {v}" for k, v in sorted(r["events"].items())) or "none"
        ms = 1e3 * r["wall"] / r["points"] if r["points"] else float("nan")
        E, f = r["E"], r["f"]
        print(f"{r['label']:<22}{r['points']:>7}{r['wall']:>9.2f}{ms:>8.1f}  {r['load']:<17}  {r['status']:<12}"
              f"{E[0]:>11.4g}{E[1]:>11.4g}{E[2]:>11.4g}  {f[0]:>9.5g}{f[1]:>9.5g}  {r['unstable']:>8}  {ev}")


def print_details(results):
    for r in results:
        print(f"\n[{r['label']}] {r['status']}: {r['message']}")
        for note in r.get("notes", []):
            print(f"  {note}")
        if r["points"]:
            f = r["f"]
            print(f"  frequency: first {f[0]:.6g} Hz, last {f[1]:.6g} Hz ({100 * (f[1] / f[0] - 1):+.2f} %), "
                  f"range {f[2]:.6g}..{f[3]:.6g} Hz")
        if r["folds"]:
            print(f"  folds ({len(r['folds'])}): " + "; ".join(
                f"{'max' if 'max' in d else 'min'} {E:.4g} J @ {fz:.5f} Hz [{tongue_of(r, i)}] #{i}"
                for i, E, fz, d in r["folds"][:40]) + (" ..." if len(r["folds"]) > 40 else ""))
        if r.get("other_events"):
            shown = r["other_events"][:12]
            print(f"  other events ({len(r['other_events'])}): " + "; ".join(
                f"{k} #{i} {E:.4g} J @ {fz:.5f} Hz ({d})" for k, i, E, fz, d in shown)
                + (" ..." if len(r["other_events"]) > len(shown) else ""))
        if r["tongues"]:
            for t in r["tongues"]:
                print(f"  tongue: {t.summary()}")
        if r.get("tongue_error"):
            print(f"  find_tongues failed: {r['tongue_error']}")
        if r["label"].startswith("a 2dof") and r["points"]:
            for lab in ("3:1", "5:1"):
                fo = [(E, fz) for i, E, fz, d in r["folds"] if tongue_of(r, i) == lab]
                ts = [t for t in r["tongues"] if t.label == lab]
                if ts:
                    t = ts[0]
                    folds = ": " + ", ".join(f"{E:.4g} J @ {fz:.5f} Hz" for E, fz in fo) if fo else ""
                    print(f"  {lab}: tongue found ({t.kind}, {'complete' if t.complete else 'incomplete'}), "
                          f"energy {t.energy_range[0]:.4g}..{t.energy_range[1]:.4g} J, "
                          f"tip {t.tip_frequency_hz:.5f} Hz; {len(fo)} folds in it{folds}")
                else:
                    print(f"  {lab}: no tongue found")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cases", default=",".join(CASES),
                   help="comma-separated: 2dof, beam, beam-soft, duffing-soft, paris (or letters a-e)")
    p.add_argument("--no-paris", action="store_true", help="skip the paris case (~1 min)")
    p.add_argument("--spp-2dof", default="200,1000", help="steps per period of the 2-DOF runs")
    p.add_argument("--beam-k3", type=float, default=None, help="tip k3 of the beam, N/m^3 (default: reference_models')")
    p.add_argument("--beam-tip", type=float, default=1e-4, help="tip amplitude (m) of the hardening beam's first point")
    p.add_argument("--beam-factor", type=float, default=1e3, help="hardening beam: energy_max / energy_min")
    p.add_argument("--soft-factor", type=float, default=1e6, help="softening beam: energy_max / first point energy")
    p.add_argument("--paris-file", default=str(ROOT / "assets" / "paris.h5"))
    p.add_argument("--no-tongues", action="store_true", help="skip analysis.find_tongues (after the timed runs)")
    p.add_argument("--blas-threads", type=int, default=None, help="limit BLAS threads (threadpoolctl)")
    args = p.parse_args(argv)
    cases = []
    for c in args.cases.split(","):
        c = LETTERS.get(c.strip(), c.strip())
        if c not in CASES:
            p.error(f"unknown case {c!r}; choose from {', '.join(CASES)} or a-e")
        cases.append(c)
    if args.no_paris and "paris" in cases:
        cases.remove("paris")
    args.cases = cases
    args.spp_2dof = [int(s) for s in args.spp_2dof.split(",")]

    limiter = None
    if args.blas_threads:
        try:
            from threadpoolctl import threadpool_limits
            limiter = threadpool_limits(args.blas_threads, user_api="blas")
        except ImportError:
            print("threadpoolctl not installed: --blas-threads ignored")

    import nnm_solver as nnm
    rm = _reference_models()
    if args.beam_k3 is None:
        args.beam_k3 = rm.K3_STRIP
    src = Path(nnm.__file__).resolve().parent
    head = _git(src.parent, "rev-parse", "--short", "HEAD")
    dirty = _git(src.parent, "status", "--porcelain", "--", "nnm_solver")
    print(f"nnm_solver: {src} (commit {head or '?'}{', nnm_solver/ modified' if dirty else ''}); "
          f"model.elements: {'yes' if hasattr(nnm.Model(np.eye(1), np.eye(1)), 'elements') else 'no'}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
          f"date {time.strftime('%Y-%m-%d %H:%M:%S %Z')}, load average {load()}")
    print(f"cases: {', '.join(cases)}")

    t = time.perf_counter()
    nnm.continue_nnm(nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)]),
                     1, energy_max=1.0, max_points=3)
    print(f"warm-up (numba compilation / cache load, not timed below): {time.perf_counter() - t:.2f} s\n")

    runs = build_runs(args, nnm, rm)
    results = []
    for case, label, model, mode, kw, notes in runs:
        print(f"running {label}: mode {mode}, " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                                            for k, v in kw.items())
              + f"  (load {load()})", flush=True)
        r = run_one(nnm, label, model, mode, kw)
        r["notes"] = notes
        results.append(r)
        print(f"  -> {r['wall']:.2f} s", flush=True)
    for r in results:
        summarise(nnm, r, tongues=not args.no_tongues)
    print(f"\nload average at the end: {load()}\n")
    print_table(results)
    print_details(results)
    if limiter is not None:
        limiter.restore_original_limits()


if __name__ == "__main__":
    main()
