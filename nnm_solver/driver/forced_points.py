"""Two points of a forced response curve found apart from the continuation (driver/forced.py): the first orbit
(Newton from the linear response, with the force ramped up where that fails) and a fold between two converged
points (regula falsi on the frequency component of the tangent along the chord)."""
from __future__ import annotations

import numpy as np

__all__ = ["first_orbit", "locate_fold"]


def first_orbit(problem, omega, tol):
    """(u, '') of the converged response at omega, from the linear response, ramping the force from a small
    fraction of it when Newton fails at full force; (None, why) if it does not converge."""
    u, ok = problem.solve_at_frequency(problem.linear_start(omega), tol)
    if ok:
        return u, ""
    for ramp in (8, 32, 128):
        problem.load = 1.0 / ramp
        u, ok = problem.solve_at_frequency(problem.linear_start(omega), tol)
        k = 1
        while ok and k < ramp:
            k += 1
            scale = k / (k - 1)
            problem.load = k / ramp
            u, ok = problem.solve_at_frequency(np.concatenate([u[:-1] * scale, u[-1:]]), tol)
        problem.load = 1.0
        if ok:
            return u, ""
    return None, (f"the response at f_start = {omega / (2 * np.pi):.6g} Hz did not converge (Newton from the linear "
                  f"response, also with the force ramped up in 128 steps): start the range elsewhere")


def locate_fold(problem, ua, ub, tol, max_iter=40):
    """The fold of the curve between the converged points ua and ub (the frequency component of the tangent
    changes sign): Illinois regula falsi on that component along the chord, each trial point corrected onto
    the curve on the hyperplane orthogonal to the chord.  None if a correction fails."""
    c = ub - ua
    w = problem.scale(ua)
    row = w * w * c

    def point(t):
        target = ua + t * c
        u = target.copy()
        for _ in range(30):
            r, J = problem.jacobian(u)
            A = np.vstack([J, row])
            if problem.error(u, r) < tol and abs(row @ (u - target)) <= 1e-14 * abs(row @ c):
                b = np.zeros(len(u))
                b[-1] = 1.0
                p = np.linalg.solve(A, b)
                return u, p[-1] / np.linalg.norm(w * p)
            u = u + np.linalg.solve(A, -np.concatenate([r, [row @ (u - target)]]))
        return None

    try:
        a, b = point(0.0), point(1.0)
        if a is None or b is None or a[1] * b[1] > 0:
            return None
        ta, tb, ga, gb = 0.0, 1.0, a[1], b[1]
        best = a if abs(ga) < abs(gb) else b
        side = 0
        for _ in range(max_iter):
            t = (ta * gb - tb * ga) / (gb - ga)
            res = point(t)
            if res is None:
                return None
            best, g = res, res[1]
            if abs(g) < 1e-13 or abs(tb - ta) < 1e-13:
                break
            if g * gb > 0:                    # t replaces b (Illinois: halve a's value if b moved twice)
                tb, gb = t, g
                if side == -1:
                    ga *= 0.5
                side = -1
            else:
                ta, ga = t, g
                if side == 1:
                    gb *= 0.5
                side = 1
        return best[0]
    except np.linalg.LinAlgError:
        return None
