r"""Pseudo-arclength continuation of the solutions of F(u) = 0 (seed paper, eq. 7-11).

Generic: it knows nothing about shooting or harmonic balance.  A *problem* provides

    problem.residual(u) -> r                  F(u), shape (m,), m >= len(u) - 1
    problem.jacobian(u) -> (r, J)             F(u) and dF/du, shape (m, len(u))
    problem.error(u, r) -> float              relative error used for convergence (eq. 11)
    problem.accept(u, J)                      called once a point is accepted (e.g. moves the
                                              phase-condition reference)
    problem.scale(u) -> w                     optional: positive weights (len(u),); steps, angles and
                                              the arclength condition are measured in y = w * u
    problem.max_step(u, p) -> float           optional: largest step from u along the tangent p
                                              (in the scaled units)
    problem.check_step(u_old, u_new) -> str   optional: a reason to refuse a converged step
                                              (e.g. too large a change of period), or ''
    problem.energy(u) -> float                optional: the conserved energy, for the fold guard
    problem.residual_kernel -> (kernel, args) optional: the residual as a compiled kernel (chord.residual_kernel,
                                              e.g. orbits/condensed_kernels.py; error(u, r) is then
                                              |r| / |u[:-1]|), or None: the corrector's chord iterations then run in
                                              one compiled call (chord.py), the same iterates

The system may be over-determined with a redundant row (shooting of a conservative system has
one: energy conservation), so every linear solve is a least-squares (Moore-Penrose) solve.

Scaling.  The unknowns of an orbit mix an amplitude part (m, from 1e-8 to 1e3 along one branch) and a
period part (O(1)).  Measured in u itself, a step would be all period at small amplitude (crawling)
and all amplitude at large amplitude (the period, and with it the entrance of internal-resonance
tongues, jumps unseen).  With the problem's weights w (e.g. 1/|amplitude| and 1/period), re-evaluated
at every accepted point, a step s = 0.1 changes the orbit by about 10 % in the balanced norm
|w * du|, whatever the amplitude.

Predictor (eq. 7-8): u~ = u_j + s p_j, with p_j the tangent, i.e. the solution of
[J; p_{j-1}^T] p = [0; 1], normalised to |w * p| = 1.  Corrector (eq. 9-10): Newton on
[F(u); (w^2 p_j)^T (u - u~)] = 0, i.e. corrections orthogonal to the tangent in the scaled norm.  The
Jacobian is re-used between iterations (chord Newton) and refreshed only when the iteration stops
contracting fast, so most iterations cost only a residual evaluation.  Step control: the step grows
when the corrector converges in few iterations, shrinks when it needs many, and is halved on
failure, when the new tangent turns by more than ``max_angle``, when the corrector lands far from the
prediction (``max_correction``), when the energy or the period changed against the tangent's derivative
of it at both ends of the step (an even number of turning points crossed unseen: a tongue stepped over,
or a jump onto a branch alongside), or when the problem refuses the step (``check_step``); these guard
against jumping between nearby branches and over the narrow entrance of internal-resonance tongues.  When
small steps keep failing (a singular point, e.g. a branch point), one longer step is tried to step over it,
never longer than the problem's largest step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .corrector import (CHORD_JUDGE, CHORD_REFRESH, CHORD_SINGULAR, CorrectorFailure, _norm,  # noqa: F401
                        correct, correct_factored, jacobian_at)
from .linalg import LeastSquares, all_finite, stacked  # noqa: F401 (LeastSquares, stacked: part of the interface)


@dataclass(frozen=True)
class ContinuationSettings:
    """Step control of the pseudo-arclength continuation (step lengths in units of u)."""

    step: float
    step_min: float
    step_max: float
    max_iter: int = 12
    target_iter: int = 4
    max_angle: float = 0.35      # rad, largest turn of the tangent between two points
    max_correction: float = 0.5  # largest corrector displacement, relative to the step
    max_failures: int = 16       # consecutive failed steps before giving up
    jump_after: int = 4          # after this many failures, try one step of jump_factor x the last good step
    jump_factor: float = 2.5
    refresh_ratio: float = 0.5   # refresh the Jacobian when |e_k+1|/|e_k| exceeds this


@dataclass
class ContinuationPoint:
    u: np.ndarray
    tangent: np.ndarray
    jacobian: np.ndarray
    iterations: int
    step: float
    error: float
    factor: object = None       # LeastSquares of [jacobian; previous tangent] (reusable for other solves)


def tangent(J, previous, w=None):
    """Tangent p of F(u) = 0 from J = dF/du (eq. 8), |w * p| = 1, oriented along ``previous``."""
    return tangent_factored(J, previous, w)[0]


def tangent_factored(J, previous, w=None, factor=None):
    """(p, factor): the tangent, and the factorisation of [J; previous^T] it was solved with (any solve
    J du = b with previous . du = 0 can reuse it).

    factor : optional factorisation of [J; c^T] with any row c transversal to the tangent (e.g. the
    corrector's, ``correct_factored``); it is used instead of a new QR (the null direction of J is
    the same whatever the extra row)."""
    w = np.ones(J.shape[1]) if w is None else w
    if factor is None:
        factor = LeastSquares(stacked(J, previous))
    b = np.zeros(J.shape[0] + 1)
    b[-1] = 1.0
    p = factor.solve(b)
    p /= _norm(w * p)
    return (p if (w * p) @ (w * previous) >= 0 else -p), factor


def scale_of(problem, u):
    """The problem's positive weights at u (problem.scale), or ones: steps are measured in |w * du|."""
    return problem.scale(u) if hasattr(problem, "scale") else np.ones(len(u))


def pseudo_arclength(problem, u0, p0, settings, tol):
    """Iterate over converged points along the branch through u0 (first yielded point: u0 corrected).

    u0 : approximate first point; p0 : approximate direction (the first point is corrected with
    corrections orthogonal to p0).  Yields ContinuationPoint; the caller stops
    the iteration.  ``send(REFUSE)`` instead of ``next`` refuses the point just yielded: the engine goes
    back to the point before it and tries again with half the step (e.g. when the caller could not
    locate the events inside the step: it jumped over a feature of the branch).  When a step cannot be completed even at ``step_min`` the generator returns with
    a ``StopIteration`` value: the reason (str).  Step lengths are in the problem's scaled units.
    """
    w = scale_of(problem, u0)
    p0 = p0 / _norm(w * p0)
    energy = _Remembered(problem) if hasattr(problem, "energy") else None
    try:
        u, J, it, err, factor = correct_factored(problem, u0, p0, settings, tol, w)
    except CorrectorFailure as exc:
        return f"the starting point did not converge: {exc}"
    w = scale_of(problem, u)
    p, factor = tangent_factored(J, p0, w, factor)
    if not all_finite(p):
        return "the starting point has no tangent (a singular Jacobian)"
    problem.accept(u, J)
    s = settings.step
    yield ContinuationPoint(u, p, J, it, 0.0, err, factor)
    failures = 0
    s_clean = s_before_jump = s
    s_cap = _largest_step(problem, u, p, settings)
    cos_max = np.cos(settings.max_angle)
    check_step = getattr(problem, "check_step", None)
    while True:
        u_pred = u + s * p
        try:
            # (the Jacobian at the converged point only once the step passed the checks that need no Jacobian:
            # on the aircraft's NNM 20 skipping its tongues 36 refused steps had a Jacobian and a factorisation made)
            u_new, J_new, it, err, factor_new = correct_factored(problem, u_pred, p, settings, tol, w, refresh=False)
            dist = _norm(w * (u_new - u_pred))
            # (a step far below the corrector's own accuracy, ~tol in the scaled units, is not judged by it)
            if dist > settings.max_correction * s and dist > 10 * tol:
                raise CorrectorFailure(f"the corrector moved {dist / s:.2f} step lengths away from the prediction")
            if check_step is not None:
                reason = check_step(u, u_new)
                if reason:
                    raise CorrectorFailure(reason)
            if J_new is None:
                J_new, err, factor_new = jacobian_at(problem, u_new, w * w * p, tol)
            p_new, factor_new = tangent_factored(J_new, p, w, factor_new)
            if not all_finite(p_new):
                raise CorrectorFailure("no tangent at the new point (a singular Jacobian)")
            cos = (w * p_new) @ (w * p) / _norm(w * p_new)
            if cos < cos_max:
                raise CorrectorFailure(f"tangent turned by {np.degrees(np.arccos(np.clip(cos, -1, 1))):.0f} deg")
            reason = _unseen_turns(energy, u, p, u_new, p_new, 10 * tol)
            if reason:
                raise CorrectorFailure(reason)
        except CorrectorFailure as exc:
            failures += 1
            if failures == settings.jump_after:
                # small steps keep failing: likely a singular point (e.g. a branch point where the
                # Jacobian loses rank); try once to step over it with a step longer than the last
                # step that succeeded without trouble
                s = min(settings.jump_factor * s_clean, s_cap)     # never beyond the problem's largest step
            elif failures == settings.jump_after + 1:
                s = s_before_jump * 0.5
            else:
                s *= 0.5
            if failures == settings.jump_after - 1:
                s_before_jump = s
            if s < settings.step_min or failures > settings.max_failures:
                return f"{failures} consecutive failed steps (last: {exc}; step {s:.2e})"
            continue
        if failures == 0:
            s_clean = s
        failures = 0
        previous = (u, J, p, factor, w)
        w = scale_of(problem, u_new)
        u, J, p, factor = u_new, J_new, p_new / _norm(w * p_new), factor_new
        problem.accept(u, J)
        if (yield ContinuationPoint(u, p, J, it, s, err, factor)) == REFUSE:
            # the caller refuses the step (its events could not be located inside it): back to the
            # previous point, half the step
            u, J, p, factor, w = previous
            problem.jacobian(u)         # the problem's state (e.g. its last sensitivity maps) at that point again
            problem.accept(u, J)
            s = max(0.5 * s, settings.step_min)
            continue
        # step control from the number of corrector iterations
        if it <= settings.target_iter // 2:
            s *= 2.0
        elif it < settings.target_iter:
            s *= 1.4
        elif it > settings.target_iter + 1:
            s *= 0.6
        s_cap = _largest_step(problem, u, p, settings)
        s = float(min(max(s, settings.step_min), s_cap))      # (np.clip's number)


def _largest_step(problem, u, p, settings):
    """The largest step from u along p: settings.step_max, or less if the problem says so (max_step)."""
    s_max = settings.step_max
    if hasattr(problem, "max_step"):
        s_max = min(s_max, problem.max_step(u, p))
    return max(s_max, settings.step_min)


#: sent to the pseudo_arclength generator (``engine.send(REFUSE)``) to refuse the point it just yielded
REFUSE = "refuse"


def _energy_slope(energy, u, p, h=1e-6):
    """dE/ds along the tangent p (scaled so that h p is a relative change of h), central difference."""
    return (energy(u + h * p) - energy(u - h * p)) / (2 * h)


def energy_slope(problem, u, p):
    """dE/ds along the tangent p: g . p with the problem's energy gradient in closed form where it says it has one
    that costs about an energy (``problem.slope_from_gradient``: the condensed HB problem, one gradient instead of
    two energies), else the central difference ``_energy_slope`` (whose own error, ~1e-10 relative, is what the two
    differ by)."""
    if getattr(problem, "slope_from_gradient", False):
        return float(problem.energy_gradient(u) @ p)
    return _energy_slope(problem.energy, u, p)


class _Remembered:
    """The problem's energy function remembering its last two values, by the orbit's bytes (each step's unseen-turns
    check asks for the energy of its start, which the step before computed as its end), with its slope along a
    tangent (``slope(u, p)``: energy_slope)."""

    def __init__(self, problem):
        self.energy = problem.energy
        if getattr(problem, "gradient_with_energy", False):
            # (an energy costs about as much with its gradient, which the problem keeps: the slope at a step's end is
            # asked for next, by this check or by the branch iterator's events; the same energy)
            self.energy = lambda u: problem.energy_and_gradient(u)[0]
        self.slope = lambda u, p: energy_slope(problem, u, p)
        self.kept = []

    def __call__(self, u):
        key = u.tobytes()
        for k, E in self.kept:
            if k == key:
                return E
        E = self.energy(u)
        self.kept = self.kept[-1:] + [(key, E)]
        return E


def _unseen_turns(energy, u, p, u_new, p_new, floor, slope=None):
    """A reason to refuse the step if the energy, or the last unknown (for orbit problems the period or the
    frequency: the other coordinate of the frequency-energy plot), changed against its derivative along the
    tangent at both ends.  Then the step crossed an even number of turning points of that coordinate (the
    branch turned back and forth unseen, e.g. over a tongue's fold), or the corrector landed on another branch
    running alongside (e.g. from the side of a tongue onto the backbone).  Changes below ``floor`` (relative:
    the corrector's own accuracy) are not judged.  energy : callable or None; slope : callable (u, p) -> dE/ds
    (default: energy's own ``slope`` if it has one, the engine's _Remembered, else central differences of energy)."""
    if energy is not None:
        slope = slope or getattr(energy, "slope", None) or (lambda x, t: _energy_slope(energy, x, t))
        E0, E1 = energy(u), energy(u_new)
        dE = E1 - E0
        if (abs(dE) > floor * max(abs(E0), abs(E1)) and dE * slope(u, p) < 0
                and dE * slope(u_new, p_new) < 0):
            return "the energy changed against its slope at both ends of the step (folds crossed unseen)"
    dT = u_new[-1] - u[-1]
    if abs(dT) > floor * max(abs(u[-1]), abs(u_new[-1])) and dT * p[-1] < 0 and dT * p_new[-1] < 0:
        return ("the period (last unknown) changed against its slope at both ends of the step (turning points "
                "crossed unseen, or another branch reached)")
    return ""
