"""Background NNM continuation: ``start_branch`` runs ``iter_nnm`` in a thread.

The job streams its converged points into ``job.queue`` (each ``Point`` as it converges, then
``None`` once the job has ended) and keeps them for ``job.points()`` (a Branch snapshot at any time);
it can be cancelled (the points computed so far are kept), and keeps the solver's exception instead
of raising it in the thread.
"""
from __future__ import annotations

import math
import queue
import threading

import numpy as np

from ..results.branch import Branch
from ..threads import blas_limited
from .api import iter_nnm
from ..errors import NNMInputError

__all__ = ["Job", "start_branch"]


class Job:
    """A branch computed in a background thread (create it with ``start_branch``).

    queue : queue.Queue of the Points as they converge, then None when the job has ended.
    settings : the branch's typed method settings.  error : the exception that ended the job, if any.
    """

    def __init__(self, iterator, on_point=None):
        self._it = iterator
        self.model = iterator.model
        self.mode = iterator.mode
        self.energy_max = iterator.energy_max
        self.settings = iterator.settings
        self.queue = queue.Queue()
        self.error = None
        self._on_point = on_point
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._done = threading.Event()
        self._result = None
        self._thread = threading.Thread(target=self._run, name=f"nnm-mode-{self.mode}", daemon=True)

    def _run(self):
        it = self._it
        try:
            with blas_limited():        # one region for the whole run: the BLAS limit changes at its start and end
                self._iterate(it)       # only, not around each point while other threads may be in BLAS
        except BaseException as exc:  # kept for the caller; the thread must not die loudly
            self.error = exc
        finally:
            self._done.set()
            self.queue.put(None)

    def _iterate(self, it):
        while not self._stop.is_set():
            with self._lock:
                try:
                    point = next(it)
                except StopIteration:
                    break
            self.queue.put(point)
            if self._on_point is not None:
                self._on_point(point)
        with self._lock:
            it.cancel()
            self._result = it.branch()

    # ------------------------------------------------------------------ public
    @property
    def done(self):
        """True once the computation has finished, failed or been cancelled."""
        return self._done.is_set()

    @property
    def progress(self):
        """Fraction 0..1 of the way in log(energy) from the first point to energy_max: 1 once the computation has
        ended by itself (done, or a stop rule: max_points, escape, tongue, ...); a cancelled or failed one keeps the
        fraction it reached (a cancelled job reported 1)."""
        if self.done and self.error is None and self._result is not None and self._result.status != "cancelled":
            return 1.0
        pts = list(self._it.points)
        if not pts:
            return 0.0
        e0 = pts[0].energy
        emax = max(p.energy for p in pts)
        if emax <= e0 or self.energy_max <= e0:
            return 0.0
        return float(np.clip(math.log(emax / e0) / math.log(self.energy_max / e0), 0.0, 1.0))

    def latest(self):
        """(number of points converged so far, the last one's energy in J, its frequency in Hz), NaN before the
        first: what a progress line shows, without the Branch snapshot of ``points()`` (which copies every point's
        state: on the unreduced 64,446-DOF aircraft 87 ms a call, 11.6 s of CPU over nnm-solve's 133 polls of a
        36-point branch, 2026-12-07)."""
        pts = self._it.points
        count = len(pts)
        if not count:
            return 0, math.nan, math.nan
        last = pts[count - 1]
        return count, float(last.energy), float(last.frequency_hz)

    def rows(self, start=0):
        """[(energy J, frequency Hz)] of the points converged so far from index ``start`` (0-based) on: a progress
        log's lines, without the Branch snapshot of ``points()``."""
        return [(float(p.energy), float(p.frequency_hz)) for p in list(self._it.points)[start:]]

    def points(self):
        """Branch snapshot of the points converged so far (status 'running' while running)."""
        if self.done and self._result is not None:
            return self._result
        pts = list(self._it.points)
        status = "running" if not self.done else ("failed" if self.error else "cancelled")
        return Branch.from_points(self.model, self.mode, pts, settings=self.settings, status=status,
                                  message="" if self.error is None else str(self.error))

    def cancel(self):
        """Ask the computation to stop after the current point; the points are kept."""
        self._stop.set()

    def result(self, timeout=None):
        """Wait for the Branch (raises TimeoutError, or the solver's error if it failed)."""
        if not self._done.wait(timeout):
            raise TimeoutError(f"the branch of mode {self.mode} is still running")
        if self.error is not None:
            raise self.error
        return self._result


def start_branch(model, mode, energy_max, on_point=None, **kwargs):
    """Start the branch ``continue_nnm(model, mode, energy_max, **kwargs)`` in a background thread.

    Returns a Job at once.  on_point : optional callable(Point), called in the job's thread after each
    converged point (as in continue_nnm; the job's thread runs in one BLAS-limited region, threads.blas_limited).  Arguments are checked before the thread starts, so bad input
    raises NNMInputError here.  Use ``job.cancel()`` instead of continue_nnm's ``stop``.
    """
    if "stop" in kwargs:
        raise NNMInputError("start_branch manages stopping itself; use job.cancel()")
    method = kwargs.pop("method", "shooting")
    job = Job(iter_nnm(model, mode, energy_max, method, **kwargs), on_point)
    job._thread.start()
    return job
