r"""The corrector's chord iterations of the condensed harmonic-balance equations in one compiled call.

The pseudo-arclength corrector (continuation/engine.py ``correct_factored``) iterates, on a factorisation
[J; row^T] = Q R kept from an earlier iterate, u <- u + du with

    [J; row^T] du = [-F(u); -row . (u - u_pred)]        (least squares, F the residual, row = w^2 p)

until the relative residual ||F(u)|| / ||u[:-1]|| (CondensedHBProblem.error) falls below tol.  In Python each
iteration costs ~25 us of calls around a ~10 us residual (the finiteness test, the error's two norms, the right-hand
side, the solve's checks, the update).  ``chord_iterations`` runs them (and the step from an iterate whose Jacobian
was just evaluated) in one compiled call on the residual's kernel
(condensed_kernels.residual_jacobian) and the corrector's compiled QR solve (continuation/linalg.py ``_qr_solve``),
with the engine's operations in its order: dot products by BLAS's ddot (numba's ``np.dot``: numpy's ``x.dot(y)`` and
``x @ y`` of 1-D arrays call the same routine; tests/test_per_point_round4.py checks the two agree bit for bit), so the
iterates are the engine's bit for bit.  It returns to the engine where the engine decides something other than the
next chord step: the residual at an iterate that converged, is not finite, or is the last one (``max_iter``); a
non-finite step (a singular system); a step that contracted poorly (the engine refreshes the Jacobian there).
(numba caches this kernel with the residual's and the solve's code inside: after editing condensed_kernels.py or
continuation/linalg.py, touch this file so that it is compiled again; jit.py.)
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.corrector import CHORD_JUDGE, CHORD_REFRESH, CHORD_SINGULAR
from ..continuation.linalg import compiled_qr_solve as _qr_solve
from ..jit import jit
from .condensed_kernels import residual_jacobian

__all__ = ["JUDGE", "SINGULAR", "REFRESH", "chord_iterations", "problem_chord_iterations"]

#: chord_iterations stopped at an iterate whose residual the engine judges (converged, not finite, or the last one)
JUDGE = 0
#: the step from the iterate is not finite (a singular corrector system)
SINGULAR = 1
#: the step contracted poorly (|du_k| > refresh_ratio |du_k-1|): u is the next iterate, the Jacobian is refreshed there
REFRESH = 2


@jit
def chord_iterations(u, u_pred, row, Q, R, last_norm, it, tol, max_iter, refresh_ratio, fresh, cos1, r, beta, w_r, h2,
                     fund, b_r, omega2, pairs, index, R0, R1, complete, E, P, powers, coeffs, kinks):
    """(u, F(u), it, last_norm, code): chord iterations of the corrector from the iterate u (number ``it``), with the
    factorisation Q R of [J; row^T] and the last step's norm ``last_norm`` (NaN: none to compare with), until a code
    (module docstring): JUDGE with the residual at u, SINGULAR with the residual at u, REFRESH with u the next iterate
    (its residual not yet evaluated: the one returned is the previous iterate's).  fresh : the residual at u, evaluated
    with the Jacobian that Q R factorises (its step is not tested for contraction), or an empty array.  The remaining
    arguments are the residual kernel's constants (condensed_kernels.kernel_arguments)."""
    nD = u.shape[0] - 2
    first = fresh.shape[0] > 0
    while True:
        if first:
            res = fresh
        else:
            res = residual_jacobian(u, False, cos1, r, beta, w_r, h2, fund, b_r, omega2, pairs, index, R0, R1,
                                    complete, E, P, powers, coeffs, kinks)[0]
        for i in range(res.shape[0]):
            if not np.isfinite(res[i]):
                return u, res, it, last_norm, JUDGE
        x = u[:nD + 1]
        err = math.sqrt(np.dot(res, res)) / max(math.sqrt(np.dot(x, x)), 1e-300)
        if err < tol or it == max_iter:
            return u, res, it, last_norm, JUDGE
        rhs = np.empty(res.shape[0] + 1)
        for i in range(res.shape[0]):
            rhs[i] = -res[i]
        rhs[-1] = -np.dot(row, u - u_pred)
        du = _qr_solve(Q, R, rhs)
        nrm = math.sqrt(np.dot(du, du))
        if not math.isfinite(nrm):
            return u, res, it, last_norm, SINGULAR
        poor = not first and nrm > refresh_ratio * last_norm          # (False against NaN: no earlier step)
        first = False
        last_norm = nrm
        u = u + du
        it += 1
        if poor:
            return u, res, it, last_norm, REFRESH


_NONE = np.zeros(0)          # (no residual of a fresh Jacobian given)
_CODES = (CHORD_JUDGE, CHORD_SINGULAR, CHORD_REFRESH)       # the kernel's codes as the engine's


def problem_chord_iterations(prob, u, u_pred, row, factor, last_norm, it, tol, settings, fresh=None):
    """CondensedHBProblem.chord_iterations (the engine's hook, continuation/engine.py CHORD_JUDGE): (u, r, it, last_norm,
    code) of ``chord_iterations`` for the condensed problem prob, or None without the compiled kernels or the compiled
    QR (the engine iterates itself).  factor : the engine's LeastSquares; fresh : the residual at u evaluated with the
    factorised Jacobian, or None.  (A problem class that changes the residual must not inherit this.)"""
    qr = factor.compiled_qr
    if prob._kernel is None or qr is None:
        return None
    u, r, it, last_norm, code = chord_iterations(u, u_pred, row, *qr, math.nan if last_norm is None else last_norm,
                                                 it, tol, settings.max_iter, settings.refresh_ratio,
                                                 _NONE if fresh is None else fresh, *prob._kernel[0])
    return u, r, it, last_norm, _CODES[code]
