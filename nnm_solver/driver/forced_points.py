"""Points of a forced response curve found apart from the continuation's steps (driver/forced.py), all with the
continuation layer's correctors: the first orbit (Newton at the start frequency from the linear response, with the
force ramped up where that fails: continuation/newton.py, continuation/natural.py), the curve's tangent at a point,
the landing on the end frequency (Newton at that frequency), and a fold between two converged points (the bracketing
root finder of stability/roots.py on the frequency component of the tangent along the chord, each trial point
corrected onto the curve by the engine's corrector on the hyperplane orthogonal to the chord)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..continuation.engine import CorrectorFailure, correct_factored, tangent_factored
from ..continuation.natural import natural_parameter
from ..stability.roots import BracketRoots

__all__ = ["first_orbit", "frequency_tangent", "land_on_frequency", "locate_fold", "ForcedPointSettings"]


@dataclass(frozen=True)
class ForcedPointSettings:
    """The points' own limits.  force_ramps : the force ramps of the first orbit, tried in turn where Newton fails at
    full force (from 1/8 of the force in 8 equal steps, then 32, then 128); fold_iterations : largest number of trial
    points of the fold's root finder; fold_corrector_iterations : largest number of corrector iterations of a trial
    point; fold_tol : the fold's root is converged when the bracket (in units of the chord) or the tangent's frequency
    component (balanced norm) is below this."""

    force_ramps: tuple = (8, 32, 128)
    fold_iterations: int = 40
    fold_corrector_iterations: int = 30
    fold_tol: float = 1e-13


def first_orbit(problem, omega, tol, settings=ForcedPointSettings()):
    """(u, '') of the converged response at omega, from the linear response, ramping the force from a small
    fraction of it when Newton fails at full force (natural-parameter continuation in the force's scale, each step
    predicted by scaling the coefficients, continuation/natural.py); (None, why) if it does not converge."""
    u, ok = problem.solve_at_frequency(problem.linear_start(omega), tol)
    if ok:
        return u, ""

    def at_load(u, load):
        problem.load = load
        return problem.solve_at_frequency(u, tol)

    def scaled(u, load_from, load_to):
        return np.concatenate([u[:-1] * (load_to / load_from), u[-1:]])

    for ramp in settings.force_ramps:
        problem.load = 1.0 / ramp
        res = natural_parameter(at_load, problem.linear_start(omega), np.arange(1, ramp + 1) / ramp, scaled)
        problem.load = 1.0
        if res.completed:
            return res.u, ""
    return None, (f"the response at f_start = {omega / (2 * np.pi):.6g} Hz did not converge (Newton from the linear "
                  f"response, also with the force ramped up in {settings.force_ramps[-1]} steps): start the range "
                  f"elsewhere")


def frequency_tangent(J):
    """The curve's tangent [dA/d(omega / w_ref); 1] at a point whose Jacobian is J (rising frequency; the
    coefficients' block of J nonsingular, i.e. not at a fold)."""
    return np.concatenate([np.linalg.solve(J[:, :-1], -J[:, -1]), [1.0]])


def land_on_frequency(problem, ua, ub, omega, tol, along):
    """The response at omega between the converged points ua and ub (omega between their frequencies): Newton at
    that frequency from the chord's point there.  (u, J, tangent oriented along ``along``), or None if it does not
    converge."""
    wa, wb = problem.frequency(ua), problem.frequency(ub)
    t = (omega - wa) / (wb - wa)
    u, ok = problem.solve_at_frequency(problem.with_frequency(ua + t * (ub - ua), omega), tol)
    if not ok:
        return None
    _, J = problem.jacobian(u)
    p = frequency_tangent(J)
    return u, J, (p if p @ along >= 0 else -p)


def locate_fold(problem, ua, ub, tol, engine_settings, settings=ForcedPointSettings()):
    """The fold of the curve between the converged points ua and ub (the frequency component of the tangent
    changes sign): the root of that component along the chord (stability/roots.py: Illinois regula falsi with a
    bisection safeguard, to settings.fold_tol of the chord or of the component), each trial point corrected onto the
    curve on the hyperplane orthogonal to the chord (the engine's corrector, ``correct_factored``, with the engine's
    ``engine_settings``, at most settings.fold_corrector_iterations iterations).  None if a correction fails or the
    component does not change sign."""
    c = ub - ua
    w = problem.scale(ua)
    cs = replace(engine_settings, max_iter=settings.fold_corrector_iterations)
    points = {}

    def component(t):
        """The tangent's frequency component at the curve's point on the hyperplane through ua + t c (NaN where the
        corrector fails: the root finder then returns that t, and the fold is not located)."""
        try:
            u, J, _, _, factor = correct_factored(problem, ua + t * c, c, cs, tol, w)
            p, _ = tangent_factored(J, c, w, factor)
        except (CorrectorFailure, np.linalg.LinAlgError):
            points[t] = None
            return float("nan")
        points[t] = u
        return float(p[-1])

    ga, gb = component(0.0), component(1.0)
    if not ga * gb <= 0:                      # (a failed correction gives NaN: not a bracket either)
        return None

    def converged(a, b, fa, fb):
        return abs(b - a) < settings.fold_tol or min(abs(fa), abs(fb)) < settings.fold_tol

    t = BracketRoots().root(component, 0.0, 1.0, ga, gb, max_iter=settings.fold_iterations, converged=converged)
    return points.get(t)
