"""The pseudo-arclength engine as the branch iterator drives it, optionally one point ahead.

The engine (continuation.pseudo_arclength) is a generator of converged points; ``send(REFUSE)`` makes it go back
and halve the step.  The iterator asks for the next point only once the last one is judged (its events located,
for which its Floquet multipliers are needed).  With ``ahead``, the next point is computed while the last one's
multipliers are, in the worker thread (threads.background; a 548-mode eigenproblem takes about as long as a
step).  A refusal of the point before it then restarts the engine at the point before the refused one with half
the refused step, which is what the engine itself does on REFUSE.
"""
from __future__ import annotations

from dataclasses import replace

from .continuation import REFUSE, pseudo_arclength

__all__ = ["EngineDriver"]


class EngineDriver:
    """The engine of one branch: ``next(command)``, ``ahead()``, ``restart(engine)``, ``close()``.

    problem, settings, tol : the engine's (for a restart after a refusal)."""

    def __init__(self, engine, problem, settings, tol):
        self.engine = engine
        self.problem, self.settings, self.tol = problem, settings, tol
        self.pending = None            # ("point", ContinuationPoint) or ("stop", reason): computed ahead
        self.last_step = None          # the step of the last point given out

    def _step(self, command):
        try:
            return "point", (self.engine.send(command) if command else next(self.engine))
        except StopIteration as fin:
            return "stop", fin.value

    def next(self, command=None, before=None):
        """("point", ContinuationPoint) or ("stop", reason).  command : REFUSE the last point given out;
        before : the ContinuationPoint before that one (needed when the engine went on ahead of it)."""
        if self.pending is None:
            out = self._step(command)
        else:
            out, self.pending = self.pending, None
            if command == REFUSE:
                step = max(0.5 * self.last_step, self.settings.step_min)
                self.restart(pseudo_arclength(self.problem, before.u, before.tangent,
                                              replace(self.settings, step=step), self.tol))
                out = self._step(None)                 # the point before again (converged already)
                if out[0] == "point":
                    out = self._step(None)
        if out[0] == "point":
            self.last_step = out[1].step
        return out

    def ahead(self):
        """Compute the engine's next point now (given out by the next ``next()``)."""
        if self.pending is None:
            self.pending = self._step(None)

    def restart(self, engine):
        """Go on with a new engine (a refined time step, a jump over a tongue)."""
        self.engine.close()
        self.engine = engine
        self.pending = None

    def close(self):
        self.engine.close()
        self.pending = None
