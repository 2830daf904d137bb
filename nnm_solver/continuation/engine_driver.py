"""The pseudo-arclength engine as the branch iterator drives it, optionally some points ahead.

The engine (continuation.pseudo_arclength) is a generator of converged points; ``send(REFUSE)`` makes it go back
and halve the step.  The iterator judges a point (its events located, for which its Floquet multipliers are
needed) before it takes the next.  With ``ahead``, the driver computes the next ``ahead_points`` (1) meanwhile, and
each point's multipliers are started in the worker threads as soon as the engine gives it (``launch``: the
problem's state is then that point's; a 548-mode eigenproblem takes about as long as a step, so the two cores
share the work).  A refusal of a point the engine has gone beyond restarts the engine at the point before the
refused one with half the refused step, which is what the engine itself does on REFUSE.
"""
from __future__ import annotations

from collections import deque
from dataclasses import replace

from .engine import REFUSE, pseudo_arclength

__all__ = ["EngineDriver"]

class EngineDriver:
    """The engine of one branch: ``next(command, before)``, ``ahead()``, ``restart(engine)``, ``close()``.

    problem, settings, tol : the engine's (for a restart after a refusal).  launch : optional callable(cp) run on
    each point as the engine gives it, its result kept as ``cp.spectrum`` (the multipliers started in the
    background, problem.multipliers_later).  ahead_points : points computed ahead of the one being judged (1: the
    multipliers of the next point run in the background while the engine steps; a point computed ahead is lost when
    the one judged is refused, jumped from or refined: the aircraft's NNM 19 skipping its tongues to 200 J computed
    50 engine points for 36 kept with 2 ahead, 43 with 1, the same branch, 13.8 -> 11.9 s CPU, 2026-12-07)."""

    def __init__(self, engine, problem, settings, tol, launch=None, ahead_points=1):
        self.engine = engine
        self.ahead_points = int(ahead_points)
        self.problem, self.settings, self.tol = problem, settings, tol
        self.launch = launch
        self.pending = deque()         # ("point", ContinuationPoint) or ("stop", reason): computed ahead
        self.last_step = None          # the step of the last point given out

    def _step(self, command):
        try:
            cp = self.engine.send(command) if command else next(self.engine)
        except StopIteration as fin:
            return "stop", fin.value
        if self.launch is not None:
            cp.spectrum = self.launch(cp)
        return "point", cp

    def next(self, command=None, before=None):
        """("point", ContinuationPoint) or ("stop", reason).  command : REFUSE the last point given out;
        before : the ContinuationPoint before that one (needed when the engine went on beyond it)."""
        if not self.pending:
            out = self._step(command)
        elif command == REFUSE:
            step = max(0.5 * self.last_step, self.settings.step_min)
            self.restart(pseudo_arclength(self.problem, before.u, before.tangent, replace(self.settings, step=step),
                                          self.tol))
            launch, self.launch = self.launch, None
            out = self._step(None)                 # the point before again (converged already; no spectrum)
            self.launch = launch
            if out[0] == "point":
                out = self._step(None)
        else:
            out = self.pending.popleft()
        if out[0] == "point":
            self.last_step = out[1].step
        return out

    def ahead(self, points=None):
        """Compute the engine's next points now, up to ``points`` (default self.ahead_points; given out by the next
        calls of ``next``)."""
        points = self.ahead_points if points is None else points
        while len(self.pending) < points and not (self.pending and self.pending[-1][0] == "stop"):
            self.pending.append(self._step(None))

    def restart(self, engine):
        """Go on with a new engine (a refined time step, a jump over a tongue, a refusal)."""
        self.close()
        self.engine = engine

    def close(self):
        """Close the engine; the multipliers of the points computed ahead are dropped if not started."""
        self.engine.close()
        for kind, cp in self.pending:
            if kind == "point" and hasattr(getattr(cp, "spectrum", None), "cancel"):
                cp.spectrum.cancel()
        self.pending.clear()
