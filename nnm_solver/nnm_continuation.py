"""continue_nnm: an NNM branch from a linear mode at low energy up to a target energy.

Shooting (shooting.py) + pseudo-arclength continuation (continuation.py) + Floquet analysis
(floquet.py), collected into a Branch (branch.py).
"""
from __future__ import annotations

import contextlib
import math

import numpy as np
from threadpoolctl import threadpool_limits

from .branch import Branch
from .continuation import ContinuationSettings, pseudo_arclength
from .errors import NNMInputError
from .floquet import STABILITY_TOL, detect_events, is_stable, sort_multipliers
from .model import Model
from .shooting import ShootingProblem, discrete_linear_period, modal_system

#: fraction of the linear potential energy carried by the springs at the first point
START_NONLINEARITY = 1e-5

#: BLAS threads used while a branch is computed.  The dense problems here (n ~ 10..2000) gain
#: little from threads on an idle machine, and multi-threaded OpenBLAS slows down 5-20x when the
#: cores are shared (measured: a 548 x 548 eigenvalue problem took 7.6 s with 2 threads and 0.36 s
#: with 1 on a busy 2-core machine).  None leaves the process setting alone.
BLAS_THREADS = 1


def _check_positive(name, value, integer=False):
    ok = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
    if not ok or isinstance(value, bool) or not np.isfinite(value) or value <= 0:
        raise NNMInputError(f"{name} must be a positive {'integer' if integer else 'number'}, got {value!r}")


def check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min):
    """Validate the arguments every branch computation shares; returns the 0-based mode index."""
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    _check_positive("energy_max", energy_max)
    _check_positive("tol", tol)
    _check_positive("max_points", max_points, integer=True)
    if energy_min is not None:
        _check_positive("energy_min", energy_min)
        if energy_min >= energy_max:
            raise NNMInputError(f"energy_min ({energy_min:g} J) must be below energy_max ({energy_max:g} J)")
    return model.check_mode(mode)


def start_amplitude(system, k, energy_max, energy_min=None):
    """Modal amplitude (sqrt(kg) m) of the first point: nearly linear, below energy_max."""
    w2 = system.omega2[k]
    if energy_min is not None:
        return math.sqrt(2.0 * energy_min / w2)
    b = system.Bq[:, k]
    c = float(np.sum(np.abs(system.k3) * b ** 4))
    a_lin = math.sqrt(2.0 * energy_max * 1e-6 / w2)
    if c <= 0:
        return a_lin
    # k3 b^4 a^4 / 4 = START_NONLINEARITY * w^2 a^2 / 2
    a_nl = math.sqrt(2.0 * START_NONLINEARITY * w2 / c)
    return min(a_nl, math.sqrt(2.0 * energy_max * 1e-2 / w2))


def continue_nnm(model, mode, energy_max, steps_per_period=200, tol=1e-6, max_points=500, on_point=None,
                 stop=None, energy_min=None, symmetric=True, floquet=True, step=None, max_angle=0.35,
                 max_correction=0.5, max_rel_step=0.4, reversible=None, max_period_step=0.005):
    """Compute the NNM branch of linear mode ``mode`` (1-based) from low energy up to ``energy_max`` (J).

    Parameters
    ----------
    steps_per_period : Newmark steps per period (the error in frequency is O(steps^-2)).
    tol : relative periodicity tolerance ||H|| / ||z0|| (seed eq. 11).
    max_points : largest number of points kept.
    on_point : optional callable(branch_snapshot_row: dict) called after each converged point.
    stop : optional threading.Event-like object; when set, the continuation stops (status 'cancelled').
    energy_min : energy (J) of the first point (default: where the springs hold 1e-5 of the energy).
    symmetric : use half-period shooting (valid for the odd cubic nonlinearity; see shooting.py).
    reversible : orbits starting at rest (v0 = 0, default with symmetric) or general orbits with a
        phase condition (False); see shooting.ShootingProblem.
    floquet : compute Floquet multipliers and stability at every point.
    step : first step length in units of the scaled unknowns (default: half the starting amplitude).
    max_angle : largest turn (rad) of the branch tangent between two points.
    max_correction : largest corrector displacement, relative to the step length.
    max_rel_step : largest step relative to the amplitude of the current orbit.
    max_period_step : largest relative change of the period between two points (keeps the
        continuation from stepping over the entrance of internal-resonance tongues).

    Returns a Branch; its ``status`` and ``message`` say why the continuation stopped, and every
    point computed before a failure is kept.
    """
    k = check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min)
    _check_positive("steps_per_period", steps_per_period, integer=True)
    if steps_per_period < 8:
        raise NNMInputError(f"steps_per_period={steps_per_period} is too small; use at least 8 (200 is typical)")
    system = modal_system(model)
    problem = ShootingProblem(system, k, steps_per_period, symmetric=symmetric, max_rel_step=max_rel_step,
                              reversible=reversible, max_rel_period_step=max_period_step)
    a0 = start_amplitude(system, k, energy_max, energy_min)
    w = math.sqrt(system.omega2[k])
    q0 = np.zeros(model.n)
    q0[k] = a0
    T0 = discrete_linear_period(w, problem.spp)
    u0 = problem.pack(q0, np.zeros(model.n), T0)
    p0 = problem.pack(q0 / a0, np.zeros(model.n), 0.0)
    s0 = 0.5 * a0 if step is None else float(step)
    settings = ContinuationSettings(step=s0, step_min=1e-8 * a0, step_max=np.inf, max_angle=max_angle,
                                    max_correction=max_correction)

    def record(pt):
        qz, vz, T = problem.unpack(pt.u)
        x0, v0 = system.to_physical(qz), system.to_physical(vz)
        if floquet:
            mu = problem.floquet_multipliers()
            stable = is_stable(mu, STABILITY_TOL)
        else:
            mu, stable = np.full(2 * model.n, np.nan, dtype=complex), True
        return dict(energy=float(model.energy(x0, v0)), frequency_hz=1.0 / T, period=T, x0=x0, v0=v0,
                    floquet=mu, stable=stable)

    branch, _ = collect_branch(model, mode, pseudo_arclength(problem, u0, p0, settings, tol), record,
                               energy_max, max_points, on_point, stop,
                               dict(method="shooting", steps_per_period=problem.spp, tol=tol, symmetric=symmetric,
                                    reversible=problem.reversible,
                                    energy_max=energy_max, k3_factor=1.0, floquet=bool(floquet)))
    return branch


BRANCH_COLUMNS = ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable")


def collect_branch(model, mode, points, record, energy_max, max_points, on_point, stop, settings):
    """Run a continuation generator and collect its points into a Branch (shared by all methods).

    points : generator of ContinuationPoint (continuation.pseudo_arclength).
    record(point) -> dict with at least BRANCH_COLUMNS (plus any extra per-point columns).
    Stops at energy_max, max_points, when ``stop`` is set, when the branch returns to low energy,
    or when the generator gives up (status 'failed'; the points so far are kept).
    Returns (branch, rows): rows maps every recorded key to its list of values.
    """
    rows = {}
    status, message = "failed", ""
    E_start = None
    limits = threadpool_limits(BLAS_THREADS, user_api="blas") if BLAS_THREADS else contextlib.nullcontext()
    with limits:
        try:
            while True:
                N = len(rows.get("energy", ()))
                if stop is not None and stop.is_set():
                    status, message = "cancelled", f"cancelled after {N} points"
                    break
                try:
                    pt = next(points)
                except StopIteration as fin:
                    status = "failed"
                    where = (f"after point {N} (E = {rows['energy'][-1]:.4g} J, "
                             f"f = {rows['frequency_hz'][-1]:.5g} Hz)" if N else "at the start")
                    message = (f"no convergence {where}: {fin.value or 'continuation stopped'}; the points so far are "
                               f"kept (try a larger steps_per_period or tol, or the branch ends here)")
                    break
                row = record(pt)
                row["floquet"] = sort_multipliers(row["floquet"])
                row["iterations"] = pt.iterations
                for key, val in row.items():
                    rows.setdefault(key, []).append(val)
                if on_point is not None:
                    on_point(row)
                E = row["energy"]
                E_start = E if E_start is None else E_start
                if E >= energy_max:
                    status, message = "done", f"reached energy_max = {energy_max:g} J"
                    break
                if N + 1 >= max_points:
                    status, message = "max_points", f"stopped at max_points = {max_points} (energy {E:.4g} J)"
                    break
                if N + 1 > 3 and E < 0.5 * E_start:
                    status, message = "done", "the branch returned to low energy"
                    break
        finally:
            points.close()
    n = model.n
    N = len(rows.get("energy", ()))
    E = np.array(rows.get("energy", []), dtype=float)
    f = np.array(rows.get("frequency_hz", []), dtype=float)
    fl = np.array(rows.get("floquet", []), dtype=complex).reshape(N, 2 * n)
    st = np.array(rows.get("stable", []), dtype=bool)
    branch = Branch(model, mode, E, f, np.array(rows.get("period", []), dtype=float),
                    np.array(rows.get("x0", []), dtype=float).reshape(N, n),
                    np.array(rows.get("v0", []), dtype=float).reshape(N, n), fl, st,
                    detect_events(E, f, fl, st), status, message, settings)
    return branch, rows
