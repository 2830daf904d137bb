"""Positions along a branch: the fractional point index s where a branch's energy equals a target (the viewer's
energy slider), and values interpolated at s (linear in energy, as ``Branch.interpolate``)."""
from __future__ import annotations

import numpy as np

__all__ = ["energy_to_s", "interp_at", "energy_at"]


def energy_to_s(energy, target, s_current=0.0):
    """Fractional index along a branch where its energy equals ``target`` (J).

    Energies need not be monotonic (folds, tongues): among all crossings of the level
    the one nearest to ``s_current`` wins, so a slider never jumps to a far part of the
    branch.  Interpolation is linear in energy, as ``Branch.interpolate`` makes it (the
    interpolated orbit's energy is the linear interpolation of its neighbours'), so the orbit
    shown at the returned index has energy ``target``.  Outside the range: nearest end.
    """
    e = np.asarray(energy, dtype=float)
    if len(e) <= 1:
        return 0.0
    y = float(target)
    lo, hi = e[:-1], e[1:]
    inside = (np.minimum(lo, hi) <= y) & (y <= np.maximum(lo, hi))
    cands = []
    for i in np.flatnonzero(inside):
        d = hi[i] - lo[i]
        cands.append(i + (0.0 if d == 0 else (y - lo[i]) / d))
    if not cands:
        # out of range: the nearest point in log energy (ties broken by distance in s)
        dist = np.abs(np.log10(np.maximum(e, 1e-300)) - np.log10(max(y, 1e-300)))
        best = np.flatnonzero(dist <= dist.min() + 1e-12)
        return float(best[np.argmin(np.abs(best - s_current))])
    cands = np.array(cands)
    return float(cands[np.argmin(np.abs(cands - s_current))])


def interp_at(values, s):
    """Linear interpolation of values (N,) at fractional index s."""
    values = np.asarray(values, dtype=float)
    if len(values) == 1:
        return float(values[0])
    i = int(np.clip(np.floor(s), 0, len(values) - 2))
    a = float(s) - i
    return float((1 - a) * values[i] + a * values[i + 1])


def energy_at(energy, s):
    """Energy (J) of the orbit shown at fractional index s of a branch whose points have energies
    ``energy`` (J): linear in energy between neighbouring points, the energy ``Branch.interpolate``
    gives the interpolated orbit (it rescales the interpolated initial state to it).  Every place
    of the viewer that prints or plots the selection's energy uses this, so that the readout, the
    selection text, the FEP marker and the Point tab agree."""
    return interp_at(energy, s)
