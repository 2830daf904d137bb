"""A converged orbit of the continuation while the branch iterator decides about it (iterator.py).

The public ``Point`` says what the orbit is; what the iterator needs about it meanwhile (the solve for its error
estimate, its harmonic content, the Krein locator's coordinates, the background multipliers) is held here, beside
it, and dropped when the point is kept (``release``): nothing private is hung on the Point.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from ..results.branch import Point

__all__ = ["Candidate"]


@dataclass
class Candidate:
    """A Point and the iterator's working data about it.

    solution : (problem, u, J, tangent, factor) of its converged solve, for its error estimate (None once kept);
    observed : (HarmonicContent, modal orbit Q) for its label and the tongue policy (None once kept);
    restoring : the smallest restoring-force ratio along the orbit (stops.py: the escape test);
    collision : the Krein locator's coordinates at it (stability/krein.py), or None;
    spectrum : the background job computing its multipliers (problem.multipliers_later), or None once settled;
    disc_error : the time discretisation's part of point.freq_error (what finer steps reduce; NaN: none or not
        estimated)."""

    point: Point
    solution: tuple | None = None
    observed: tuple | None = None
    restoring: float = 1.0
    collision: Any = None
    spectrum: Callable | None = None
    disc_error: float = math.nan

    def release(self):
        """Drop the large working data (a solve's Jacobian and factorisation, O(n^2) each, and the orbit)."""
        self.solution = self.observed = self.spectrum = None
