r"""Newton's method at a fixed parameter: F(u) = 0 solved for the unknowns ``free`` while the others stay as given
(natural-parameter correction: e.g. the skeleton's orbit at a fixed modal amplitude, backbone/amplitude_orbit.py).

The problem is the engine's (engine.py): ``jacobian(u) -> (r, J)`` and ``error(u, r)``; where it also offers
``residual_parts(u)`` and ``jacobian_of(parts)`` (the residual first, its Jacobian from the same evaluation), the
converged iterate costs a residual only.  The corrector along the arclength (``engine.correct``) and this one are the
two Newton loops of the solver's continuation; the bracketing root finder of the events is stability/roots.py.
"""
from __future__ import annotations

import numpy as np

__all__ = ["newton"]


def newton(problem, u, free=None, tol=1e-10, max_iter=30, positive_last=True):
    """The solution of F(u) = 0 over the unknowns ``free`` (indices; default all, for a square system) from u, or None
    when it does not converge in max_iter iterations, meets a singular Jacobian, leaves the finite numbers or (with
    positive_last) makes the last unknown (a frequency or period) non-positive."""
    u = np.array(u, dtype=float)
    parts_of = getattr(problem, "residual_parts", None)
    for _ in range(max_iter):
        if parts_of is not None:
            parts = parts_of(u)
            if problem.error(u, parts[-1]) < tol:
                return u
            r, J = problem.jacobian_of(parts)
        else:
            r, J = problem.jacobian(u)
            if problem.error(u, r) < tol:
                return u
        try:
            du = np.linalg.solve(J if free is None else J[:, free], -r)
        except np.linalg.LinAlgError:
            return None
        if free is None:
            u += du
        else:
            u[free] += du
        if not np.all(np.isfinite(u)) or (positive_last and u[-1] <= 0):
            return None
    return None
