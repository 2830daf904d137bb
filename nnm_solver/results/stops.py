r"""Why a branch stops: the documented stop reasons, escape to a saddle, and closed loops.

Every branch ends with one of these statuses (``Branch.status``), its message naming the cause and,
where there is one, the remedy:

* ``done``        reached energy_max, or the branch returned to low energy (it came back to its start)
* ``max_points``  stopped at max_points (raise it to go on)
* ``escape``      the orbit reached the escape energy of a softening structure: its turning point is
                  within reach of a static equilibrium x* != 0 (a saddle of the potential); above that
                  energy the motion is unbounded and no NNM exists.  Nothing to fix: the family ends
* ``closed_loop`` the continuation came back onto points it had already computed (a loop of the
                  solution set); one lap is kept
* ``tongue``      (``tongues="skip"``) the backbone entered an internal-resonance tongue it could not jump
                  over and reached energy_max or max_points inside it: the backbone's points below it are
                  kept, the message names the k:1 resonance, the partner mode and the entry energy; also a
                  backbone whose continuation cannot go on where its family itself ends in a k:1 resonance
                  (its skeleton ends there too, driver/ends.py): no backbone beyond it
* ``failed``      the corrector could not converge at the smallest step (a singular point, or too
                  coarse a time discretisation: try a larger steps_per_period or tol)
* ``cancelled``   cancelled through ``stop`` / ``Job.cancel``;  ``stopped``: the caller left the
                  iteration (a ``break``)
* ``running``     a snapshot of a job in progress

Escape test.  At the turning point x0 of a reversible orbit (v0 = 0) -- or at any configuration of
the orbit with at least half its largest amplitude -- the restoring force K x + f_nl(x) vanishes only
at an equilibrium.  In modal coordinates its size relative to the linear
force, r = |Omega^2 q0 + Bq^T g(Bq q0)| / |Omega^2 q0|, is 1 for a linear motion and falls to 0 as the
family approaches a saddle (a homoclinic orbit, whose period tends to infinity).  So does the work ratio
q0 . (restoring force) / q0 . Omega^2 q0, which is >= 1 for hardening forces; the larger of the two is used
(the norm ratio alone can be small far from any equilibrium when masses or stiffnesses are decades apart).
r < escape_ratio (1e-2, results/settings.py: RESULTS) stops the branch with status ``escape``; so does a failure of
the continuation where r < escape_ratio_failed (0.1).
"""
from __future__ import annotations

import math

import numpy as np

from ..jit import jit, numba

STOP_STATUSES = ("done", "max_points", "escape", "closed_loop", "tongue", "failed", "cancelled", "stopped", "running")


def restoring_ratio(system, q0):
    """r = |Omega^2 q0 + Bq^T g(Bq q0)| / |Omega^2 q0| at the modal displacement q0 (1: linear, 0: equilibrium).

    q0 may also be (samples, n): the smallest r over those configurations (an orbit that passes near a
    saddle during its period, not only at t = 0)."""
    q = np.atleast_2d(q0)
    lin = q * system.omega2
    res = lin + system.force(q @ system.Bq.T) @ system.Bq
    r = np.linalg.norm(res, axis=1) / np.maximum(np.linalg.norm(lin, axis=1), 1e-300)
    # the work ratio q . res / q . lin (the secant stiffness along q, coordinate-free) vanishes at an
    # equilibrium too, and is >= 1 for hardening forces: the norm ratio alone can be small without one when
    # a small component of a much stiffer mode dominates |lin| (masses or stiffnesses decades apart)
    work = np.maximum(np.einsum("ij,ij->i", q, res), 0.0) / np.maximum(np.einsum("ij,ij->i", q, lin), 1e-300)
    r = np.maximum(r, work)
    big = np.linalg.norm(q, axis=1) >= 0.5 * np.max(np.linalg.norm(q, axis=1))   # not the passages through 0
    return float(np.min(r[big]))


def escape_message(point, ratio):
    return (f"escape at E = {point.energy:.6g} J, f = {point.frequency_hz:.6g} Hz: the orbit's turning point is "
            f"within reach of a static equilibrium (restoring force {ratio:.1e} of the linear one), so the "
            f"softening structure escapes above this energy and the NNM family ends here")


class LoopDetector:
    """Detects a continuation that re-traverses points it has already computed.

    Points are compared in scaled coordinates y = [z / |z|; T / T_r; log |z|], z = [q0; v0 / w_r]
    (the orbit's shape, period and log-amplitude).  A new point re-traverses the path when it lies
    on a segment between two earlier points (not the latest ``skip``), within the segment's own
    chord-to-arc deviation (a quarter of its length times the turn of the polyline there, plus
    ``floor``), moving the same way along it (the two sides of a fold come close to each other but
    are run in opposite directions), and the next point does too.  Half-wave symmetric orbits
    (odd forces) are the same orbit from -x0 as from x0 (shifted by half a period), so both are
    compared: a loop that comes back through the mirrored orbits is caught after one lap.
    """

    def __init__(self, skip=4, floor=1e-4, mirror=True):
        self.skip = skip
        self.floor = floor
        self.mirror = mirror
        self.pending = None
        self._rows = _Rows()           # the points' y and, cached as they come, their segments (O(len y) a point)

    @property
    def Y(self):
        """The points' scaled coordinates y so far (N, 2n + 2)."""
        return self._rows.y()

    def add(self, q0, v0, w_r, T, T_r):
        """Record the next point; returns the index j of the earlier segment (j, j+1) that the
        continuation is re-traversing (confirmed over two points), or None."""
        n = len(q0)
        y = np.empty(2 * n + 2)                 # [z / |z|; T / T_r; log |z|], z = [q0; v0 / w_r], filled in place
        y[:n] = q0
        np.divide(v0, w_r, out=y[n:2 * n])
        z = y[:2 * n]
        nz = max(math.sqrt(float(z.dot(z))), 1e-300)     # (np.linalg.norm's number)
        z /= nz
        y[-2], y[-1] = T / T_r, np.log(nz)
        move = y - self._rows.last() if len(self._rows) else None
        near = self._screen(y)
        hit = self._near_segment(y, move, near)
        if hit is None and self.mirror and move is not None and near is not None:
            # (the mirrored orbit has the same period and amplitude, the last two coordinates: the same screen)
            flip = np.ones(len(y))
            flip[:-2] = -1.0
            hit = self._near_segment(y * flip, move * flip, near)
        self._rows.append(y)
        if hit is None:
            self.pending = None
            return None
        if self.pending is not None and abs(hit - self.pending) <= 3:
            return self.pending
        self.pending = hit
        return None

    def _screen(self, y):
        """The segments whose distance in the last two coordinates (period, log amplitude) from y is within their
        reach, a lower bound of the whole distance: (indices, reach of each), or None when there are none (or too
        few points).  O(m) instead of O(m n): the whole distance only for the segments it leaves in (none on a
        branch whose period or amplitude moves on)."""
        rows = self._rows
        m = len(rows) - self.skip
        if m < 3:
            return None
        ab, L, u, ang = rows.segments(m - 1)                      # segments j -> j+1 of the first m points
        a = rows.y()[:m - 1]
        if numba is not None:           # one compiled pass over the segments (the numpy form's numbers)
            near, reach = _screened(a[:, -2], a[:, -1], ab[:, -2], ab[:, -1], L, ang, float(y[-2]), float(y[-1]),
                                    float(self.floor))
            return (near, reach) if len(near) else None
        turn = np.zeros(len(ab))                                  # turn (rad) of the polyline at each end
        turn[1:] = np.maximum(turn[1:], ang)
        turn[:-1] = np.maximum(turn[:-1], ang)
        reach = 0.25 * L * turn + self.floor
        near = np.flatnonzero(_segment_distance(a[:, -2], a[:, -1], ab[:, -2], ab[:, -1], y[-2], y[-1])
                              <= reach * (1 + 1e-9))
        return (near, reach[near]) if len(near) else None

    def _near_segment(self, y, move, screened):
        """The first segment (index) that y re-traverses moving along ``move``, among those ``screened``
        (``_screen``), or None."""
        if screened is None or move is None:
            return None
        rows = self._rows
        m = len(rows) - self.skip
        near, reach = screened
        ab, L, u, _ = rows.segments(m - 1)
        a = rows.y()[:m - 1]
        a, ab, L, u = a[near], ab[near], L[near], u[near]
        t = np.einsum("ij,ij->i", y - a, ab) / np.maximum(L * L, 1e-300)
        inside = (t > 0.0) & (t < 1.0)
        t = np.clip(t, 0.0, 1.0)
        d = np.linalg.norm(a + t[:, None] * ab - y, axis=1)
        same_way = u @ move >= 0.8 * max(np.linalg.norm(move), 1e-300)
        # the path travelled since the segment must be much longer than the segment: a lap, not a
        # continuation that merely crawls on from the segment's end
        all_L = rows.lengths()
        since = (np.sum(all_L) - np.concatenate([[0.0], np.cumsum(all_L)])[1:m] + np.linalg.norm(y - rows.last()))[near]
        ok = np.flatnonzero((d <= reach) & same_way & inside & (since > 3.0 * L))
        return int(near[ok[0]]) if len(ok) else None


def _segment_distance(ax, ay, bx, by, x, y):
    """Distance (m,) of the point (x, y) in a plane from each segment (ax, ay) -> (ax + bx, ay + by) (m,) each."""
    t = np.clip(((x - ax) * bx + (y - ay) * by) / np.maximum(bx * bx + by * by, 1e-300), 0.0, 1.0)
    return np.hypot(ax + t * bx - x, ay + t * by - y)


@jit
def _nan_max(a, b):
    """np.maximum of two floats (NaN if either is)."""
    if a != a or b != b:
        return np.nan
    return a if a >= b else b


@jit
def _screened(ax, ay, bx, by, L, ang, x, y, floor):
    """LoopDetector._screen's numpy form in one pass over the segments, its operations in its order (the same
    numbers): (near, reach[near]) with the turn of each segment the larger of the angles at its two ends and
    ``_segment_distance``'s distance of (x, y) from it compared with its reach 0.25 L turn + floor."""
    k = L.shape[0]
    near = np.empty(k, dtype=np.int64)
    reach = np.empty(k)
    c = 0
    margin = 1 + 1e-9
    for j in range(k):
        turn = 0.0
        if j >= 1:
            turn = _nan_max(turn, ang[j - 1])
        if j < k - 1:
            turn = _nan_max(turn, ang[j])
        r = 0.25 * L[j] * turn + floor
        den = bx[j] * bx[j] + by[j] * by[j]
        t = ((x - ax[j]) * bx[j] + (y - ay[j]) * by[j]) / _nan_max(den, 1e-300)
        if t != t:
            pass
        elif t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        d = np.hypot(ax[j] + t * bx[j] - x, ay[j] + t * by[j] - y)
        if d <= r * margin:
            near[c] = j
            reach[c] = r
            c += 1
    return near[:c], reach[:c]


class _Rows:
    """The loop detector's points y (rows) in a growing buffer, and per segment j -> j+1 its vector ab, length L
    (and L at least 1e-300, for the divisions), direction u and the turn angle between it and the segment before
    (computed once, when the point comes in: the same numbers as from the whole array at once, row by row)."""

    def __init__(self):
        self._y = self._ab = self._L = self._Lc = self._u = self._ang = None
        self._n = 0

    def __len__(self):
        return self._n

    def y(self):
        return self._y[:self._n] if self._n else np.zeros((0, 0))

    def last(self):
        return self._y[self._n - 1]

    def lengths(self):
        return self._L[:self._n - 1]

    def segments(self, k):
        """(ab, L, u, ang) of the first k segments (ang: the k - 1 angles between consecutive ones)."""
        return self._ab[:k], self._Lc[:k], self._u[:k], self._ang[:k - 1]

    def append(self, y):
        n = self._n
        if self._y is None or n == len(self._y):
            self._grow(max(16, 2 * n), len(y))
        self._y[n] = y
        if n:           # (row by row, the numbers of the whole arrays' np.diff, norm(axis=1), einsum, arccos)
            ab = self._ab[n - 1]
            np.subtract(self._y[n], self._y[n - 1], out=ab)
            L = math.sqrt(float(np.add.reduce(ab * ab)))
            self._L[n - 1] = L
            self._Lc[n - 1] = L = max(L, 1e-300)
            u = self._u[n - 1]
            np.divide(ab, L, out=u)
            if n > 1:
                self._ang[n - 2] = np.arccos(min(max(float(np.einsum("i,i->", u, self._u[n - 2])), -1.0), 1.0))
        self._n = n + 1

    def _grow(self, size, dim):
        def grown(old, shape):
            new = np.zeros(shape)
            if old is not None:
                new[:len(old)] = old
            return new
        self._y = grown(self._y, (size, dim))
        self._ab, self._u = grown(self._ab, (size, dim)), grown(self._u, (size, dim))
        self._L, self._Lc, self._ang = grown(self._L, size), grown(self._Lc, size), grown(self._ang, size)
