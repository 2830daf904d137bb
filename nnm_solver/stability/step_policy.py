"""Decisions about one continuation step before its events are located: the events' energy tolerance (from the
step's estimated discretisation error) and whether the step gets the mid-step check (Locator.jumped).  Small
functions that return values; the thresholds are settings.py's.
"""
from __future__ import annotations

import numpy as np

from .settings import STABILITY

__all__ = ["event_rtol", "mid_step_check"]


def event_rtol(freq_error):
    """Relative energy tolerance of the events of a step whose points have the estimated relative frequency error
    freq_error (the time discretisation's, ShootingProblem.frequency_error): a hundredth of it, within
    [STABILITY.event_rtol, STABILITY.event_rtol_max] (STABILITY.event_rtol when there is no estimate).  Locating far
    below the discretisation error would only cost corrector runs."""
    if not np.isfinite(freq_error):
        return STABILITY.event_rtol
    return float(min(max(0.01 * freq_error, STABILITY.event_rtol), STABILITY.event_rtol_max))


def mid_step_check(step, distances):
    """Whether a step of the continuation gets the mid-step check (Locator.jumped): where the step is long (at least
    STABILITY.jump_check_long in the balanced norm: a relative change of the orbit) or a tongue is near, i.e. at
    either end the point's relative distance from the skeleton's family is at least STABILITY.jump_check_near x its
    label's tolerance; and wherever a distance is unknown.  distances : ((dev, tolerance) or None) of the step's two ends
    (labels.Verdict: dev None where no skeleton covers the energy).  settings.py gives the measurement."""
    if step >= STABILITY.jump_check_long:
        return True
    for d in distances:
        if d is None or d[0] is None or not d[1] > 0 or not np.isfinite(d[0]):
            return True
        if d[0] >= STABILITY.jump_check_near * d[1]:
            return True
    return False
