"""Point numbers as users read them: 1-based, in every text, slider and event of the viewer (issue 53,
finding 3).  Inside, a position along a branch is a fractional 0-based row index ``s`` (row i is point
i + 1); these functions are the only place where one becomes the other."""
from __future__ import annotations

import math

__all__ = ["point_number", "point_words", "slider_value", "along_from_slider", "nearest_row"]


def point_number(along):
    """The 1-based number of position ``along`` (0-based, fractional): '7' on computed point 7 (row 6),
    '7.40' between points 7 and 8."""
    x = float(along) + 1.0
    r = round(x)
    return str(int(r)) if math.isclose(x, r, abs_tol=5e-3) else f"{x:.2f}"


def point_words(along, n=None):
    """'point 7 of 21' (``n`` points), 'point 7.40 of 21' between two computed points; 'point 7' without n."""
    return f"point {point_number(along)}" + (f" of {int(n)}" if n is not None else "")


def slider_value(along):
    """The Along-branch slider's value at position ``along``: the point's 1-based number."""
    return float(along) + 1.0


def along_from_slider(value):
    """The 0-based position of the Along-branch slider's ``value`` (a 1-based point number)."""
    return max(float(value) - 1.0, 0.0)


def nearest_row(along, n):
    """The computed row (0-based) nearest to position ``along`` of a branch of ``n`` points, by the rule of
    ``Branch.interpolate`` (whose stability, multipliers and label are the nearer neighbour's): between rows j and
    j + 1 the upper one from half way on (weight >= 0.5), not Python's round (half to even: round(70.5) == 70).
    The one nearest-point rule of the viewer's texts and orbits; ``along`` is clipped to 0..n-1."""
    n = int(n)
    if n <= 1:
        return 0
    s = min(max(float(along), 0.0), float(n - 1))
    j = min(int(math.floor(s)), n - 2)
    return j + 1 if s - j >= 0.5 else j
