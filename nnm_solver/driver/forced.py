r"""Forced responses: the periodic response of a damped model to f(t) = force cos(omega t) over a
frequency range, continued in the arclength through the folds of the curve (docs/forced.md).

    forced_response(model, force, f_range_hz, damping, harmonics=7, condensed=None, ...)  -> ForcedResponse

The driver checks the arguments, builds the forced harmonic-balance problem (``orbits/forced_hb.py``,
uncondensed or condensed onto the nonlinear elements), converges the first orbit at the start of the range
(from the linear response; if Newton fails there, by ramping the force from a small fraction of it), and
runs the generic pseudo-arclength engine (``continuation/engine.py``) in frequency until the curve leaves
the range; the last point is corrected onto the end frequency.  Between two points where the frequency
turns back (the tangent's frequency component changes sign) the fold is located (the root of that component
along the chord).  Every Newton iteration of these is the continuation layer's (forced_points.py).  Stability: Hill's method with damping (``damped_hill_multipliers``) while the Hill matrix
is small, else the fold test (sign of det dR/dx), or as asked with ``stability=``.
"""
from __future__ import annotations

import math
import time

import numpy as np

from ..continuation.engine import ContinuationSettings, pseudo_arclength
from ..errors import NNMInputError
from ..model.damping import modal_damping
from ..model.modal import modal_system
from ..model.model import Model
from ..orbits.forced_hb import FORCED_BASES, ForcedBasis, ForcedHBProblem
from ..orbits.forced_hb_condensed import CondensedForcedHBProblem
from ..orbits.forced_hill import damped_hill_multipliers
from ..results.forced import STABILITY_METHODS, ForcedResponse
from ..stability.floquet import is_stable
from .forced_points import first_orbit, frequency_tangent, land_on_frequency, locate_fold
from .problems import check_positive
from .settings import SIZES

__all__ = ["forced_response"]



def _check_vector(name, value, n, what="entries"):
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise NNMInputError(f"{name} must be numbers, got {type(value).__name__}") from None
    if v.ndim != 1 or len(v) != n:
        raise NNMInputError(f"{name} has {v.size if v.ndim else 'a single'} {what if v.ndim else 'value'}"
                            f"{' (shape ' + str(v.shape) + ')' if v.ndim > 1 else ''}, the model has {n} DOFs: "
                            f"give one amplitude (N) per DOF")
    bad = np.flatnonzero(~np.isfinite(v))
    if len(bad):
        raise NNMInputError(f"{name}[{bad[0]}] is {v[bad[0]]}: every entry must be finite")
    return v


def _check_range(f_range_hz):
    try:
        lo_hi = [float(f) for f in f_range_hz]
    except (TypeError, ValueError):
        raise NNMInputError(f"f_range_hz must be (f_start, f_end) in Hz, got {f_range_hz!r}") from None
    if len(lo_hi) != 2:
        raise NNMInputError(f"f_range_hz must be two frequencies (f_start, f_end) in Hz, got {len(lo_hi)} values")
    f0, f1 = lo_hi
    if not (math.isfinite(f0) and math.isfinite(f1)) or f0 <= 0 or f1 <= 0:
        raise NNMInputError(f"f_range_hz = ({f0:g}, {f1:g}) Hz: both frequencies must be positive and finite")
    if f0 == f1:
        raise NNMInputError(f"f_range_hz = ({f0:g}, {f1:g}) Hz is empty: give two different frequencies")
    return f0, f1


def _stability_choice(stability, n, hill_H):
    if stability is None:
        return "hill" if 2 * n * (2 * hill_H + 1) <= SIZES.hill_auto_size else "fold"
    if stability is False:
        return "none"
    if stability not in STABILITY_METHODS:
        raise NNMInputError(f"stability must be one of {STABILITY_METHODS} (or None: automatic), got {stability!r}")
    return stability


def forced_response(model, force, f_range_hz, damping, harmonics=7, condensed=None, *, damping_matrix=None,
                    basis=None, samples=None, tol=1e-9, max_points=1000, stability=None, hill_harmonics=None,
                    step=0.05, max_rel_step=0.2, max_freq_step=None, max_angle=0.35, locate_folds=True, name="",
                    on_point=None):
    """The periodic responses of ``model`` to ``force`` cos(omega t) over ``f_range_hz``, with damping.

    Parameters
    ----------
    model : nnm_solver.Model.
    force : (n,) force amplitudes (N) per DOF; f(t) = force cos(2 pi f t).
    f_range_hz : (f_start, f_end) Hz; the continuation starts at f_start (either order: a sweep up or down)
        and follows the curve through its folds until it leaves the range.
    damping : modal damping ratio zeta (one number for every mode, or (n,) one per mode, mode k at index
        k-1): modal damping 2 zeta_k w_k in mass-normalised modal coordinates.
    harmonics : highest harmonic H of the Fourier series.
    condensed : solve the equations condensed onto the nonlinear elements' deformations (unknowns
        N_b n_s + 1 whatever n; modal damping only).  None: condensed when n_s * 4 < n and the damping is modal.
    damping_matrix : optional (n, n) viscous damping matrix C (N s/m), added to the modal damping.  One that
        is diagonal in the modal basis (e.g. Rayleigh damping) is modal damping; one that couples the modes
        needs the uncondensed equations.
    basis : "full" (mean, cos and sin of 1..H) or "odd" (cos and sin of the odd harmonics: enough for odd
        element forces under this symmetric forcing, half the unknowns).  Default: "odd" for odd elements.
    samples : AFT time samples per period (default 4 H + 4).
    tol : corrector tolerance on the relative residual.
    max_points : largest number of orbits.
    stability : "hill" (Floquet multipliers by Hill's method with damping; O((2 n (2H + 1))^3) per point),
        "fold" (the sign of det dR/dx: the saddle-node instabilities between folds, any model size) or
        "none"; None: Hill when 2 n (2 H + 1) <= 1000, else the fold test.
    hill_harmonics : harmonics of Hill's method (default: harmonics).
    step, max_rel_step, max_freq_step, max_angle : first step (balanced norm: relative change of the orbit),
        largest relative change of the orbit and of the frequency in one step (default max_freq_step:
        1 %, or 1/25 of the range if narrower), largest turn of the tangent (rad).
    locate_folds : locate the folds of the curve (frequency, orbit) between points.
    name : name of the result (the group name in the file).
    on_point : optional callable(dict(index, frequency_hz, stable)) after each orbit.

    Returns a ForcedResponse: frequency_hz, amplitude(dof), phase(dof), stable, folds, status, message.
    Bad arguments raise NNMInputError (one line) before any computation.
    """
    t_start = time.perf_counter()
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    n = model.n
    force = _check_vector("force", force, n)
    if not np.any(force != 0):
        raise NNMInputError("force is zero everywhere: the response would be zero; give the force amplitudes (N)")
    f0, f1 = _check_range(f_range_hz)
    check_positive("harmonics", harmonics, integer=True)
    check_positive("tol", tol)
    check_positive("max_points", max_points, integer=True)
    for key, value in (("step", step), ("max_rel_step", max_rel_step), ("max_angle", max_angle)):
        check_positive(key, value)
    if max_freq_step is not None:
        check_positive("max_freq_step", max_freq_step)
    H = int(harmonics)
    if hill_harmonics is not None:
        check_positive("hill_harmonics", hill_harmonics, integer=True)
    hill_H = int(hill_harmonics or H)
    zeta, c_modal, Cq = modal_damping(model, damping, damping_matrix)
    system = modal_system(model)
    el = system.elements
    odd = el.odd
    if basis is None:
        basis = "odd" if odd else "full"
    if basis not in FORCED_BASES:
        raise NNMInputError(f"basis must be one of {FORCED_BASES}, got {basis!r}")
    if basis == "odd" and not odd:
        raise NNMInputError("basis='odd' needs odd element forces (odd powers, symmetric kinks); use basis='full'")
    if samples is not None:
        check_positive("samples", samples, integer=True)
        if samples < 2 * H + 2:
            raise NNMInputError(f"samples={samples} is too few for {H} harmonics; use at least {2 * H + 2} "
                                f"(more than {4 * H} avoids aliasing of a cubic)")
    lam = system.omega2
    rigid = lam <= 10 * n * np.finfo(float).eps * max(lam[-1], 1e-300)
    if basis == "full" and np.any(rigid):
        raise NNMInputError(f"mode {int(np.flatnonzero(rigid)[0]) + 1} is a rigid-body mode: with basis='full' its "
                            f"mean displacement is undetermined; use basis='odd' (odd elements) or ground the "
                            f"structure")
    ns = len(el)
    if condensed is None:
        condensed = bool(ns > 0 and ns * SIZES.condense_ratio < n and c_modal is not None)
    elif not isinstance(condensed, (bool, np.bool_)):
        raise NNMInputError(f"condensed must be True, False or None (automatic), got {condensed!r}")
    condensed = bool(condensed)
    if condensed and ns == 0:
        raise NNMInputError("condensed=True needs nonlinear elements (the model has none): use condensed=False")
    if condensed and c_modal is None:
        raise NNMInputError("condensed=True needs modal damping, but damping_matrix couples the modes: "
                            "use condensed=False (or a damping matrix diagonal in the modal basis)")
    fb = ForcedBasis(H, basis, samples)
    if not condensed and len(fb) * n > SIZES.max_uncondensed:
        raise NNMInputError(f"the uncondensed equations would have {len(fb) * n} unknowns (dense Jacobian); use "
                            f"condensed=True (with modal damping) or fewer harmonics")
    method = _stability_choice(stability, n, hill_H)
    if not callable(on_point) and on_point is not None:
        raise NNMInputError("on_point must be a callable or None")

    # ------------------------------------------------------------ the problem and its first orbit
    direction = 1.0 if f1 > f0 else -1.0
    w0, w1 = 2 * np.pi * f0, 2 * np.pi * f1
    rel_range = abs(f1 - f0) / min(f0, f1)
    max_freq_step = float(max_freq_step if max_freq_step is not None else min(0.01, rel_range / 25))
    w_ref = 2 * np.pi * math.sqrt(f0 * f1)
    fq = system.Phi.T @ force
    steps = dict(max_rel_step=float(max_rel_step), max_rel_freq_step=max_freq_step)
    if condensed:
        problem = CondensedForcedHBProblem(system, fb, fq, c_modal, w_ref, **steps)
    else:
        problem = ForcedHBProblem(system, fb, fq, Cq if c_modal is None else c_modal, w_ref, **steps)
    settings = dict(tol=float(tol), max_points=int(max_points), hill_harmonics=hill_H, step=float(step),
                    max_rel_step=float(max_rel_step), max_freq_step=max_freq_step, max_angle=float(max_angle),
                    f_range_hz=[f0, f1])
    u0, message = first_orbit(problem, w0, tol)
    result_args = dict(harmonics=H, basis=basis, samples=samples, damping=zeta,
                       damping_matrix=None if damping_matrix is None else _dense(damping_matrix), name=str(name),
                       condensed=condensed, stability=method, settings=settings)
    if u0 is None:
        return ForcedResponse(model, force, [], np.zeros((0, len(fb), n)), status="failed", message=message,
                              **result_args)
    p0 = direction * frequency_tangent(problem.jacobian(u0)[1])

    # ------------------------------------------------------------ the continuation
    cs = ContinuationSettings(step=float(step), step_min=1e-9, step_max=np.inf, max_angle=float(max_angle),
                              max_correction=0.5)
    engine = pseudo_arclength(problem, u0, p0, cs, tol)
    rows, folds = [], []
    status, message = None, ""
    prev = None                                         # (u, tangent) of the last kept point

    def keep(u, J, tangent):
        A, w = problem.modal_coefficients(u)
        fs = problem.fold_sign(J)
        if method == "hill":
            mu = damped_hill_multipliers(system, fb, A, w, Cq, hill_H)
            st = is_stable(mu)
        else:
            mu = np.full(2 * n, np.nan, dtype=complex)
            st = fs > 0 if method == "fold" else True
        rows.append((w / (2 * np.pi), A @ system.Phi.T, mu, st, fs))
        if on_point is not None:
            on_point(dict(index=len(rows) - 1, frequency_hz=w / (2 * np.pi), stable=bool(st)))

    def fold_between(ua, pa, ub, pb):
        if pa[-1] * pb[-1] < 0:
            uf = locate_fold(problem, ua, ub, tol, cs) if locate_folds else None
            if uf is None:
                uf = ua if abs(pa[-1]) < abs(pb[-1]) else ub
                located = False
            else:
                located = True
            A, w = problem.modal_coefficients(uf)
            folds.append(dict(index=len(rows), frequency_hz=w / (2 * np.pi), coefficients=A @ system.Phi.T,
                              located=located))

    while True:
        try:
            cp = next(engine)
        except StopIteration as stop:
            status, message = "failed", f"the continuation stopped at {_last_f(rows)}: {stop.value}"
            break
        w = problem.frequency(cp.u)
        if prev is not None and (w - w1) * direction >= 0:          # past the end: land on it
            end = land_on_frequency(problem, prev[0], cp.u, w1, tol, cp.tangent)
            if end is not None:
                ue, Je, pe = end
                fold_between(prev[0], prev[1], ue, pe)
                keep(ue, Je, pe)
                status, message = "done", f"reached f_end = {f1:.6g} Hz"
            else:
                fold_between(prev[0], prev[1], cp.u, cp.tangent)
                keep(cp.u, cp.jacobian, cp.tangent)
                status, message = "done", (f"passed f_end = {f1:.6g} Hz (last point at {w / (2 * np.pi):.6g} Hz: "
                                           f"the correction onto f_end did not converge)")
            break
        if prev is not None and (w - w0) * direction < 0:
            status, message = "left_range", (f"the curve turned back and left the range at f_start = {f0:.6g} Hz "
                                             f"after {len(rows)} points")
            break
        if prev is not None:
            fold_between(prev[0], prev[1], cp.u, cp.tangent)
        keep(cp.u, cp.jacobian, cp.tangent)
        prev = (cp.u, cp.tangent)
        if len(rows) >= max_points:
            status, message = "max_points", (f"max_points = {max_points} reached at {_last_f(rows)} before "
                                             f"f_end = {f1:.6g} Hz")
            break
    engine.close()
    elapsed = time.perf_counter() - t_start
    message = f"{message} ({len(rows)} points, {len(folds)} fold{'s' if len(folds) != 1 else ''}, {elapsed:.3g} s)"
    settings["seconds"] = elapsed
    N = len(rows)
    return ForcedResponse(model, force, [r[0] for r in rows],
                          np.array([r[1] for r in rows]).reshape(N, len(fb), n),
                          floquet=np.array([r[2] for r in rows]).reshape(N, 2 * n),
                          stable=[r[3] for r in rows], fold_sign=[r[4] for r in rows], folds=folds,
                          status=status, message=message, **result_args)


def _dense(C):
    """A damping matrix as a dense array (for the result)."""
    return C.toarray() if hasattr(C, "toarray") else np.asarray(C, dtype=float)


def _last_f(rows):
    return f"{rows[-1][0]:.6g} Hz" if rows else "the first point"
