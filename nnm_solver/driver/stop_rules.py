r"""When a branch's iteration ends, decided after each point and on a failed continuation (the statuses are
results/stops.py's).

Each rule is a small function returning a ``Stop`` (status, message) or None (go on); the iterator
(driver/iterator.py) applies it.  After a kept point, in this order: the restoring-force ratio r at its turning point
below ``RESULTS.escape_ratio`` (the orbit reaches a saddle of the potential: ``escape``), energy_max reached or a jump
that landed at it (``done``), max_points (``max_points``), a branch that started at low energy and came back below
half its first point's energy (``done``).  On a failed continuation: ``escape`` where r < ``escape_ratio_failed``
(the continuation stalls next to the saddle), else ``failed`` naming the last point (1-based) and the reason
(the backbone policy's "the family ends here" is asked first by the iterator).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..results.settings import RESULTS
from ..results.stops import escape_message, restoring_ratio


@dataclass(frozen=True)
class Stop:
    """The end of a branch's iteration: its status (results/stops.py STOP_STATUSES) and message."""

    status: str
    message: str


def turning_ratio(system, w_r, q0, v0):
    """Restoring-force ratio (results/stops.py) at the orbit's turning point, the modal state (q0, v0) at t = 0 of
    the mode of linear angular frequency w_r (rad/s); 1 when t = 0 is not a turning point (|v0| above 1e-6 w_r |q0|)."""
    if np.linalg.norm(v0) > 1e-6 * w_r * np.linalg.norm(q0):
        return 1.0
    return restoring_ratio(system, q0)


def stop_after_point(points, ratio, energy_max, max_points, landed, start_is_low, note=lambda points: ""):
    """The Stop after the newest of ``points`` (its restoring ratio ``ratio``), or None to go on.  ``landed``: the
    branch was cut exactly at energy_max; ``note(points)``: the backbone policy's words on reaching it (where the
    last points are off the family; called only then)."""
    point, n = points[-1], len(points)
    E, E0 = point.energy, points[0].energy
    if ratio < RESULTS.escape_ratio:
        return Stop("escape", escape_message(point, ratio))
    if E >= energy_max or landed:
        return Stop("done", f"reached energy_max = {energy_max:g} J" + note(points))
    if n >= max_points:
        return Stop("max_points", f"stopped at max_points = {max_points} (energy {E:.4g} J); raise max_points to go on")
    if n > 3 and E < 0.5 * E0 and start_is_low:
        return Stop("done", "the branch returned to low energy")
    return None


def closed_loop(points, n_new, loop):
    """The Stop of a continuation that came back onto its points ``loop``..``loop`` + 1 (0-based) from point n_new."""
    p = points[loop]
    return Stop("closed_loop", f"closed loop: from point {n_new - 1} on the continuation re-traverses points "
                               f"{loop}..{loop + 1} (E = {p.energy:.6g} J, f = {p.frequency_hz:.6g} Hz); one lap is kept")


def stop_on_failure(points, ratio, reason):
    """The Stop of a continuation that could not go on after ``points`` (the last one's restoring ratio ``ratio``):
    ``escape`` next to a saddle, else ``failed`` (the points so far are kept)."""
    if points and ratio < RESULTS.escape_ratio_failed:
        return Stop("escape", escape_message(points[-1], ratio) + f" (the continuation could not go further: {reason})")
    where = (f"after point {len(points)} (E = {points[-1].energy:.4g} J, f = {points[-1].frequency_hz:.5g} Hz)"
             if points else "at the start")
    return Stop("failed", f"no convergence {where}: {reason or 'continuation stopped'}; the points so far are kept "
                          f"(try a larger steps_per_period or tol, or the branch ends here)")
