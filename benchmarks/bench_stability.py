"""Stability and event location: the local route against the dense one and the code before (issue 52), side by side.

Routes, each run in its own process (BLAS 1 thread, the solver's worker threads on), in turn, ``--repeats`` times:

* ``before``: the solver tree given by ``--before`` (e.g. the commit this work started from, unpacked with
  ``git archive <commit> | tar -x -C /tmp/base``), as it is;
* ``local``: this tree: Krein collisions followed by shift-invert Arnoldi, a flag changed nearer the stable end found
  at the margin points (krein._earlier_change), the multipliers' eigenproblem of the coupled modes only
  (floquet.coupled_modes);
* ``dense``: this tree with every Krein collision located by bisection on the full (dense) stability flag and the
  eigenproblem of all modes: the reference (``stability.settings.STABILITY.krein_route = "dense"``).

Cases: ``m20`` the aircraft's NNM 20 with the defaults until its first energy fold (as bench_targets.py's ``paris``);
``m20skip`` its NNM 20 to 200 J skipping tongues (9 tori: issue 52's profile of event location);
``m13`` its NNM 13 to 26 J (the torus near 22.5 J); ``2dof`` the 2-DOF benchmark's NNM 1 to 100 J (the pitchfork at
40.97 J); ``3dof`` a 3-DOF chain's combination resonance (two Krein collisions; tests/test_bifurcation.py), gauss6.
Printed per case and route: the median time, the load average before and after each run, the dense eigenproblems
(floquet.eigenvalues calls; on the main thread: during event location), the orbits located inside steps and the
Krein follower's local evaluations among them, the event location's CPU time and the integrator's sweeps during it
(gauss6's sensitivity and state sweeps), the events, and each event's relative
energy difference from the dense route's; the CPU time of the process (all its threads) beside the wall time (the
steadier number on a shared machine).  ``--signatures CASE`` instead runs CASE once in this process and prints, at each top-level Krein location, the Krein
signatures (stability/krein_signature.py) of every coupled coordinate c at the step's stable end and at the located
collision's stable side (the interval the probes check): how many real coordinates carry each sign, and whether the
two sign sequences (sorted by c) are the same -- the test that would replace the probes, had no opposite-signature
pair passed between the two points -- with the cost of the signatures of a local window of 6.  Usage::

    git archive b28e431 | (mkdir -p /tmp/base && tar -x -C /tmp/base)
    python benchmarks/bench_stability.py --before /tmp/base --cases m20 --repeats 3
    python benchmarks/bench_stability.py --signatures m20
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _model(case):
    import nnm_solver as nnm
    if case in ("m20", "m20skip", "m13"):
        return nnm.load_model(str(ROOT / "assets" / "paris.h5"))
    if case == "2dof":
        return nnm.load_model(str(ROOT / "assets" / "two_dof.h5"))
    from scipy.stats import ortho_group
    Phi = ortho_group.rvs(3, random_state=0)
    K = Phi @ np.diag([1.0, 1.8 ** 2, 2.4 ** 2]) @ Phi.T
    return nnm.Model(M=np.eye(3), K=K, springs=[nnm.CubicSpring(dof=0, k3=1.0)])


def worker(case, route):
    """One run in this process (PYTHONPATH: the tree to run): prints one JSON line."""
    import threading
    import scipy.linalg  # noqa: F401  (scipy's own BLAS is loaded before the limit: threadpoolctl limits loaded ones)
    from threadpoolctl import threadpool_limits
    import nnm_solver as nnm
    threadpool_limits(1)
    import nnm_solver.stability.floquet as fl
    counts = {"all": 0, "main": 0}
    eig = fl.eigenvalues

    def counted(C):
        counts["all"] += 1
        counts["main"] += threading.current_thread() is threading.main_thread()
        return eig(C)

    fl.eigenvalues = counted
    import nnm_solver.stability.locator as lc
    counts.update(local=0, orbits=0)
    local_collision, at = lc.Locator.local_collision, lc.Locator.at

    def counted_local(self, sigma, shift):
        counts["local"] += 1
        return local_collision(self, sigma, shift)

    def counted_at(self, sigma, *args, **kw):
        counts["orbits"] += float(sigma) not in self.cache
        return at(self, sigma, *args, **kw)

    lc.Locator.local_collision, lc.Locator.at = counted_local, counted_at
    # the event location's own cost: CPU time inside locate_between (all threads of the process, so a spectrum the
    # continuation computes in the background meanwhile counts too) and the integrator's sweeps there
    import nnm_solver.driver.iterator as iterator
    import nnm_solver.integrators.registry as registry
    counts.update(location_cpu=0.0, sweeps=0, states=0)
    locating = [False]
    between = iterator.locate_between

    def timed_between(*a, **k):
        c, locating[0] = time.process_time(), True
        try:
            return between(*a, **k)
        finally:
            locating[0] = False
            counts["location_cpu"] += time.process_time() - c

    iterator.locate_between = timed_between
    gauss = getattr(registry, "_Gauss", None)
    for name, key in (("sensitivity", "sweeps"), ("state", "states")):
        if gauss is not None and hasattr(gauss, name):
            def sweep(self, *a, _f=getattr(gauss, name), _k=key, **k):
                counts[_k] += locating[0]
                return _f(self, *a, **k)
            setattr(gauss, name, sweep)
    import nnm_solver.orbits.shooting_stability as ss
    if hasattr(ss, "eigenvalues"):
        ss.eigenvalues = counted
    if route == "dense":
        import dataclasses
        import nnm_solver.stability.settings as st
        if hasattr(st.STABILITY, "krein_route"):         # the reference route, a setting since issue 52
            st.STABILITY = dataclasses.replace(st.STABILITY, krein_route="dense")
        else:
            import nnm_solver.stability.events as ev
            ev.locate_collision = lambda loc, lo, hi, rho_stars, ends=None: loc.bisect(loc.stable, lo, hi)
            if hasattr(ss.ShootingStability, "coupled_modes"):
                ss.ShootingStability.coupled_modes = property(lambda self: None)
    for integrator in ("newmark", "gauss6"):          # warm-up: numba kernels compiled (or loaded) outside the time
        nnm.continue_nnm(nnm.load_model(str(ROOT / "assets" / "two_dof.h5")), mode=1, energy_max=1.0,
                         integrator=integrator)
    model = _model(case)
    counts.update(all=0, main=0, local=0, orbits=0, location_cpu=0.0, sweeps=0, states=0)
    t0, c0 = time.perf_counter(), time.process_time()
    if case == "m20":
        stop, E = threading.Event(), []

        def on_point(p):
            E.append(p["energy"])
            if len(E) > 2 and E[-1] < E[-2]:
                stop.set()
        b = nnm.continue_nnm(model, mode=20, energy_max=1e6, on_point=on_point, stop=stop)
    elif case == "m20skip":
        b = nnm.continue_nnm(model, mode=20, energy_max=200.0, tongues="skip")
    elif case == "m13":
        b = nnm.continue_nnm(model, mode=13, energy_max=26.0)
    elif case == "2dof":
        b = nnm.continue_nnm(model, mode=1, energy_max=100.0)
    else:
        b = nnm.continue_nnm(model, 1, 3.0, integrator="gauss6", steps_per_period=100)
    t, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(json.dumps(dict(seconds=t, cpu=cpu, points=len(b.energy), eig_all=counts["all"], eig_main=counts["main"],
                          local=counts["local"], located=counts["orbits"], location_cpu=counts["location_cpu"],
                          sweeps=counts["sweeps"], states=counts["states"],
                          stable=np.asarray(b.stable).astype(int).tolist(),
                          events=[(e["kind"], float(e["energy"]), e.get("stability_change")) for e in b.events],
                          solver=nnm.__file__)))


def signature_orders(case):
    """--signatures: the full signature sequences at both ends of each top-level Krein location's probed interval."""
    import scipy.linalg as sla
    import nnm_solver as nnm
    import nnm_solver.stability.events as ev
    import nnm_solver.stability.krein as kr
    from nnm_solver.stability.krein_signature import signatures
    from nnm_solver.threads import blas_limited

    def sequence(loc, x):
        u, J, _ = loc.at(x)
        loc.refresh(u, J)
        p = loc.problem
        idx = p.coupled_modes
        idx = np.arange(p.n) if idx is None else idx
        A11 = p.stability_maps()[0][:, :p.n]
        c, Y = sla.eig(A11[np.ix_(idx, idx)])
        X = np.zeros((p.n, len(c)), dtype=complex)
        X[idx] = Y
        kappa = signatures(c, p.krein_form(X))
        t = time.process_time()
        cw, Xw = p.local_eigenpairs(float(c.real[0]), 6)
        signatures(cw, p.krein_form(Xw))
        window = time.process_time() - t
        real = (np.abs(c.imag) <= 1e-12) & (np.abs(c + 1) > 1e-6)
        order = np.argsort(c.real[real])
        return c.real[real][order], kappa[real][order], c[c.imag > 1e-12], window

    def without(c, kappa, pairs):
        """The sequence without the two real coordinates nearest each complex pair's real part (the colliding pair)."""
        keep = np.ones(len(c), dtype=bool)
        for z in pairs:
            keep[np.argsort(np.abs(c - z.real))[:2]] = False
        return kappa[keep]

    locate = kr.locate_collision

    def hooked(loc, lo, hi, rho_stars, ends=None, depth=0):
        r = locate(loc, lo, hi, rho_stars, ends, depth)
        if depth == 0:
            start = lo if loc.stable(lo) else hi
            x_s = min(r) if start == lo else max(r)
            (ca, ka, za, wa), (cb, kb, zb, wb) = sequence(loc, start), sequence(loc, x_s)
            ka, kb = without(ca, ka, zb), without(cb, kb, za)     # (the followed pair: complex at one end)
            differ = int(np.sum(ka != kb)) if len(ka) == len(kb) else None
            print(f"  {loc.energy(start):.6g} -> {loc.energy(x_s):.6g} J: {len(ka)} / {len(kb)} real coordinates "
                  f"besides the complex pairs' (+ {np.sum(ka > 0)} / {np.sum(kb > 0)}, undetermined {np.sum(ka == 0)} "
                  f"/ {np.sum(kb == 0)}); complex pairs {len(za)} / {len(zb)}; sign sequences "
                  f"{'the same' if differ == 0 else f'differ at {differ} places'}; a window's signatures "
                  f"{1e3 * wa:.0f} / {1e3 * wb:.0f} ms CPU", flush=True)
        return r

    kr.locate_collision = ev.locate_collision = hooked
    model = _model(case)
    with blas_limited():
        if case == "m20":
            it, E = nnm.iter_nnm(model, 20, 1e6), []
            for point in it:
                E.append(point.energy)
                if len(E) > 2 and E[-1] < E[-2]:
                    break
        elif case == "m20skip":
            nnm.continue_nnm(model, mode=20, energy_max=200.0, tongues="skip")
        else:
            nnm.continue_nnm(model, 1, 3.0, integrator="gauss6", steps_per_period=100)


def run(case, route, tree):
    env = dict(os.environ, PYTHONPATH=str(tree))
    l0 = os.getloadavg()[0]
    out = subprocess.run([sys.executable, __file__, "--worker", case, route], env=env, capture_output=True, text=True,
                         cwd=str(tree))
    if out.returncode:
        raise SystemExit(f"{case}/{route} failed:\n{out.stderr[-2000:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["load"] = (l0, os.getloadavg()[0])
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", nargs=2, metavar=("CASE", "ROUTE"))
    ap.add_argument("--before", default=None, help="a source tree of the solver before (omit: no 'before' route)")
    ap.add_argument("--cases", default="m20,2dof,3dof", help="comma-separated: m20, m20skip, m13, 2dof, 3dof")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--signatures", metavar="CASE", help="m20, m20skip or 3dof: the Krein signature sequences")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(*args.worker)
    if args.signatures:
        return signature_orders(args.signatures)
    routes = [("dense", ROOT), ("local", ROOT)] + ([("before", Path(args.before))] if args.before else [])
    print(f"bench_stability: {os.cpu_count()} cores, BLAS 1 thread, numpy {np.__version__}; "
          f"{time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())}; before: {args.before}")
    for case in args.cases.split(","):
        results = {name: [] for name, _ in routes}
        for _ in range(args.repeats):
            for name, tree in routes:
                results[name].append(run(case, name, tree))
        ref = results["dense"][-1]
        print(f"\n{case}:")
        for name, _ in routes:
            rs = results[name]
            last = rs[-1]
            flags = "equal" if last["stable"] == ref["stable"] else (
                f"{sum(a != b for a, b in zip(last['stable'], ref['stable']))} differ"
                if len(last["stable"]) == len(ref["stable"]) else f"{len(last['stable'])} vs {len(ref['stable'])} points")
            times = ", ".join("%.2f" % r["seconds"] for r in rs)
            loads = ", ".join("%.1f->%.1f" % tuple(r["load"]) for r in rs)
            cpus = ", ".join("%.2f" % r.get("cpu", np.nan) for r in rs)
            print(f"  {name:7s} median {np.median([r['seconds'] for r in rs]):7.2f} s wall ({times}; load {loads}), "
                  f"CPU {np.median([r.get('cpu', np.nan) for r in rs]):.2f} s ({cpus})  "
                  f"{last['points']} points, flags {flags}; dense eigenproblems {last['eig_all']} "
                  f"({last['eig_main']} on the main thread); located orbits {last.get('located', '-')} "
                  f"(Krein follower's local evaluations {last.get('local', '-')})")
            if "location_cpu" in last:
                print(f"          event location: CPU {np.median([r['location_cpu'] for r in rs]):.2f} s "
                      f"({', '.join('%.2f' % r['location_cpu'] for r in rs)}), sensitivity sweeps {last['sweeps']}, "
                      f"state sweeps {last['states']}")
            for kind, energy, change in last["events"]:
                same = [e for k, e, c in ref["events"] if k == kind and c == change]
                near = min(same, key=lambda e: abs(e - energy)) if same else None
                diff = f"{energy / near - 1:+.1e} from dense" if near else "(not in the dense route)"
                print(f"      {kind:14s} {energy:.8g} J {change or '':5s} {diff}")


if __name__ == "__main__":
    main()
