"""The root of one cubic piece of a spline, for the skeleton's frequency at an energy (skeleton.Skeleton.frequency_at:
its sheets are parametric cubic splines of ln E and f, solved for ln E on the piece that holds it)."""
from __future__ import annotations

import math

__all__ = ["cubic", "cubic_root"]


def cubic(p, s):
    """p[0] s^3 + p[1] s^2 + p[2] s + p[3] (Horner)."""
    return ((p[0] * s + p[1]) * s + p[2]) * s + p[3]


def cubic_root(p, x, h, ga, gb, xtol):
    """The root s in [0, h] of cubic(p, s) = x, given its values minus x at the ends ga, gb of opposite signs:
    Newton's steps kept inside the bracket (a bisection where one would leave it), to within xtol (the bracket or
    the last step).  What scipy's brentq on the spline gave, to its xtol (Skeleton.frequency_at: 18 us against 73)."""
    lo, hi = (0.0, h) if ga < 0 else (h, 0.0)          # cubic - x < 0 at lo, > 0 at hi
    s = h * ga / (ga - gb)                             # the chord's root
    for _ in range(60):
        g = cubic(p, s) - x
        if g == 0.0:
            return s
        if g < 0:
            lo = s
        else:
            hi = s
        dg = (3.0 * p[0] * s + 2.0 * p[1]) * s + p[2]
        step = g / dg if dg != 0.0 else math.inf
        new = s - step
        if not (min(lo, hi) < new < max(lo, hi)):       # outside the bracket (or no slope): bisect
            new = 0.5 * (lo + hi)
        if abs(new - s) <= xtol or abs(hi - lo) <= xtol:
            return new
        s = new
    return s
