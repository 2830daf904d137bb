"""Background NNM continuation: ``start_branch`` runs ``continue_nnm`` in a thread.

The job streams its converged points (``job.points()`` is a Branch snapshot at any time), can be
cancelled (the points computed so far are kept), and keeps the solver's exception instead of
raising it in the thread.
"""
from __future__ import annotations

import math
import threading

import numpy as np

from .branch import Branch
from .errors import NNMInputError
from .nnm_continuation import continue_nnm


class Job:
    """A branch computed in a background thread (create it with ``start_branch``)."""

    def __init__(self, model, mode, energy_max, kwargs, runner=continue_nnm):
        self.model = model
        self.mode = mode
        self.energy_max = float(energy_max)
        self._lock = threading.Lock()
        self._rows = []
        self._stop = threading.Event()
        self._done = threading.Event()
        self._result = None
        self.error = None
        self._kwargs = kwargs
        self._runner = runner
        self._thread = threading.Thread(target=self._run, name=f"nnm-mode-{mode}", daemon=True)

    def _on_point(self, row):
        with self._lock:
            self._rows.append(row)

    def _run(self):
        try:
            self._result = self._runner(self.model, self.mode, self.energy_max, on_point=self._on_point,
                                        stop=self._stop, **self._kwargs)
        except BaseException as exc:  # kept for the caller; the thread must not die loudly
            self.error = exc
        finally:
            self._done.set()

    # ------------------------------------------------------------------ public
    @property
    def done(self):
        """True once the computation has finished, failed or been cancelled."""
        return self._done.is_set()

    @property
    def progress(self):
        """Fraction 0..1 of the way in log(energy) from the first point to energy_max."""
        if self.done and self.error is None:
            return 1.0
        with self._lock:
            if not self._rows:
                return 0.0
            e0 = self._rows[0]["energy"]
            emax = max(r["energy"] for r in self._rows)
        if emax <= e0 or self.energy_max <= e0:
            return 0.0
        return float(np.clip(math.log(emax / e0) / math.log(self.energy_max / e0), 0.0, 1.0))

    def points(self):
        """Branch snapshot of the points converged so far (status 'running' while running)."""
        if self.done and self._result is not None:
            return self._result
        with self._lock:
            rows = list(self._rows)
        n = self.model.n
        N = len(rows)

        def col(key, shape=None, dtype=float):
            a = np.array([r[key] for r in rows], dtype=dtype)
            return a.reshape((N,) + shape) if shape else a.reshape(N)

        return Branch(self.model, self.mode, col("energy"), col("frequency_hz"), col("period"),
                      col("x0", (n,)), col("v0", (n,)),
                      col("floquet", (2 * n,), complex) if N else np.zeros((0, 2 * n), complex),
                      col("stable", dtype=bool),
                      status="running" if not self.done else ("failed" if self.error else "cancelled"),
                      message="" if self.error is None else str(self.error),
                      settings=dict(self._kwargs))

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


def start_branch(model, mode, energy_max, **kwargs):
    """Start ``continue_nnm(model, mode, energy_max, **kwargs)`` in a background thread; returns a Job.

    Arguments are checked before the thread starts, so bad input raises NNMInputError here.
    """
    if "on_point" in kwargs or "stop" in kwargs:
        raise NNMInputError("start_branch manages on_point and stop itself; use job.points() and job.cancel()")
    # validate now, in the caller's thread (cheap): the same checks continue_nnm does
    from .model import Model
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    model.check_mode(mode)
    if not isinstance(energy_max, (int, float, np.number)) or not energy_max > 0 or not np.isfinite(energy_max):
        raise NNMInputError(f"energy_max must be a positive number, got {energy_max!r}")
    job = Job(model, mode, energy_max, kwargs)
    job._thread.start()
    return job
