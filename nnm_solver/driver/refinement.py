"""Finer time steps where the frequency error demands it, and the error estimate of the kept points.

``StepRefinement`` is held by the branch iterator (iterator.NNMIterator).  With ``freq_tol`` a point whose estimated
frequency error (the time discretisation's part, step doubling: ShootingProblem.frequency_error) exceeds it
raises the steps per period, by the scheme's order, and the continuation starts again from that orbit: ``refine``
returns the new engine, which the iterator restarts on.
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import CorrectorFailure, correct, pseudo_arclength

__all__ = ["StepRefinement", "HarmonicRefinement", "accuracy_note"]


class StepRefinement:
    """freq_tol refinement and the points' frequency error estimate (driver/candidate.Candidate's).

    freq_tol : the largest estimated error of the time discretisation (None: no refinement); error_estimate : estimate
    every point's error; max_steps_per_period : the finest step it goes to (Shooting.max_steps_per_period);
    pause_after_failure : points it waits after a finer step failed (next to a fold that the finer step moves);
    failures : how many finer steps failed."""

    def __init__(self, freq_tol=None, error_estimate=True, max_steps_per_period=20000, pause_after_failure=3):
        self.freq_tol = None if not freq_tol else float(freq_tol)
        self.error_estimate = bool(error_estimate) or self.freq_tol is not None
        self.max_steps_per_period = int(max_steps_per_period)
        self.pause_after_failure = int(pause_after_failure)
        self.failures = 0
        self._pause = 0

    def refine(self, problem, cp, cand, settings, tol):
        """freq_tol: if the point's estimated frequency error exceeds it, raise the problem's steps per period
        (aiming at a quarter of the tolerance, by the scheme's order) and return the continuation restarted from
        this orbit (engine.pseudo_arclength), so that the point is computed again with the finer step; None if
        nothing was done."""
        if not self.freq_tol or not hasattr(problem, "set_steps"):
            return None
        self.estimate(cand)
        est = cand.disc_error                   # what finer steps can reduce
        if not est > self.freq_tol or problem.spp >= self.max_steps_per_period:
            return None
        if self._pause > 0:
            self._pause -= 1
            return None
        factor = min(max((est / (0.25 * self.freq_tol)) ** (1.0 / problem.integrator.order), 1.25), 4.0)
        old = problem.spp
        # the finer step aimed at a quarter of the tolerance, else one that just meets it: next to an energy fold the
        # larger change moves the fold away from the coarse orbit (the 2-DOF's 3:1 tongue top at 4.68 kJ, Newmark 364
        # -> 828 steps: no convergence; 364 -> 456 converged)
        meets = min(max((est / self.freq_tol) ** (1.0 / problem.integrator.order), 1.25), factor)
        if self._converges(problem, cp, settings, tol, old, factor) or (
                meets < factor and self._converges(problem, cp, settings, tol, old, meets)):
            return pseudo_arclength(problem, cp.u, cp.tangent, settings, tol)
        problem.set_steps(old)                  # e.g. next to a fold that the finer step moves: keep the coarse
        self._pause = self.pause_after_failure  # point and try again a few points later
        self.failures += 1
        return None

    def _converges(self, problem, cp, settings, tol, old, factor):
        """Set the problem's steps to factor x old (at most max_steps_per_period): does the orbit with them converge
        next to the point cp?"""
        problem.set_steps(min(int(np.ceil(old * factor)), self.max_steps_per_period))
        try:
            correct(problem, cp.u, cp.tangent, settings, tol, problem.scale(cp.u))
        except CorrectorFailure:
            return False
        return True

    def estimate(self, cand):
        """cand.point.freq_error (and cand.disc_error) from the problem's estimate (shooting: step doubling),
        unless disabled."""
        prob, u, J, p, factor = cand.solution or (None,) * 5
        if self.error_estimate and prob is not None and hasattr(prob, "frequency_error") and J is not None:
            if not np.isfinite(cand.point.freq_error):
                cand.point.freq_error, cand.disc_error = prob.frequency_error(u, J, p, factor)


class HarmonicRefinement:
    """freq_tol for harmonic balance: more harmonics where a point's estimated truncation error exceeds it.

    The estimate (orbits/hb_error.py) is the change of the frequency with two more harmonics at the same energy; where
    it exceeds freq_tol the branch goes on with ``step`` more harmonics from that orbit (its coefficients embedded,
    the new ones zero), up to max_harmonics, and the point is computed again.  Points whose estimate is inf (the
    larger problem does not settle: inside a tongue the truncation does not resolve) are left as they are: more
    harmonics there would follow the tongue, not the backbone.  Only a problem on every mode (not a Ritz basis, whose
    modes were chosen for the first number of harmonics) is refined."""

    def __init__(self, freq_tol=None, max_harmonics=0, step=2, pause_after_failure=3):
        self.freq_tol = None if not freq_tol else float(freq_tol)
        self.max_harmonics = int(max_harmonics)
        self.step = int(step)
        self.pause_after_failure = int(pause_after_failure)
        self.raised = 0
        self.failures = 0
        self._pause = 0

    def refine(self, problem, cp, cand, settings, tol):
        """(new problem, the continuation restarted on it) when the point asks for more harmonics, else None."""
        err = cand.point.freq_error
        if (not self.freq_tol or not hasattr(problem, "with_harmonics") or not np.isfinite(err)
                or not err > self.freq_tol or problem.basis.harmonics + self.step > self.max_harmonics):
            return None
        if self._pause > 0:
            self._pause -= 1
            return None
        finer = problem.with_harmonics(problem.basis.harmonics + self.step)
        u, t = problem.embedded(finer, cp.u), problem.embedded(finer, cp.tangent)
        try:
            correct(finer, u, t, settings, tol, finer.scale(u))
        except CorrectorFailure:
            # no orbit with more harmonics next to this one (e.g. beside a tongue's entry): keep this truncation
            # for a few points and try again.  Giving up for good left a softening beam's HB backbone (a cubic
            # spring at mid-span) at 7 harmonics after one failure beside a 7:1 tongue at 0.61 of its saddle
            # energy, its points near the saddle then 2e-2 off with the estimate saying so (2026-12-07).
            self._pause = self.pause_after_failure
            self.failures += 1
            return None
        self.raised += 1
        return finer, pseudo_arclength(finer, u, t, settings, tol)


def accuracy_note(errors, disc_errors, freq_tol, tol, harmonics=None, max_harmonics=None):
    """What a branch's message says of its points above the accuracy target freq_tol: errors (each point's estimated
    relative frequency error), disc_errors (the time discretisation's part; NaN for harmonic balance), tol (the
    corrector's); harmonics / max_harmonics: a harmonic-balance branch's truncation at its end and its cap (None for
    shooting, or without the target).  "" when every point meets the target."""
    over = [i for i, e in enumerate(errors) if e > freq_tol]
    steps = [i for i in over if disc_errors[i] > freq_tol]
    note = ""
    if steps:
        note += (f"; {len(steps)} points exceed freq_tol = {freq_tol:g} (the finer step did not converge next to "
                 f"them, e.g. near a fold: see freq_error)")
    rest = len(over) - len(steps)
    if rest and harmonics is not None and max_harmonics is not None:
        note += (f"; {rest} points exceed freq_tol = {freq_tol:g} (harmonic balance, {harmonics} harmonics at the "
                 f"end, at most {max_harmonics}: more did not converge next to them or were not allowed; see "
                 f"freq_error)")
    elif rest:
        note += (f"; {rest} points exceed freq_tol = {freq_tol:g} because of the corrector's tolerance: lower tol "
                 f"(now {tol:g})")
    return note
