"""The engine's corrector: Newton-Moore-Penrose on [F(u); (w^2 p)^T (u - u_pred)] = 0 (seed eq. 9-10) with chord
iterations (the Jacobian re-used while the iterates contract fast), the one Newton loop of the continuation layer; the
engine (engine.py), the event locator and the tongue jumps call it.  A problem whose residual is a compiled kernel
(``problem.residual_kernel``, engine.py's protocol) has the chord iterations run in one compiled call (chord.py: the
same iterates); the codes it returns are chord.py's, CHORD_* here.
"""
from __future__ import annotations

import math

import numpy as np

from . import chord as _chord
from .linalg import LeastSquares, all_finite, stacked

__all__ = ["CorrectorFailure", "correct", "correct_factored", "jacobian_at", "CHORD_JUDGE", "CHORD_SINGULAR",
           "CHORD_REFRESH"]


def _norm(x):
    """|x| of a 1-D float array: sqrt(x . x), np.linalg.norm's numbers bit for bit without its dispatch (~3 us; the
    engine takes several per corrector iteration)."""
    return math.sqrt(float(x.dot(x)))


class CorrectorFailure(Exception):
    pass


#: the codes of the compiled chord iterations (chord.py): stopped at an iterate whose residual the corrector judges; a
#: non-finite step; poor contraction (u is the next iterate: a fresh Jacobian there)
CHORD_JUDGE, CHORD_SINGULAR, CHORD_REFRESH = _chord.JUDGE, _chord.SINGULAR, _chord.REFRESH


def correct(problem, u_pred, p, settings, tol, w=None):
    """Newton-Moore-Penrose corrector (eq. 9-10) from the prediction u_pred, orthogonal to p in the
    norm |w * u|.

    Returns (u, J, iterations, error).  J is the Jacobian at the converged point.
    """
    return correct_factored(problem, u_pred, p, settings, tol, w)[:4]


def correct_factored(problem, u_pred, p, settings, tol, w=None, start=None, refresh=True):
    """``correct``, also returning the factorisation of [J; (w^2 p)^T] at the converged point (5th item):
    the tangent there and other solves with J reuse it (one QR per Jacobian evaluation).

    start : optional (u0, factor): a first iterate u0 on the same hyperplane (w^2 p)^T (u - u_pred) = 0 and
    the factorisation of [J_near; (w^2 p)^T] at a converged point next to it (e.g. the previous point of
    an event locator, whose hyperplanes are parallel): the chord iterations start there instead of at
    u_pred with a Jacobian there.  A fresh Jacobian is taken when they contract poorly, and always at the
    converged point unless refresh=False (then J and the factorisation are None when the iterations converged on
    an older Jacobian: for callers that need only the point)."""
    row = p if w is None else w * w * p
    u = u_pred.copy() if start is None else start[0].copy()
    factor = None if start is None else start[1]
    last_norm = None
    kernel = getattr(problem, "residual_kernel", None) if _chord.AVAILABLE else None
    it = 0
    while True:
        fresh = False
        if factor is None:
            r, J = problem.jacobian(u)
            fresh = True
            factor = LeastSquares(stacked(J, row))
        # the compiled chord iterations where the problem's residual is a kernel (the same iterates), else one here
        done = (_chord.iterate(kernel, u, u_pred, row, factor, last_norm, it, tol, settings, r if fresh else None)
                if kernel is not None else None)
        if done is None:
            if not fresh:
                r = problem.residual(u)
        else:
            first = it
            u, r, it, last_norm, code = done
            fresh = fresh and it == first       # (J is the iterate's own only where no step was taken)
            if code == CHORD_REFRESH:           # poor contraction: the Jacobian at the new iterate
                factor = None
                continue
            if code == CHORD_SINGULAR:
                raise CorrectorFailure("singular corrector system")
        if not all_finite(r):
            raise CorrectorFailure("the time integration diverged (non-finite state)")
        err = problem.error(u, r)
        if err < tol:
            if not fresh and not refresh:
                return u, None, it, err, None
            if not fresh:  # the monodromy/Jacobian must belong to the converged point
                J, err, factor = jacobian_at(problem, u, row, tol)
            return u, J, it, err, factor
        if it == settings.max_iter:
            break
        rhs = np.empty(len(r) + 1)
        np.negative(r, out=rhs[:-1])
        rhs[-1] = -(row @ (u - u_pred))
        du = factor.solve(rhs)
        nrm = _norm(du)
        if not math.isfinite(nrm):
            raise CorrectorFailure("singular corrector system")
        if last_norm is not None and nrm > settings.refresh_ratio * last_norm and not fresh:
            factor = None  # poor contraction: refresh the Jacobian at the next iterate
        last_norm = nrm
        u = u + du
        it += 1
    raise CorrectorFailure(f"no convergence in {settings.max_iter} corrector iterations (error {err:.2e})")


def jacobian_at(problem, u, row, tol):
    """(J, error, factorisation of [J; row^T]) at a point u the chord iterations converged to on an older Jacobian:
    the Jacobian (and the problem's monodromy) must belong to the converged point.  CorrectorFailure if u's residual,
    evaluated again with it, is no longer within tol."""
    r, J = problem.jacobian(u)
    err = problem.error(u, r)
    if not err < tol:
        raise CorrectorFailure("the residual changed when the Jacobian was refreshed")
    return J, err, LeastSquares(stacked(J, row))
