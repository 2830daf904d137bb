r"""Newton's method at a fixed parameter: F(u) = 0 solved for the unknowns ``free`` while the others stay as given
(natural-parameter correction: e.g. the skeleton's orbit at a fixed modal amplitude, backbone/amplitude_orbit.py;
a forced response at a fixed frequency, orbits/forced_hb.py), or a bordered system whose extra rows the problem
itself appends (the truncation estimate's Newton at a fixed energy, orbits/hb_error.py).

The problem is the engine's (engine.py): ``jacobian(u) -> (r, J)`` and ``error(u, r)``; where it also offers
``residual_parts(u)`` and ``jacobian_of(parts)`` (the residual first, its Jacobian from the same evaluation), the
converged iterate costs a residual only.  The corrector along the arclength (``engine.correct``) and this one are the
two Newton loops of the solver; the bracketing root finder of the events is stability/roots.py.

One iteration: the residual r and the Jacobian J at u; converged when ``error(u, r) < tol``; else the step du solves
J[:, free] du = -r (a square system by LU, ``np.linalg.solve``; an over-determined one in the least-squares sense,
``np.linalg.lstsq``; or by the caller's ``linear(J, b)``).  After at most ``max_iter`` steps the last iterate's
residual is checked once more.  A caller's own stopping rule (e.g. "the frequency has settled", "the step fell
below round-off") is a function ``stop(k, u, du, u_new) -> str`` called after each step: a non-empty reason ends the
iteration there as converged (``NewtonResult.reason``).  Failures are values, not exceptions: a singular system, an
iterate or residual that leaves the finite numbers, a non-positive last unknown (``positive_last``: a frequency or
period) or no convergence in ``max_iter`` steps.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np
import scipy.linalg

from .linalg import all_finite

__all__ = ["newton", "newton_solve", "NewtonSettings", "NewtonResult", "CONVERGED", "MAX_ITER", "SINGULAR",
           "NOT_FINITE", "NON_POSITIVE"]

#: NewtonResult.reason of a converged solve (the residual below tol; a stopping rule gives its own reason)
CONVERGED = "converged"
#: NewtonResult.reason of the failures
MAX_ITER = "no convergence in max_iter steps"
SINGULAR = "singular linear system"
NOT_FINITE = "left the finite numbers"
NON_POSITIVE = "the last unknown (a frequency or period) became non-positive"


@dataclass(frozen=True)
class NewtonSettings:
    """Stopping rule of Newton's method.  tol : converged when problem.error(u, r) < tol (0: only the caller's
    ``stop`` rule ends it); max_iter : largest number of Newton steps; positive_last : the last unknown (a frequency
    or period) must stay positive."""

    tol: float = 1e-10
    max_iter: int = 30
    positive_last: bool = True


@dataclass(frozen=True)
class NewtonResult:
    """u : the last iterate (the solution when converged; before a failing step, the iterate it started from);
    iterations : Newton steps taken; converged : bool; reason : CONVERGED, the stopping rule's reason or the
    failure (MAX_ITER, SINGULAR, NOT_FINITE, NON_POSITIVE)."""

    u: np.ndarray
    iterations: int
    converged: bool
    reason: str


def square_or_least_squares(J, b):
    """du of J du = b: LU for a square J (np.linalg.LinAlgError when singular), least squares otherwise: the
    minimum-norm solution by LAPACK's gelsy (a complete orthogonal factorisation with column pivoting; measured on a
    481 x 480 system of the skeleton's full-basis Newton, one BLAS thread: 14 ms against 40 ms for numpy's SVD-based
    gelsd, the same solution)."""
    if J.shape[0] == J.shape[1]:
        return np.linalg.solve(J, b)
    try:
        return scipy.linalg.lstsq(J, b, lapack_driver="gelsy", check_finite=False)[0]
    except (ValueError, scipy.linalg.LinAlgError) as exc:
        raise np.linalg.LinAlgError(str(exc)) from None


def newton_solve(problem, u, settings: NewtonSettings = NewtonSettings(), free=None,
                 stop: Optional[Callable] = None, linear: Optional[Callable] = None) -> NewtonResult:
    """Newton's method on problem from u (module docstring): a NewtonResult.

    free : indices (or a slice) of the unknowns solved for (default all); the others keep their values.
    stop : optional stopping rule stop(k, u, du, u_new) -> reason ('' to go on), after step k (0-based).
    linear : optional linear solver linear(J, b) -> x (default: square_or_least_squares)."""
    u = np.array(u, dtype=float)
    linear = linear or square_or_least_squares
    parts_of = getattr(problem, "residual_parts", None)
    tol = settings.tol
    for k in range(settings.max_iter):
        if parts_of is not None:
            parts = parts_of(u)
            r = parts[-1]
            if tol > 0 and all_finite(r) and problem.error(u, r) < tol:
                return NewtonResult(u, k, True, CONVERGED)
            r, J = problem.jacobian_of(parts)
        else:
            r, J = problem.jacobian(u)
        if not all_finite(r):
            return NewtonResult(u, k, False, NOT_FINITE)
        if tol > 0 and problem.error(u, r) < tol:
            return NewtonResult(u, k, True, CONVERGED)
        try:
            du = linear(J if free is None else J[:, free], -r)
        except np.linalg.LinAlgError:
            return NewtonResult(u, k, False, SINGULAR)
        u_new = u + du if free is None else _added(u, free, du)
        if not all_finite(u_new):
            return NewtonResult(u, k, False, NOT_FINITE)
        if settings.positive_last and u_new[-1] <= 0:
            return NewtonResult(u, k, False, NON_POSITIVE)
        reason = stop(k, u, du, u_new) if stop is not None else ""
        u = u_new
        if reason:
            return NewtonResult(u, k + 1, True, reason)
    if tol > 0:
        r = problem.residual(u)
        if all_finite(r) and problem.error(u, r) < tol:
            return NewtonResult(u, settings.max_iter, True, CONVERGED)
    return NewtonResult(u, settings.max_iter, False, MAX_ITER)


def _added(u, free, du):
    v = u.copy()
    v[free] += du
    return v


def newton(problem, u, free=None, tol=1e-10, max_iter=30, positive_last=True):
    """The solution of F(u) = 0 over the unknowns ``free`` (indices; default all, for a square system) from u, or None
    when it does not converge in max_iter iterations, meets a singular Jacobian, leaves the finite numbers or (with
    positive_last) makes the last unknown (a frequency or period) non-positive (``newton_solve``'s result, short)."""
    res = newton_solve(problem, u, NewtonSettings(tol, max_iter, positive_last), free)
    return res.u if res.converged else None
