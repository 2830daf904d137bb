"""Background NNM computations: start a solver job, stream its points into the shared
state, keep the points on Stop, and report solver errors without stopping the server."""
from __future__ import annotations

import queue
import threading

import nnm_solver


def one_line(exc):
    """A one-line message for an exception (solver errors are one line already)."""
    text = str(exc).strip().splitlines()
    msg = text[0] if text else ""
    if isinstance(exc, ValueError):
        return msg or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


class JobRunner:
    """Runs ``nnm_solver.start_branch`` on the file's model with every k3 x ``k3_factor``
    and streams points into a new entry of ``shared``.

    The job puts each converged ``Point`` in ``job.queue`` (then None once it has ended); the
    runner drains the queue into its own Branch (``Branch.extend``) and gives the entry a
    snapshot of the rows so far (``subset``: views of the columns, no copy; ``extend`` replaces
    the columns, so the draw threads never see a half-extended branch).  At the end the entry
    gets ``job.result()``, the final Branch with its status, message and events.

    start : the function starting the job (default ``nnm_solver.start_branch``; tests may
    pass another with the same contract).  poll : seconds between progress updates.
    """

    def __init__(self, shared, mode, energy_max, k3_factor=1.0, start=None, poll=0.25, **options):
        self.shared = shared
        self.mode = int(mode)
        self.energy_max = float(energy_max)
        self.k3_factor = float(k3_factor)
        self.options = options
        self.poll = poll
        self._start = start
        self.entry = None
        self.job = None
        self.branch = None           # the rows received so far (extended in place)
        self.thread = None
        self.finished = threading.Event()

    def start(self):
        """Start the job; raises the solver's one-line errors for bad arguments at once."""
        model = self.shared.model
        if abs(self.k3_factor - 1.0) > 1e-12:
            model = model.scaled(self.k3_factor)
        start = self._start or nnm_solver.start_branch
        self.job = start(model, mode=self.mode, energy_max=self.energy_max, **self.options)
        self.branch = nnm_solver.Branch.from_points(model, self.mode, [], settings=self.job.settings,
                                                    status="running")
        self.entry = self.shared.add(self._snapshot(), k3_factor=self.k3_factor, source="running", saved=False)
        with self.shared.lock:
            self.shared.job = self
            self.shared.error = ""
        self.shared.set_progress(0.0, f"computing NNM {self.mode} up to {self.energy_max:.3g} J ...")
        self.thread = threading.Thread(target=self._run, name=f"nnm-job-mode{self.mode}", daemon=True)
        self.thread.start()
        return self

    def _snapshot(self):
        """The rows received so far, as a Branch of its own (no copy of the columns)."""
        return self.branch.subset(slice(None))

    def _drain(self):
        """Points queued by the job (waiting up to ``poll`` s for the first); (points, ended)."""
        points = []
        try:
            item = self.job.queue.get(timeout=self.poll)
            while item is not None:
                points.append(item)
                item = self.job.queue.get_nowait()
        except queue.Empty:
            return points, False
        return points, True

    def _run(self):
        try:
            ended = False
            while not ended:
                points, ended = self._drain()
                if points:
                    self.branch.extend(points)
                    self.shared.update(self.entry, branch=self._snapshot())
                self.shared.set_progress(float(getattr(self.job, "progress", 0.0) or 0.0),
                                         f"NNM {self.mode}: {len(self.branch)} points")
            self._finish()
        except Exception as exc:  # never let the thread die silently
            self.shared.update(self.entry, source="failed", status=one_line(exc))
            self.shared.set_error(f"solver job failed: {one_line(exc)}")
        finally:
            with self.shared.lock:
                if self.shared.job is self:
                    self.shared.job = None
            self.shared.notify("progress")
            self.finished.set()

    def _failed(self, err):
        """Keep the points received before the solver error ``err``, and show it."""
        snap = self._snapshot()
        snap.status, snap.message = "failed", one_line(err)
        self.shared.update(self.entry, branch=snap, source="failed", status=one_line(err))
        return snap

    def _finish(self):
        err = getattr(self.job, "error", None)
        if err is not None:
            snap = self._failed(err)
            self.shared.set_progress(self.shared.progress, f"NNM {self.mode}: failed after {len(snap)} points")
            self.shared.set_error(f"solver error: {one_line(err)} ({len(snap)} points kept)")
            return
        try:
            branch = self.job.result(timeout=5.0)
        except Exception as exc:
            snap = self._failed(exc)
            self.shared.set_error(f"solver error: {one_line(exc)} ({len(snap)} points kept)")
            return
        cancelled = self.cancelled
        status = getattr(branch, "status", "") or ""
        message = getattr(branch, "message", "") or ""
        self.shared.update(self.entry, branch=branch, source="stopped" if cancelled else "computed",
                           status=f"{status}: {message}".strip(": "))
        self.shared.set_progress(1.0 if not cancelled else self.shared.progress,
                                 f"NNM {self.mode}: {len(branch)} points, "
                                 f"{'stopped' if cancelled else 'done'}" + (f" ({message})" if message else ""))

    cancelled = False

    def cancel(self):
        """Ask the solver to stop; the points computed so far are kept."""
        self.cancelled = True
        if self.job is not None:
            self.job.cancel()

    @property
    def running(self):
        return self.thread is not None and not self.finished.is_set()
