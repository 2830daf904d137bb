"""Background NNM computations: start a solver job, stream its points into the shared
state, keep the points on Stop, and report solver errors without stopping the server."""
from __future__ import annotations

import math
import queue
import threading
import time
from dataclasses import dataclass

import nnm_solver
from nnm_solver.cli.defaults import solver_defaults

from .eta import TimeLeft
from .eta import time_left as estimate_time_left



def one_line(exc):
    """A one-line message for an exception (solver errors are one line already)."""
    text = str(exc).strip().splitlines()
    msg = text[0] if text else ""
    if isinstance(exc, ValueError):
        return msg or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def duration_text(seconds):
    """'42 s', '3 min 05 s', '1 h 02 min'."""
    s = max(0, int(round(float(seconds))))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {(s % 3600) // 60:02d} min"


@dataclass
class JobProgress:
    """How far a job is: ``points`` converged of at most ``max_points``, ``energy_fraction`` (0..1,
    the solver's ``Job.progress``: the way in log energy from the first point to energy_max) and
    ``elapsed`` seconds since Start.  A branch ends at max_points or at energy_max, whichever comes
    first, so the progress is the further of the two fractions.  ``left``: the time left at the
    recent points' pace (``eta.time_left``; no number before three points or while a point takes
    much longer than the recent ones)."""

    points: int
    max_points: int
    energy_fraction: float
    elapsed: float
    done: bool = False
    left: TimeLeft = TimeLeft(None, "too few points")

    @property
    def points_fraction(self):
        return min(1.0, self.points / self.max_points) if self.max_points > 0 else 0.0

    @property
    def fraction(self):
        return 1.0 if self.done else max(self.points_fraction, float(min(max(self.energy_fraction, 0.0), 1.0)))

    @property
    def by(self):
        """Which measure gives the progress: 'points' or 'energy'."""
        return "points" if self.points_fraction >= self.energy_fraction else "energy"

    @property
    def rate_per_min(self):
        """Points per minute since Start (None before the first point)."""
        return 60.0 * self.points / self.elapsed if self.points and self.elapsed > 0 else None

    @property
    def eta(self):
        """Seconds left at the recent points' pace, to whichever end comes first (max_points or
        energy_max); None when no estimate can be made (done, too few points, a stall)."""
        return None if self.done else self.left.seconds

    def text(self):
        """One line: progress and the measure it is by, elapsed time, rate and time left (or, with no
        estimate, how long the job has waited for its next point)."""
        parts = [f"{self.points} of at most {self.max_points} points",
                 f"{100 * self.fraction:.0f} % (by energy)" if self.by == "energy" else
                 f"{100 * self.fraction:.0f} % (by {self.by}; by energy {100 * self.energy_fraction:.0f} %)",
                 f"elapsed {duration_text(self.elapsed)}"]
        if self.rate_per_min is not None:
            parts.append(f"{self.rate_per_min:.3g} points/min")
        eta = self.eta
        if eta is not None and self.left.by == "points":
            parts.append(f"at most {self.max_points - self.points} more points, about {duration_text(eta)} at the "
                         f"recent pace" + ("" if not self.left.bound else " (the energy is not growing)"))
        elif eta is not None:
            parts.append(f"about {duration_text(eta)} left at the recent pace")
        elif not self.done and self.left.by == "stalled":
            parts.append(f"no new point for {duration_text(self.left.wait)}: time left unknown")
        return " · ".join(parts)


class JobRunner:
    """Runs ``nnm_solver.start_branch`` on the file's model with every k3 x ``k3_factor``
    and streams points into a new entry of ``shared``.

    The job puts each converged ``Point`` in ``job.queue`` (then None once it has ended); the
    runner drains the queue into its own Branch (``Branch.extend``; ``_extend``: a harmonic-balance job's raised
    harmonics) and gives the entry a
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
        self.max_points = int(options.get("max_points") or solver_defaults()["max_points"])
        self.t_start = None          # time.monotonic() at Start
        self.t_end = None            # ... when the job ended
        self._arrivals = []          # s after Start, when each point was received
        self._energy = 0.0           # the job's energy fraction, last read while it ran
        self.thread = None
        self.finished = threading.Event()

    def start(self):
        """Start the job; raises the solver's one-line errors for bad arguments at once, and
        state.JobBusy if another job is running.  The job slot of ``shared`` is claimed first, atomically
        (``SharedState.claim_job``), and released if the solver refuses to start."""
        self._claimed = True              # running from now on: another tab's Start sees it at once
        try:
            self.shared.claim_job(self)
        except Exception:                 # JobBusy: this runner never runs
            self.finished.set()
            raise
        try:
            model = self.shared.model
            if abs(self.k3_factor - 1.0) > 1e-12:
                model = model.scaled(self.k3_factor)
            start = self._start or nnm_solver.start_branch
            self.t_start = time.monotonic()
            self.job = start(model, mode=self.mode, energy_max=self.energy_max, **self.options)
            self.branch = nnm_solver.Branch.from_points(model, self.mode, [], settings=self.job.settings,
                                                        status="running")
            self.entry = self.shared.add(self._snapshot(), k3_factor=self.k3_factor, source="running",
                                         saved=False)
        except BaseException:
            self.finished.set()
            self.shared.release_job(self)
            self.shared.notify("progress")
            raise
        if self.cancelled:                # Stop pressed while the solver was starting
            self.job.cancel()
        self.shared.set_progress(0.0, self.status_text())
        self.thread = threading.Thread(target=self._run, name=f"nnm-job-mode{self.mode}", daemon=True)
        self.thread.start()
        return self

    @property
    def name(self):
        """The branch's name in the lists ('NNM 2 (out-of-phase mode)')."""
        return self.entry.label.split(" [")[0] if self.entry is not None else f"NNM {self.mode}"

    def progress(self):
        """JobProgress now (frozen once the job has ended: a cancelled solver job reports 1)."""
        if self.t_end is None and self.job is not None and not self.cancelled:
            try:
                energy = float(getattr(self.job, "progress", 0.0) or 0.0)
            except (TypeError, ValueError):
                energy = 0.0
            self._energy = energy if math.isfinite(energy) else self._energy
        energy = self._energy
        end = self.t_end if self.t_end is not None else time.monotonic()
        n = 0 if self.branch is None else len(self.branch)
        t0 = self.t_start or end
        left = TimeLeft(None, "too few points")
        if n and self.t_end is None:
            left = estimate_time_left(self._arrivals[:n], self.branch.energy[:n], end - t0, self.energy_max,
                                      self.max_points, resolution=self.poll)
        return JobProgress(points=n, max_points=self.max_points, energy_fraction=energy,
                           elapsed=end - t0, left=left)

    def status_text(self, p=None, ended=""):
        """Markdown of the Compute tab's job line."""
        p = p or self.progress()
        head = f"**{self.name}** up to {self.energy_max:.3g} J"
        if ended:
            rate = f" ({p.rate_per_min:.3g} points/min)" if p.rate_per_min is not None else ""
            return f"{head}: {p.points} points in {duration_text(p.elapsed)}{rate}, {ended}"
        return f"{head}  \n{p.text()}"

    def _extend(self, points):
        """Append ``points`` to the rows received so far.  A harmonic-balance job that raises its harmonics (its
        accuracy target) sends its next points with more Fourier coefficients than the earlier ones, and
        re-expresses its own earlier points in the larger basis (their higher harmonics zero); ``Branch.extend``
        cannot join the two (the job failed with 'all the input array dimensions ... must match'): the rows are then
        the job's own snapshot (``job.points()``, the same orbits in one basis), as many as were received."""
        shapes = {None if p.coefficients is None else p.coefficients.shape for p in points}
        if self.branch.coefficients is not None and len(self.branch):
            shapes.add(self.branch.coefficients.shape[1:])
        if len(shapes) == 1:
            self.branch.extend(points)
            return
        received = len(self.branch) + len(points)
        snap = self.job.points()               # the job's points are in its newest basis
        if len(snap) < received:
            raise RuntimeError(f"the job's snapshot has {len(snap)} points, {received} were received")
        self.branch = snap.subset(slice(0, received))

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
                    self._extend(points)
                    self._arrivals.extend([time.monotonic() - self.t_start] * len(points))
                    self.shared.update(self.entry, branch=self._snapshot())
                p = self.progress()
                self.shared.set_progress(p.fraction, self.status_text(p))
            self._finish()
        except Exception as exc:  # never let the thread die silently
            self.t_end = self.t_end or time.monotonic()
            self.shared.update(self.entry, source="failed", status=one_line(exc))
            self.shared.set_error(f"solver job failed: {one_line(exc)}")
        finally:
            self.shared.release_job(self)
            self.shared.notify("progress")
            self.finished.set()

    def _failed(self, err):
        """Keep the points received before the solver error ``err``, and show it."""
        snap = self._snapshot()
        snap.status, snap.message = "failed", one_line(err)
        self.shared.update(self.entry, branch=snap, source="failed", status=one_line(err))
        return snap

    def _finish(self):
        self.t_end = time.monotonic()
        err = getattr(self.job, "error", None)
        if err is not None:
            snap = self._failed(err)
            self.shared.set_progress(self.shared.progress, self.status_text(ended="failed"))
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
        p = self.progress()
        self.shared.set_progress(p.fraction if cancelled else 1.0,
                                 self.status_text(p, ended=("stopped" if cancelled else "done")
                                                  + (f" ({message})" if message else "")))

    cancelled = False

    def cancel(self):
        """Ask the solver to stop; the points computed so far are kept."""
        self.cancelled = True
        if self.job is not None:
            self.job.cancel()

    _claimed = False

    @property
    def running(self):
        """From Start (the job slot claimed, the solver maybe still starting) until the job has ended."""
        return self._claimed and not self.finished.is_set()
