"""Whose Floquet multipliers a branch holds, and the width of its ``floquet`` column.

Shooting and harmonic balance in the full modal basis give the model's 2n multipliers.  Harmonic balance in a
Ritz basis (a sparse model above the Ritz threshold, model/ritz.py) solves the Ritz system: r modal coordinates
(the modes below the basis cutoff and the residual-flexibility vectors of the nonlinear elements), and Hill's
method gives that system's 2r multipliers.  Those are the multipliers of the model's modes below the cutoff
(the ones that can exchange energy with the orbit's harmonics) plus one pair per residual vector; the model's
multipliers of the modes above the cutoff are not computed (computing them would need Hill's method on all n
coordinates, 2n (2H + 1) unknowns).  Branch.multipliers_of says which, and a file keeps the column's width.
"""
from __future__ import annotations

import numpy as np

__all__ = ["MULTIPLIER_SYSTEMS", "multipliers_of", "floquet_columns"]

#: 'model': the model's 2n multipliers; 'ritz': the 2r multipliers of the Ritz system harmonic balance solved
MULTIPLIER_SYSTEMS = ("model", "ritz")


def multipliers_of(settings):
    """'ritz' for a branch computed in a Ritz basis (settings.modal_basis == 'ritz'), else 'model'."""
    return "ritz" if getattr(settings, "modal_basis", "full") == "ritz" else "model"


def floquet_columns(floquet, N, n, settings, width=None):
    """The (N, w) complex ``floquet`` column of a branch of N rows on a model of n DOFs: w = 2n (NaN: not computed)
    for the model's multipliers; for a Ritz branch the width of the rows given (2r), or ``width`` when there are
    none.  ValueError (one line) for rows of another width."""
    full = 2 * int(n)
    ritz = multipliers_of(settings) == "ritz"
    if floquet is None:
        return np.full((N, full if width is None else int(width)), np.nan, dtype=complex)
    a = np.asarray(floquet, dtype=complex)
    if a.ndim == 2 and a.shape[0] == N:
        w = a.shape[1]
    elif N:
        w = a.size // N
    else:
        w = full if width is None else int(width)
    if w != full and not (ritz and w > 0 and w % 2 == 0 and w < full):
        what = "a Ritz branch's 2r multipliers (r < n)" if ritz else f"the model's 2n = {full} multipliers"
        raise ValueError(f"the Floquet multipliers have {w} columns per point; expected {what}")
    return a.reshape(N, w)
