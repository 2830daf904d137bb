"""Finer time steps where the frequency error demands it, and the error estimate of the kept points.

A mixin of the branch iterator (iterator.NNMIterator; attributes used: freq_tol, error_estimate, _problem, _engine,
_cs, _tol, _prev, _refusals, _refine_pause, refine_failures, max_steps_per_period).  With ``freq_tol`` a point whose estimated
frequency error (the time discretisation's part, step doubling: ShootingProblem.frequency_error) exceeds it
raises the steps per period, by the scheme's order, and the continuation starts again from that orbit.
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import CorrectorFailure, correct, pseudo_arclength

__all__ = ["StepRefinement"]


class StepRefinement:
    """freq_tol refinement and the points' frequency error estimate, for NNMIterator."""

    def _refined(self, cp, point):
        """freq_tol: if the point's estimated frequency error exceeds it, raise the steps per period (aiming at
        a quarter of the tolerance, by the scheme's order) and restart the continuation from this orbit, so
        that the point is computed again with the finer step.  False if nothing was done."""
        prob = self._problem
        if not self.freq_tol or not hasattr(prob, "set_steps"):
            return False
        self._estimate_error(point)
        est = getattr(point, "_disc_error", point.freq_error)   # what finer steps can reduce
        if not est > self.freq_tol or prob.spp >= self.max_steps_per_period:
            return False
        if self._refine_pause > 0:
            self._refine_pause -= 1
            return False
        factor = min(max((est / (0.25 * self.freq_tol)) ** (1.0 / prob.integrator.order), 1.25), 4.0)
        old = prob.spp
        prob.set_steps(min(int(np.ceil(prob.spp * factor)), self.max_steps_per_period))
        try:                                    # the orbit with the finer step, near this one
            correct(prob, cp.u, cp.tangent, self._cs, self._tol, prob.scale(cp.u))
        except CorrectorFailure:                # e.g. next to a fold that the finer step moves: keep the
            prob.set_steps(old)                 # coarse point and try again a few points later
            self._refine_pause = 3
            self.refine_failures += 1
            return False
        self._engine.restart(pseudo_arclength(prob, cp.u, cp.tangent, self._cs, self._tol))
        self._prev = None                       # no event is located across a change of time step
        self._refusals = 0
        return True

    def _estimate_error(self, point):
        """point.freq_error from the problem's estimate (shooting: step doubling), unless disabled."""
        prob, u, J, p, factor = getattr(point, "_solution", None) or (None,) * 5
        if self.error_estimate and prob is not None and hasattr(prob, "frequency_error") and J is not None:
            if not np.isfinite(point.freq_error):
                point.freq_error, point._disc_error = prob.frequency_error(u, J, p, factor)

    @staticmethod
    def _release(point):
        """Drop the Jacobian and factorisation a kept point carried for its error estimate (O(n^2) each)."""
        point._solution = None
        point._observed = None

