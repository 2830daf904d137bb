"""The Compute tab's time left: an estimate from the recent points' pace, or none when the pace
is refuted by a stall.

A job ends at ``max_points`` or when the branch reaches ``energy_max``, whichever comes first (or
earlier, at a stop the solver decides: a fold, a tongue, the minimum step, which no pace predicts).
The way to ``energy_max`` is measured in log(energy): continuation steps in arclength give roughly
even steps in log E along a hardening backbone, and the solver's own progress is that fraction.

The estimate uses the last ``window`` intervals between points only (the first point carries the
start-up: the linear mode, the first Newton solves), and the time since the last point counts as
part of the recent span, so a slow point lengthens the estimate while it is being computed.  When
the time since the last point exceeds ``stall_factor`` times the recent interval between points,
the recent pace no longer describes the job: no number is given, only how long the job has waited; so too
when the estimate is shorter than the time the current point has already taken.  Measured on the aircraft's mode
11 (39 points in 88 s, tests/test_viewer_eta.py): the pace of the first points said 2 s while points 9 and 10
took 15 and 31 s (the estimate from the average pace said 2-5 s through both waits).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

WINDOW = 6          # intervals between points that set the recent pace
STALL_FACTOR = 3.0  # a wait this many times the recent interval makes the pace unknown


@dataclass(frozen=True)
class TimeLeft:
    """An estimate of a job's remaining time.

    seconds : s, or None when no estimate can be made.  by : the end it is counted to ('energy' or
    'points'), or why there is no number ('too few points', 'stalled').  wait : s since the last point.
    bound : the number is the time to max_points while the energy does not grow (in a tongue, past a fold):
    the job ends then at the latest, at this pace, but sooner if the energy climbs again (a measured case: the
    aircraft's mode 11 in its 5:1 tongue, 'about 5 min' to 500 points at 0.6 s a point, was done in 20 s).
    """

    seconds: float | None
    by: str
    wait: float = 0.0
    bound: bool = False


def time_left(times, energies, now, energy_max, max_points, window=WINDOW, stall_factor=STALL_FACTOR,
              resolution=0.0):
    """Seconds left to whichever end comes first, at the recent points' pace.

    times : s, when each converged point arrived (non-decreasing; several points may share a time when
    they arrive together).  energies : J, each point's energy.  now : s, on the same clock.
    energy_max : J, the job's energy end.  max_points : the job's points end.  window : the number of
    recent intervals that set the pace.  resolution : s, the clock's granularity (the poll interval
    the points are read at): waits shorter than it are never a stall.

    The pace over the recent span [t_(n-1-w), now]: w points and Delta log(max E) in that time.
    Energy end: (log energy_max - log max E) / (Delta log E per s); points end: (max_points - n) /
    (points per s); the smaller.  An energy that has not grown over the span (a fold turning back, a
    tongue at one energy) gives no energy end, only the points end.
    """
    t = np.asarray(times, dtype=float)
    n = t.size
    if n == 0:
        return TimeLeft(None, "too few points")
    wait = max(0.0, float(now) - float(t[-1]))
    if n < 3:
        return TimeLeft(None, "too few points", wait)
    w = min(int(window), n - 1)
    i0 = n - 1 - w
    typical = (t[-1] - t[i0]) / w
    if wait > stall_factor * max(typical, resolution):
        return TimeLeft(None, "stalled", wait)
    span = float(now) - t[i0]
    if span <= 0.0:
        return TimeLeft(None, "too few points", wait)
    left = {}
    if max_points > n:
        left["points"] = (max_points - n) * span / w
    e = np.asarray(energies, dtype=float)[:n]
    logs = np.log(np.maximum.accumulate(np.maximum(e, np.finfo(float).tiny)))
    gained = logs[-1] - logs[i0]
    if energy_max > 0 and gained > 0 and math.isfinite(gained):
        left["energy"] = max(0.0, math.log(energy_max) - logs[-1]) * span / gained
    if not left:
        return TimeLeft(0.0, "points", wait)
    by = min(left, key=left.get)
    if left[by] < wait:                  # less than the current point has already taken: the pace is refuted
        return TimeLeft(None, "stalled", wait)
    return TimeLeft(float(left[by]), by, wait, bound="energy" not in left)
