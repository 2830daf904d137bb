"""Progress of a sweep: ``SweepProgress`` (branches and points done, per branch) and the reporter that
shows it (a progress bar on stderr, or a user's callable)."""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field

__all__ = ["SweepProgress", "reporter"]


@dataclass
class SweepProgress:
    """State of a running sweep, passed to the ``progress`` callable.

    total : branches in the sweep;  skipped : found in ``out`` (not computed again);
    finished : computed (including failed ones);  failed : finished with status 'failed';
    cancelled : not computed because the sweep was stopped;  points : points of the finished branches;
    running : branch name -> points converged so far, for branches a worker has started;
    workers : branch name -> {"worker": address, "pid": process id} of the worker computing it.
    """

    total: int
    skipped: int = 0
    finished: int = 0
    failed: int = 0
    cancelled: int = 0
    points: int = 0
    running: dict = field(default_factory=dict)
    workers: dict = field(default_factory=dict)
    started: float = field(default_factory=time.perf_counter)

    @property
    def remaining(self):
        return self.total - self.skipped - self.finished - self.cancelled

    @property
    def all_points(self):
        """Converged points so far: finished branches plus running ones."""
        return self.points + sum(self.running.values())

    @property
    def elapsed(self):
        return time.perf_counter() - self.started

    def line(self, width=24):
        done = self.skipped + self.finished + self.cancelled
        f = done / self.total if self.total else 1.0
        bar = "#" * int(width * f) + "-" * (width - int(width * f))
        return (f"[{bar}] {done}/{self.total} branches ({len(self.running)} running, {self.failed} failed"
                f"{f', {self.skipped} in file' if self.skipped else ''}), {self.all_points} points, "
                f"{self.elapsed:.0f} s")


# ---------------------------------------------------------------------- on a worker
def reporter(progress):
    if progress is None or progress is False:
        return lambda state, final=False: None
    if callable(progress):
        return lambda state, final=False: progress(state)

    shown = [""]

    def bar(state, final=False):
        line = state.line()
        if line != shown[0] or final:
            shown[0] = line
            sys.stderr.write("\r" + line + " " + ("\n" if final else ""))
            sys.stderr.flush()
    return bar
