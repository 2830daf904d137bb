r"""Natural-parameter continuation: the solutions of F(u; lambda) = 0 at given values lambda_1, lambda_2, ... of a
parameter in turn, each corrected at its fixed value from a prediction off the solution at the one before (e.g. a
forced response's force ramped up to its full value, driver/forced_points.py).  Unlike the arclength (engine.py) it
cannot pass a fold in lambda: it is for parameters along which the solution is known to stay regular (a ramp from a
linear regime), and it stops at the first value whose correction fails.

The corrector is the caller's ``solve(u, value) -> (u, converged)``, typically continuation/newton.py on the problem
with its parameter set to ``value``; the predictor ``predict(u, value_from, value_to) -> u_guess`` (default: the
last solution itself).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

__all__ = ["natural_parameter", "NaturalResult"]


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
