"""Cost per converged point against the model size n (issue 17): where the time of a point goes.

A family of Craig-Bampton models of one structure (``build_family``): an aluminium plate on four
mounts, 4 grounded softening cubic springs on the vertical displacement of the mounts (the joints), the
4 mount nodes retained (24 boundary DOFs) and 276, 526, 1076, 2176, 4376 fixed-interface modes, i.e.
n = 300, 550, 1100, 2200, 4400.  The FE model (nnm_fem MITC4 shells, 7,830 DOFs) is the same for every
size; so is the NNM branch (mode ``--mode``): only the number of fixed-interface modes grows.  Models are
cached as .h5 files in benchmarks/_cache/ (git-ignored; ~4 MB for the whole family).

For every n, in a fresh subprocess (so that the memory and the BLAS state are its own):
``continue_nnm(model, mode, energy_max, steps_per_period=200, max_points=...)``, with timers wrapped
around the solver's public / semi-public entry points (nothing in nnm_solver is edited; a name the
solver no longer has is simply not timed, its time then shows under "other"):

  sweep      Integrator.sensitivity / .sensitivity_factors (the exact sensitivity sweep) + ShootingProblem.jacobian's own work
             (assembling J from the sweep)
  state      Integrator.state / .record: state-only sweeps (chord-Newton residuals, the orbit record)
  linalg     continuation.LeastSquares (QR factorisations and solves: corrector, tangent)
  stability  ShootingProblem.multipliers / .floquet_multipliers / .multipliers_later and NNMIterator._settle
             (Floquet multipliers; where their eigenproblems run in worker threads beside the next steps, the
             main thread's part and its wait for them)
  events     everything inside events.locate_between (event location, all its sweeps/QRs/eigenproblems)
  error      everything inside ShootingProblem.frequency_error (the per-point error estimate)
  other      the rest of the point's wall time (Python, harmonic labels, energies, ...)

The columns are exclusive and add up to the wall time of the point.  "sweep", "state", "linalg" and
"stability" count only what is spent outside event location and the error estimate; the totals over all
phases are printed too.  Runs per size: a backbone (max_points 40, events included, stopped after the point
that exceeds a wall-clock budget), short repeats (``--points``, default 6), and one untimed run with
tracemalloc on.  Profile: points 2..--points of every timed run (the same points of the branch at every
size; point 1 includes the start-up correction), mean per point, median over the runs (3 for n <= 2200).
Memory per point: the tracemalloc peak of point 2 (numpy arrays included), and in the timed runs the
growth of VmHWM (reset through /proc/self/clear_refs before each point) above the RSS at the reset (a lower
bound).  The load average (os.getloadavg) is printed with every size and run.

    python benchmarks/bench_scaling.py                 # all sizes, ~15 min (model build: +2 min once)
    python benchmarks/bench_scaling.py --quick         # n <= 2200 (~10 min)
    python benchmarks/bench_scaling.py --replot benchmarks/_cache/scaling_results.json   # report + plot again
    python benchmarks/bench_scaling.py --sizes 300,550 --repeats 3 --points 8
    python benchmarks/bench_scaling.py --build-only    # only build / check the cached models
    python benchmarks/bench_scaling.py --help

Writes benchmarks/img/scaling.png (log-log time per point vs n, fitted exponents) and
benchmarks/_cache/scaling_results.json (every number).
"""
from __future__ import annotations

import os

# one BLAS thread (as the solver itself uses while it computes points: nnm_solver.threads), also for the build
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
CACHE = HERE / "_cache"
IMG = HERE / "img"

# ----------------------------------------------------------------------------------------------- the family
#: the structure (changing any of these changes the cache key)
PLATE = dict(
    Lx=1.2, Ly=0.8, t=4e-3,                 # m: aluminium plate
    E=70e9, nu=0.33, rho=2700.0,
    nx=44, ny=28,                           # MITC4 elements: 45 x 29 nodes, 7,830 DOFs
    mount_frac=0.125,                       # mounts at 1/8 of each side from the edges
    k_mount=(2e5, 2e5, 2e5, 50.0, 50.0, 50.0),   # linear mount bushings to ground (N/m, N m/rad)
    k3=-2e10,                               # N/m^3: softening cubic spring on each mount's uz, to ground
)
BUILDER_VERSION = 1
SIZES = (300, 550, 1100, 2200, 4400)
N_BOUNDARY = 24                             # 4 mount nodes x 6 DOFs, retained first
#: the continued NNM and its energy range (a few % softening of the frequency within it)
MODE = 4
ENERGY_MAX = 5.0


def _key():
    s = json.dumps(dict(PLATE, version=BUILDER_VERSION), sort_keys=True)
    return hashlib.sha1(s.encode()).hexdigest()[:10]


def model_path(n):
    return CACHE / f"plate_{_key()}_n{n}.h5"


def plate_fe():
    """The FE plate (nnm_fem): (FEModel, K, M, mount node ids)."""
    from nnm_fem import FEModel
    p = PLATE
    fe = FEModel()
    x = np.linspace(0.0, p["Lx"], p["nx"] + 1)
    y = np.linspace(0.0, p["Ly"], p["ny"] + 1)
    X, Y = np.meshgrid(x, y, indexing="ij")
    ids = fe.add_nodes(np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])).reshape(len(x), len(y))
    quads = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    fe.add_shells("plate", quads, p["E"], p["nu"], p["t"], rho=p["rho"])
    i = round(p["mount_frac"] * p["nx"])
    j = round(p["mount_frac"] * p["ny"])
    mounts = [int(ids[a, b]) for a in (i, p["nx"] - i) for b in (j, p["ny"] - j)]
    for m in mounts:
        fe.add_bushing("mounts", m, None, list(p["k_mount"]))
    K, M = fe.assemble()
    return fe, K, M, mounts


def build_family(sizes, log=print):
    """Build (or find in the cache) the reduced model of every size; returns {n: path}.

    Craig-Bampton with the 4 mount nodes retained: the constraint modes from
    nnm_solver.model.reduction.craig_bampton (n_modes=0, sparse), the fixed-interface modes of the one FE model
    from a single dense generalized eigenproblem (7,806 internal DOFs, ~1-2 min) shared by every size:
    Lanczos (craig_bampton's eigsh) for 4,376 of 7,806 modes would take far longer.  Checked against
    craig_bampton itself at the smallest size (its reduced frequencies are printed side by side).
    """
    import scipy.linalg as sla
    import nnm_solver
    from nnm_solver.model.reduction import craig_bampton
    CACHE.mkdir(exist_ok=True)
    paths = {n: model_path(n) for n in sizes}
    missing = [n for n in sizes if not paths[n].exists()]
    if not missing:
        return paths
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    fe, K, M, mounts = plate_fe()
    b = np.array([6 * m + c for m in mounts for c in range(6)])
    log(f"FE plate: {fe.n_nodes} nodes, {fe.n_dof} DOFs, {len(mounts)} mounts; building n = {missing}")
    _, _, R0, _ = craig_bampton(M, K, b, 0, xyz=fe.nodes)          # constraint modes (static), sparse
    internal = np.setdiff1d(np.arange(fe.n_dof), b)
    Kii = K[internal][:, internal].toarray()
    Mii = M[internal][:, internal].toarray()
    kmax = max(missing) - N_BOUNDARY
    t = time.perf_counter()
    lam, Phi = sla.eigh(Kii, Mii, driver="gvd", check_finite=False)     # all: faster than a subset here
    del Kii, Mii
    lam, Phi = lam[:kmax], Phi[:, :kmax]
    log(f"fixed-interface modes: {kmax} of {len(internal)} by a dense eigenproblem in {time.perf_counter() - t:.1f} s "
        f"({np.sqrt(lam[0]) / 2 / np.pi:.1f} .. {np.sqrt(lam[-1]) / 2 / np.pi:.0f} Hz)")
    check = None
    for n in sorted(missing):
        k = n - N_BOUNDARY
        R = np.zeros((fe.n_dof, n))
        R[:, :N_BOUNDARY] = R0
        R[internal, N_BOUNDARY:] = Phi[:, :k]
        Mr = R.T @ (M @ R)
        Kr = R.T @ (K @ R)
        Mr[N_BOUNDARY:, N_BOUNDARY:] = np.eye(k)                   # exact modal blocks, as craig_bampton
        Kr[N_BOUNDARY:, N_BOUNDARY:] = np.diag(lam[:k])
        Kr[:N_BOUNDARY, N_BOUNDARY:] = 0.0
        Kr[N_BOUNDARY:, :N_BOUNDARY] = 0.0
        Mr, Kr = 0.5 * (Mr + Mr.T), 0.5 * (Kr + Kr.T)
        if check is None and k <= 600:                               # the project's reduction, same size
            Mc, Kc, _, _ = craig_bampton(M, K, b, k, xyz=fe.nodes)
            f_own = np.sqrt(np.abs(sla.eigvalsh(Kr, Mr)))[:20] / 2 / np.pi
            f_cb = np.sqrt(np.abs(sla.eigvalsh(Kc, Mc)))[:20] / 2 / np.pi
            check = float(np.max(np.abs(f_own / f_cb - 1)))
            log(f"check at n = {n}: first 20 frequencies vs nnm_solver.model.reduction.craig_bampton: max rel. diff "
                f"{check:.1e}")
        springs = [nnm_solver.CubicSpring(dof=6 * a + 2, k3=PLATE["k3"]) for a in range(len(mounts))]
        labels = [f"mount {a + 1} {c}" for a in range(len(mounts)) for c in ("ux", "uy", "uz", "rx", "ry", "rz")]
        labels += [f"CB mode {j + 1} ({np.sqrt(lam[j]) / 2 / np.pi:.1f} Hz)" for j in range(k)]
        model = nnm_solver.Model(Mr, Kr, springs, dof_labels=labels, name=f"plate on 4 mounts, CB n={n}",
                                 info=dict(builder="benchmarks/bench_scaling.py", builder_version=BUILDER_VERSION,
                                           key=_key(), full_dof=int(fe.n_dof), fixed_interface_modes=int(k)))
        nnm_solver.save_model(paths[n], model, extra={"plate": {k_: np.asarray(v, float) for k_, v in PLATE.items()}})
        log(f"  n = {n}: {paths[n].name} ({paths[n].stat().st_size / 1e6:.0f} MB)")
    log(f"family built in {time.perf_counter() - t0:.1f} s (load average {load0:.2f} -> {os.getloadavg()[0]:.2f})")
    return paths


# ----------------------------------------------------------------------------------------------- timers
CATEGORIES = ("sweep", "state", "linalg", "stability", "events", "error", "other")
KERNELS = ("sweep", "state", "linalg", "stability")


class Profile:
    """Exclusive wall time per (phase, category) of wrapped calls, with a stack for nesting.

    A wrapped call's own time (minus the wrapped calls inside it) goes to its category, in the phase of
    the outermost phase wrapper active (events / error), else the phase 'step'."""

    def __init__(self):
        self.acc = {}
        self.stack = []                      # [category, phase-or-None, t0, child]
        self.calls = {}
        self.installed = []

    def wrap(self, owner, name, category, phase=None):
        fn = getattr(owner, name, None)
        if fn is None or getattr(fn, "_bench_wrapped", False):
            return False
        prof = self

        def wrapper(*a, **k):
            prof.stack.append([category, phase, time.perf_counter(), 0.0])
            try:
                return fn(*a, **k)
            finally:
                cat, ph, t0, child = prof.stack.pop()
                el = time.perf_counter() - t0
                outer = next((f[1] for f in prof.stack if f[1]), None) or ph or "step"
                key = (outer, cat)
                prof.acc[key] = prof.acc.get(key, 0.0) + el - child
                prof.calls[(cat, name)] = prof.calls.get((cat, name), 0) + 1
                if prof.stack:
                    prof.stack[-1][3] += el

        wrapper._bench_wrapped = True
        wrapper.__wrapped__ = fn
        wrapper.__name__ = getattr(fn, "__name__", name)
        setattr(owner, name, wrapper)
        self.installed.append(f"{getattr(owner, '__name__', type(owner).__name__)}.{name} -> {category}"
                              + (f" (phase {phase})" if phase else ""))
        return True

    def snapshot(self):
        return dict(self.acc)


def install_timers(prof):
    """Wrap the solver's entry points (public or semi-public names only; none is edited)."""
    import nnm_solver.continuation.engine as cont
    import nnm_solver.stability.events as events
    import nnm_solver.integrators.registry as integ
    import nnm_solver.driver.iterator as iterator
    from nnm_solver.orbits import shooting
    SP = shooting.ShootingProblem
    seen = set()
    for name in getattr(integ, "INTEGRATORS", ("newmark",)):
        cls = type(integ.get_integrator(name))
        if cls in seen:
            continue
        seen.add(cls)
        prof.wrap(cls, "sensitivity", "sweep")
        if hasattr(cls, "sensitivity_factors"):
            prof.wrap(cls, "sensitivity_factors", "sweep")
        prof.wrap(cls, "state", "state")
        prof.wrap(cls, "record", "state")
    prof.wrap(SP, "jacobian", "sweep")
    prof.wrap(SP, "residual", "state")
    prof.wrap(cont.LeastSquares, "__init__", "linalg")
    prof.wrap(cont.LeastSquares, "solve", "linalg")
    prof.wrap(SP, "multipliers", "stability")
    prof.wrap(SP, "floquet_multipliers", "stability")
    # the multipliers computed in worker threads beside the next steps: the main thread's part (maps, deflation)
    # and its wait for them
    prof.wrap(SP, "multipliers_later", "stability")
    prof.wrap(iterator.NNMIterator, "_settle", "stability")
    prof.wrap(SP, "frequency_error", "error", phase="error")
    # the iterator calls the name it imported: wrap it there (and in events for any other caller)
    for mod in (iterator, events):
        prof.wrap(mod, "locate_between", "events", phase="events")


# ----------------------------------------------------------------------------------------------- memory
def _status(field):
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024.0      # MB
    except OSError:
        pass
    return float("nan")


def reset_peak():
    """Reset VmHWM to the current RSS (Linux >= 4.0); returns the RSS (MB) at the reset."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass
    return _status("VmRSS")


# ----------------------------------------------------------------------------------------------- one size
def run_size(n, plan, mode=MODE, energy_max=ENERGY_MAX, spp=200):
    """In this process: load model n, then the runs of ``plan`` ([max_points, budget s] each; the first is the
    backbone, the others short repeats); a dict of results."""
    import resource
    import nnm_solver
    from nnm_solver.model.modal import modal_system
    out = dict(n=n, load_start=os.getloadavg(), plan=plan)
    t = time.perf_counter()
    warm = nnm_solver.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm_solver.CubicSpring(dof=0, k3=0.5)])
    nnm_solver.continue_nnm(warm, mode=1, energy_max=1.0, max_points=3)        # numba kernels (cache load)
    out["warmup_s"] = time.perf_counter() - t
    t = time.perf_counter()
    model = nnm_solver.load_model(str(model_path(n)))
    out["load_s"] = time.perf_counter() - t
    t = time.perf_counter()
    modal_system(model)                   # dense n x n eigenproblem, once per model (not per point)
    out["modal_setup_s"] = time.perf_counter() - t
    out["rss_after_setup_mb"] = _status("VmRSS")
    prof = Profile()
    install_timers(prof)
    out["timers"] = prof.installed
    runs = []
    for entry in plan:
        points, budget = entry[:2]
        traced = len(entry) > 2 and bool(entry[2])
        if traced:
            tracemalloc.start()
        stop = threading.Event()
        marks = []                        # per point: time, timer snapshot, peak RSS above the RSS at the reset, ...
        state = dict(base=reset_peak())
        t_begin = time.perf_counter()

        def on_point(p):
            now = time.perf_counter()
            peak = _status("VmHWM") - state["base"]
            if traced:
                peak = tracemalloc.get_traced_memory()[1] / 2 ** 20
                tracemalloc.reset_peak()
            marks.append((now, prof.snapshot(), peak, p.energy, p.frequency_hz, bool(p.stable)))
            if now - t_begin > budget:
                stop.set()
            state["base"] = reset_peak()

        load = os.getloadavg()
        prof.acc.clear()
        t0 = time.perf_counter()
        br = nnm_solver.continue_nnm(model, mode=mode, energy_max=energy_max, steps_per_period=spp,
                                     max_points=points, on_point=on_point, stop=stop)
        wall = time.perf_counter() - t0
        if traced:
            tracemalloc.stop()
        per_point = []
        prev_t, prev_s = t0, {}
        for now, snap, peak, E, f, stable in marks:
            d = {f"{ph}:{cat}": v - prev_s.get((ph, cat), 0.0) for (ph, cat), v in snap.items()}
            per_point.append(dict(wall=now - prev_t, parts=d, peak_mb=peak, energy=E, f=f, stable=stable))
            prev_t, prev_s = now, snap
        events = [(e["kind"], float(e["energy"]), float(e["frequency_hz"])) for e in (br.events or [])]
        runs.append(dict(max_points=points, budget=budget, traced=traced, wall=wall, points=len(br.energy),
                         status=br.status,
                         message=br.message, load_start=load, load_end=os.getloadavg(), per_point=per_point,
                         events=events, f_first=float(br.frequency_hz[0]), f_last=float(br.frequency_hz[-1]),
                         E_first=float(br.energy[0]), E_last=float(br.energy[-1]),
                         unstable=int(np.sum(~np.asarray(br.stable, bool)))))
    out["runs"] = runs
    out["calls"] = {f"{c}:{nm}": v for (c, nm), v in prof.calls.items()}
    out["maxrss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    out["load_end"] = os.getloadavg()
    return out


def columns(point):
    """The exclusive columns (CATEGORIES) of one point from its parts {phase:category: s}."""
    c = dict.fromkeys(CATEGORIES, 0.0)
    for key, v in point["parts"].items():
        ph, cat = key.split(":")
        if ph == "step":
            c[cat if cat in KERNELS else "other"] += v
        else:
            c[ph] += v
    c["other"] += point["wall"] - sum(point["parts"].values())
    return c


def kernel_totals(point):
    """Kernel time over all phases (sweep, linalg, stability, state incl. inside events / error)."""
    c = dict.fromkeys(KERNELS, 0.0)
    for key, v in point["parts"].items():
        cat = key.split(":")[1]
        if cat in c:
            c[cat] += v
    return c


# ----------------------------------------------------------------------------------------------- summary
def _mean_cols(pts):
    cols = [columns(p) for p in pts]
    kern = [kernel_totals(p) for p in pts]
    return dict(total=float(np.mean([p["wall"] for p in pts])),
                cols={c: float(np.mean([x[c] for x in cols])) for c in CATEGORIES},
                kern={c: float(np.mean([x[c] for x in kern])) for c in KERNELS},
                peak_mb=float(np.median([p["peak_mb"] for p in pts])),
                peak_max_mb=float(np.max([p["peak_mb"] for p in pts])))


def summarise(res, profile_points):
    """Profile: per run, the mean per point over points 2..profile_points (the same first points of the
    branch at every size; point 1 includes the start-up correction), median over the runs.  Backbone: the
    first run's mean per point over all its points after the first (events included)."""
    timed = [r for r in res["runs"] if not r.get("traced")]
    prof = [_mean_cols(r["per_point"][1:profile_points]) for r in timed if len(r["per_point"]) > 1]
    traced = [p["peak_mb"] for r in res["runs"] if r.get("traced") for p in r["per_point"][1:]]
    med = lambda f: float(np.median([f(x) for x in prof]))  # noqa: E731
    bb = res["runs"][0]
    s = dict(n=res["n"], runs=len(prof), total=med(lambda x: x["total"]),
             cols={c: med(lambda x, c=c: x["cols"][c]) for c in CATEGORIES},
             kern={c: med(lambda x, c=c: x["kern"][c]) for c in KERNELS},
             peak_mb=med(lambda x: x["peak_mb"]), peak_max_mb=max(x["peak_max_mb"] for x in prof),
             first=float(np.median([r["per_point"][0]["wall"] for r in timed if r["per_point"]])),
             traced_mb=float(np.max(traced)) if traced else float("nan"),
             load=[timed[0]["load_start"][0], timed[-1]["load_end"][0]])
    bcols = _mean_cols(bb["per_point"][1:]) if len(bb["per_point"]) > 1 else None
    walls = [p["wall"] for p in bb["per_point"]]
    s["backbone"] = dict(points=bb["points"], max_points=bb["max_points"], wall=bb["wall"], status=bb["status"],
                         message=bb["message"], events=[e[0] for e in bb["events"]],
                         f_change=bb["f_last"] / bb["f_first"] - 1, E_last=bb["E_last"],
                         per_point=None if bcols is None else bcols["total"],
                         cols=None if bcols is None else bcols["cols"],
                         peak_max_mb=None if bcols is None else bcols["peak_max_mb"],
                         projected=(walls[0] + float(np.median(walls[1:])) * (bb["max_points"] - 1)
                                    if bb["points"] < bb["max_points"] and bb["status"] == "cancelled"
                                    and len(walls) > 1 else None),
                         load=[bb["load_start"][0], bb["load_end"][0]])
    return s


def fit_exponent(ns, ts, n_min=0):
    """Least-squares slope of log t against log n over the sizes n >= n_min with t > 0 (nan if < 2)."""
    ns, ts = np.asarray(ns, float), np.asarray(ts, float)
    ok = (ns >= n_min) & (ts > 0) & np.isfinite(ts)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(ns[ok]), np.log(ts[ok]), 1)[0])


def print_report(summ, args, log=print):
    ns = [s["n"] for s in summ]
    log(f"\nprofile: cost per converged point (s), points 2-{args.points} of the branch (the same points at every "
        f"size), mean per point, median over runs; the columns add up to s/point")
    heads = ["n", "runs", "load", "s/point", *CATEGORIES, "RSS growth MB/point", "traced peak MB", "dominant"]
    log(" | ".join(heads))
    for s in summ:
        dom = max(CATEGORIES, key=lambda c: s["cols"][c])
        log(" | ".join([f"{s['n']}", f"{s['runs']}", f"{s['load'][0]:.1f}-{s['load'][1]:.1f}", f"{s['total']:.3g}"]
                       + [f"{s['cols'][c]:.3g}" for c in CATEGORIES]
                       + [f"{s['peak_mb']:.1f} (max {s['peak_max_mb']:.1f})", f"{s.get('traced_mb', np.nan):.1f}",
                          f"{dom} {100 * s['cols'][dom] / s['total']:.0f} %"]))
    lo = args.fit_from
    ex = {c: fit_exponent(ns, [s["cols"][c] for s in summ], lo) for c in CATEGORIES}
    ex["total"] = fit_exponent(ns, [s["total"] for s in summ], lo)
    ex["peak_mb"] = fit_exponent(ns, [s["peak_mb"] for s in summ], lo)
    ex["traced_mb"] = fit_exponent(ns, [s.get("traced_mb", np.nan) for s in summ], lo)
    exk = {c: fit_exponent(ns, [s["kern"][c] for s in summ], lo) for c in KERNELS}
    log(f"fitted exponents (t ~ n^p, least squares over n >= {lo}): "
        + ", ".join(f"{c} {ex[c]:.2f}" for c in ("total",) + CATEGORIES + ("peak_mb", "traced_mb")))
    for a, b in zip(summ, summ[1:]):
        r = np.log(b["n"] / a["n"])
        loc = {c: np.log(b["cols"][c] / a["cols"][c]) / r if a["cols"][c] > 0 and b["cols"][c] > 0 else np.nan
               for c in ("sweep", "linalg", "stability")}
        log(f"  local exponent {a['n']} -> {b['n']}: total {np.log(b['total'] / a['total']) / r:.2f}, "
            + ", ".join(f"{c} {v:.2f}" for c, v in loc.items()))
    log("kernels over all phases (also inside event location and the error estimate), s/point: ")
    for s in summ:
        log(f"  n = {s['n']}: " + ", ".join(f"{c} {s['kern'][c]:.3g}" for c in KERNELS))
    log("  exponents: " + ", ".join(f"{c} {exk[c]:.2f}" for c in KERNELS))
    log(f"\nbackbone: mode {args.mode} to {args.energy_max:g} J, max_points {args.backbone_points}, one run per size "
        f"(stopped after the point that exceeds its budget); s/point = mean over the points after the first")
    log(" | ".join(["n", "points", "wall s", "s/point", "events s/pt", "f change", "E last", "status", "events",
                    "load", "projected 40-point s"]))
    for s in summ:
        b = s["backbone"]
        log(" | ".join([f"{s['n']}", f"{b['points']}", f"{b['wall']:.1f}",
                        f"{b['per_point']:.3g}" if b["per_point"] else "-",
                        f"{b['cols']['events']:.3g}" if b["cols"] else "-", f"{100 * b['f_change']:+.2f} %",
                        f"{b['E_last']:.3g}", b["status"], ",".join(b["events"]) or "-",
                        f"{b['load'][0]:.1f}-{b['load'][1]:.1f}",
                        f"{b['projected']:.0f}" if b["projected"] else "-"]))
    log("  (projected 40-point s: a stopped backbone's first point + 39 x its median point: events not met yet are "
        "not in it)")
    full = [s for s in summ if s["backbone"]["status"] != "cancelled" and s["n"] >= lo]
    if len(full) >= 2:
        p = fit_exponent([s["n"] for s in full], [s["backbone"]["wall"] for s in full])
        ex["backbone_wall"] = p
        last = full[-1]
        for n in sorted({s["n"] for s in summ if s["n"] > last["n"]} | {4400}):
            log(f"  complete backbones (n = {', '.join(str(s['n']) for s in full)}): wall ~ n^{p:.2f}; extrapolated "
                f"to n = {n}: {last['backbone']['wall'] * (n / last['n']) ** p:.0f} s "
                f"({last['backbone']['points']} points, events included)")
    return ex, exk


def plot(summ, ex, exk, path, args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ns = np.array([s["n"] for s in summ], float)
    fig, ax = plt.subplots(figsize=(8, 5.6))
    styles = dict(total=("k", "o", "-"), sweep=("C0", "s", "-"), linalg=("C1", "^", "-"),
                  stability=("C2", "v", "-"), error=("C4", "x", "--"), state=("C5", ".", ":"), other=("C7", "+", ":"))
    for c, (col, mk, ls) in styles.items():
        t = np.array([s["total"] if c == "total" else s["cols"][c] for s in summ])
        if not (t > 0).any() or (c != "total" and np.max(t / [s["total"] for s in summ]) < 0.005):
            continue
        ok = t > 0
        ax.loglog(ns[ok], t[ok], color=col, marker=mk, ls=ls, lw=2.2 if c == "total" else 1.2,
                  label=f"{'whole point' if c == 'total' else c}: n^{ex[c]:.2f}")
    bb = np.array([s["backbone"]["per_point"] or np.nan for s in summ], float)
    full = np.array([s["backbone"]["status"] != "cancelled" for s in summ])
    if np.any(np.isfinite(bb)):
        bexp = f" (whole runs ~ n^{ex['backbone_wall']:.2f})" if "backbone_wall" in ex else ""
        ax.loglog(ns[full], bb[full], color="k", marker="o", mfc="w", ls="--", lw=1.4,
                  label=f"backbone mean incl. events (complete runs){bexp}")
        if np.any(~full & np.isfinite(bb)):
            ax.loglog(ns[~full], bb[~full], color="k", marker="o", mfc="w", ls="none",
                      label="backbone mean, run stopped by its budget")
    ref = summ[0]["total"] * (ns / ns[0]) ** 2.2
    ax.loglog(ns, ref, color="0.6", lw=0.8, ls="-.", label="n^2.2 (issue 17 target), from the smallest n")
    ax.set_xticks(ns)
    ax.set_xticklabels([f"{int(n)}" for n in ns])
    ax.minorticks_off()
    ax.set_xlabel("model size n (DOFs of the Craig-Bampton model)")
    ax.set_ylabel("wall time per converged point (s)")
    load = ", ".join(f"{s['load'][0]:.1f}" for s in summ)
    ax.set_title(f"continue_nnm, plate on 4 cubic mounts, mode {args.mode}, 200 steps/period; components: points 2-"
                 f"{args.points}\n(exponents fitted on n >= {args.fit_from}; 2 shared cores, load avg {load})",
                 fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper left")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------------------------- main
def _plan(n, args):
    """[[max_points, budget s], ...] for size n: the backbone, then the short repeats."""
    if n >= 4400:
        return [[args.backbone_points, args.budget_4400]] + ([[2, args.budget_4400, True]] if args.memory_4400 else [])
    budget = args.budget if n <= 1100 else args.budget_2200
    repeats = args.repeats if n <= 2200 else 1
    return ([[args.backbone_points, budget]] + [[args.points, budget]] * (repeats - 1)
            + ([[2, budget, True]] if args.memory else []))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)), help="comma-separated sizes of the family")
    ap.add_argument("--quick", action="store_true", help="skip n = 4400 (~10 min instead of ~15)")
    ap.add_argument("--points", type=int, default=6,
                    help="profile: points 2..POINTS of every run, the same at every size (default 6)")
    ap.add_argument("--repeats", type=int, default=3, help="runs per size for n <= 2200 (median; default 3)")
    ap.add_argument("--backbone-points", type=int, default=40, help="max_points of the backbone run (default 40)")
    ap.add_argument("--budget", type=float, default=300.0,
                    help="wall-clock budget (s) of one run for n <= 1100 (stopped after the point exceeding it)")
    ap.add_argument("--budget-2200", type=float, default=60.0, help="the same for n = 2200 (default 60)")
    ap.add_argument("--budget-4400", type=float, default=360.0,
                    help="the same for the n = 4400 backbone (default 360: 6 points today); a stopped backbone's "
                         "40-point time is "
                         "projected from its median point")
    ap.add_argument("--no-memory", dest="memory", action="store_false",
                    help="skip the traced run (tracemalloc, 2 points, not timed) that gives the peak memory of a point")
    ap.add_argument("--memory-4400", action="store_true", help="also for n = 4400 (2 more points, ~2-3 min)")
    ap.add_argument("--fit-from", type=int, default=550, help="fit the exponents on sizes n >= this (default 550)")
    ap.add_argument("--mode", type=int, default=MODE, help=f"NNM (default {MODE})")
    ap.add_argument("--energy-max", type=float, default=ENERGY_MAX, help=f"J (default {ENERGY_MAX:g})")
    ap.add_argument("--build-only", action="store_true", help="build / check the cached models and stop")
    ap.add_argument("--plot", default=str(IMG / "scaling.png"))
    ap.add_argument("--json", default=str(CACHE / "scaling_results.json"))
    ap.add_argument("--replot", default=None, metavar="JSON",
                    help="only print the report and redraw the plot from a results file of an earlier run")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--worker-plan", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker is not None:            # one size, in its own process
        res = run_size(args.worker, json.loads(args.worker_plan), args.mode, args.energy_max)
        print("RESULT " + json.dumps(res))
        return 0

    if args.replot:
        saved = json.loads(Path(args.replot).read_text())
        for key in ("mode", "energy_max"):
            setattr(args, key, saved[key])
        summ = [summarise(r, args.points) for r in saved["results"]]
        ex, exk = print_report(summ, args)
        plot(summ, ex, exk, Path(args.plot), args)
        print(f"plot: {args.plot}")
        return 0
    sizes = [int(s) for s in args.sizes.split(",") if s]
    if args.quick:
        sizes = [n for n in sizes if n < 4400]
    t_all = time.perf_counter()
    print(f"bench_scaling: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, numpy {np.__version__}; load average {os.getloadavg()}; "
          f"{time.strftime('%Y-%m-%d %H:%M:%S %Z')}")
    print(f"plate family {_key()}, mode {args.mode}, energy_max {args.energy_max:g} J, 200 steps/period, BLAS 1 thread")
    build_family(sizes)
    if args.build_only:
        return 0
    results, summ = [], []
    for n in sizes:
        plan = _plan(n, args)
        print(f"\nn = {n}: runs [max_points, budget s] {plan}; load average {os.getloadavg()[0]:.2f}", flush=True)
        proc = subprocess.run([sys.executable, __file__, "--worker", str(n), "--worker-plan", json.dumps(plan),
                               "--mode", str(args.mode), "--energy-max", repr(args.energy_max)],
                              capture_output=True, text=True)
        line = next((ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")), None)
        if proc.returncode or line is None:
            print(f"  worker failed (rc {proc.returncode}):\n{proc.stderr[-3000:]}")
            continue
        res = json.loads(line[7:])
        results.append(res)
        s = summarise(res, args.points)
        summ.append(s)
        for r in res["runs"]:
            print(f"  run: {r['points']} points in {r['wall']:.1f} s ({r['status']}), E {r['E_first']:.3g} -> "
                  f"{r['E_last']:.3g} J, f {r['f_first']:.4f} -> {r['f_last']:.4f} Hz "
                  f"({100 * (r['f_last'] / r['f_first'] - 1):+.2f} %), unstable points {r['unstable']}, events "
                  f"{[e[0] for e in r['events']] or '-'}, load {r['load_start'][0]:.2f} -> {r['load_end'][0]:.2f}")
        print(f"  set-up once per model (not per point): load {res['load_s']:.1f} s, modal eigenproblem "
              f"{res['modal_setup_s']:.1f} s, RSS after set-up {res['rss_after_setup_mb']:.0f} MB; process maxrss "
              f"{res['maxrss_mb']:.0f} MB; first point {s['first']:.2f} s; profile {s['total']:.3g} s/point, peak RSS "
              f"growth {s['peak_mb']:.1f} MB/point, traced peak of a point {s['traced_mb']:.1f} MB", flush=True)
    if not summ:
        return 1
    ex, exk = print_report(summ, args)
    plot(summ, ex, exk, Path(args.plot), args)
    print(f"\nplot: {args.plot}")
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(dict(results=results, summary=summ, exponents=ex, kernel_exponents=exk,
                                               plate=PLATE, mode=args.mode, energy_max=args.energy_max,
                                               argv=sys.argv[1:]), default=float, indent=1))
    print(f"results: {args.json}; benchmark wall time {time.perf_counter() - t_all:.0f} s (load average now "
          f"{os.getloadavg()[0]:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
