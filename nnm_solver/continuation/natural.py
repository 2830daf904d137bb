r"""Natural-parameter continuation in the logarithm of a parameter: the stepping of the backbone's skeleton in the
followed mode's modal amplitude (backbone/amplitude_family.py), of its one-harmonic guide and of a sheet followed
down to where it begins (backbone/family_guide.py).

The solutions of F(u; p) = 0 are followed in p by steps of a ratio p_{i+1} / p_i, each from the secant predictor in
ln p through the last two solutions (from the last one alone at the first step, or after a restart), corrected by
Newton's method at the fixed p (continuation/newton.py, through the caller's ``solve``).  The step control is the
ratio's: halved towards 1 on a refusal down to ``ratio_min``, grown by a factor the caller measures (at most
``grow_max``) on acceptance, within ``[ratio_min, cap]``.  What counts as a refusal (no solution, a frequency that
jumps, a point off a trend) and what the points mean are the caller's decisions; the stepping is here, once.

Pseudo-arclength continuation, for paths that fold in p, is engine.py.

``natural_parameter`` is the plain form: the solutions at a given list of values in turn (e.g. a forced response's
force ramped up to its full value, driver/forced_points.py), each corrected from a prediction off the one before; it
stops at the first value whose correction fails.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

__all__ = ["LogSteps", "LogStepper", "natural_parameter", "NaturalResult"]


@dataclass(frozen=True)
class LogSteps:
    """Step control of LogStepper: ratio the first ratio p_{i+1} / p_i (> 1 up, < 1 down); ratio_min, ratio_max the
    smallest and largest (for steps up; for steps down their inverses); grow_max the largest growth of ratio - 1 at
    one acceptance; clamp: a halving never goes below ratio_min (else the last halving may, once: the skeleton's
    stepping, whose family ends are placed by that last, shortest trial)."""

    ratio: float
    ratio_min: float
    ratio_max: float
    grow_max: float = 2.0
    clamp: bool = True


class LogStepper:
    """Natural-parameter continuation in ln p of the solutions u of F(u; p) = 0 (module docstring).

    solve(p, guess) -> u or None: the corrector at the fixed parameter p (the caller puts p into the unknowns).
    ``trial(points)`` gives (p, u or None) one step past the last of ``points`` [(p_i, u_i), ...];
    ``shorter()`` halves the step after a refusal (False when it is already the smallest: the caller decides what
    then); ``accept(growth, cap)`` sets the next step after an accepted point; ``restart(ratio)`` steps on from a
    point that is not the secant's continuation of the one before (e.g. another sheet of the family)."""

    def __init__(self, solve, steps, scaled_first=None):
        self._solve = solve
        self.steps = steps
        self.ratio = steps.ratio
        self._fresh = False              # True after a restart, until the next accepted point
        self._scaled = scaled_first      # slice of u scaled with p at a first step (amplitudes ~ p), or None

    def predict(self, points, p):
        """The secant predictor at p through the last two points in ln p (the last point alone, scaled with p where
        ``scaled_first`` says, at a first step or after a restart)."""
        p0, u0 = points[-1]
        if len(points) > 1 and not self._fresh:
            p1, u1 = points[-2]
            return u0 + (u0 - u1) * (math.log(p / p0) / math.log(p0 / p1))
        guess = np.array(u0, dtype=float)
        if self._scaled is not None:
            guess[self._scaled] *= p / p0
        return guess

    def trial(self, points):
        """(p, solution or None) at p = p_last * ratio."""
        p = points[-1][0] * self.ratio
        return p, self._solve(p, self.predict(points, p))

    def solve_at(self, points, p):
        """(solution or None) at a given p beyond the last point, from the predictor (no change of the step)."""
        return self._solve(p, self.predict(points, p))

    def shorter(self):
        """Halve the step (ratio - 1 halved, not below ratio_min with clamp) after a refusal; False when it is at
        ratio_min or below already."""
        s = self.steps
        if abs(math.log(self.ratio)) <= abs(math.log(s.ratio_min)):
            return False
        self.ratio = 1 + (self.ratio - 1) / 2
        if s.clamp and abs(math.log(self.ratio)) < abs(math.log(s.ratio_min)):
            self.ratio = s.ratio_min
        return True

    def accept(self, growth, cap=None):
        """After an accepted point: ratio - 1 grown by ``growth`` (at most grow_max), within [ratio_min, cap]
        (cap: ratio_max unless given)."""
        s = self.steps
        cap = s.ratio_max if cap is None else cap
        self.ratio = max(s.ratio_min, min(cap, 1 + (self.ratio - 1) * min(s.grow_max, growth)))
        self._fresh = False

    def restart(self, ratio=None):
        """Step on from the last point alone (no secant through the one before) with ``ratio`` (default: as is)."""
        if ratio is not None:
            self.ratio = ratio
        self._fresh = True


@dataclass(frozen=True)
class NaturalResult:
    """u : the solution at the last value reached (None if not even the first converged); reached : how many of the
    values were solved, in order; completed : all of them."""

    u: Optional[np.ndarray]
    reached: int
    completed: bool


def natural_parameter(solve: Callable, u, values, predict: Optional[Callable] = None) -> NaturalResult:
    """The solutions at ``values`` in turn (module docstring), from the first guess u at values[0]."""
    values = list(values)
    guess, done = u, None
    for i, value in enumerate(values):
        if i > 0:
            guess = predict(done, values[i - 1], value) if predict is not None else done
        sol, ok = solve(guess, value)
        if not ok:
            return NaturalResult(done, i, False)
        done = sol
    return NaturalResult(done, len(values), True)
