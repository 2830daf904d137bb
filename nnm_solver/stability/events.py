r"""Events along a branch located between two converged points, and classified.

Between two consecutive points u_a and u_b of the continuation (u_b reached by a step s along the
tangent p_a of u_a), the branch is parametrised by the pseudo-arclength sigma in [0, s]: u(sigma)
solves F(u) = 0 on the hyperplane (w^2 p_a)^T (u - u_a - sigma p_a) = 0, by the same corrector as the
continuation (continuation.correct).  A scalar test function g(u(sigma)) that changes sign between
the two points is zeroed by the Illinois (regula falsi) method, or by bisection when it is a flag:

* fold         g = dE/ds, the energy's derivative along the local tangent (an energy extremum);
* stability    the stability flag of the non-trivial Floquet multipliers (floquet.py);
* energy_max   g = E - energy_max (the branch ends exactly at the requested energy).

Events are located to a relative energy tolerance of 1e-8 to 5e-7 (locator.event_rtol) (or to a step of 1e-12 in sigma) and
stored with their orbit (x0, v0 in m, m/s; period in s).  A change of stability is classified by the
critical multiplier on its unstable side: ``branch_point`` (a real pair through +1 away from a fold:
pitchfork or transcritical), ``period_doubling`` (through -1), ``torus`` (a complex quadruple leaves
the unit circle: a Krein collision); at an energy fold the stability change is part of the ``fold``
(its key ``stability_change`` is then "loss" or "gain"), also where the +1 crossing lies within the fold
orbit's energy spread of it (harmonic balance: the truncation displaces it; the fold's key ``note`` says so).
"""

from __future__ import annotations

import numpy as np

from ..continuation.engine import CorrectorFailure
from .floquet import instability_kind, real_crossing
from .krein import candidates as krein_candidates
from .krein import locate_collision
from .locator import EVENT_RTOL, Locator
from .settings import STABILITY
from . import settings as _settings         # (the Krein route read at each call: a reference run swaps STABILITY)

__all__ = ["Locator", "classify_multipliers", "EVENT_KINDS", "EVENT_RTOL", "locate_between", "stability_changes",
           "change_detail"]

EVENT_KINDS = ("fold", "branch_point", "period_doubling", "torus")


#: the kind of instability of a multiplier set (floquet.instability_kind)
classify_multipliers = instability_kind


def event_record(kind, index, point, detail, **extra):
    """An event dict: kind, index (first branch point after it), energy J, frequency_hz Hz, period s,
    x0, v0 (lists, m and m/s), detail, located=True, plus ``extra``."""
    rec = dict(kind=kind, index=int(index), energy=float(point.energy), frequency_hz=float(point.frequency_hz),
               period=float(point.period), x0=np.asarray(point.x0, dtype=float).tolist(),
               v0=np.asarray(point.v0, dtype=float).tolist(), detail=detail, located=True)
    rec.update(extra)
    return rec


def locate_between(loc, s, a, b, index, record, energy_max=None):
    """Events between point a (sigma = 0) and point b (sigma = s) of the continuation.

    a, b : (point, slope) with slope = dE/ds at the point; record(sigma) -> Point at sigma.  The multipliers and the
    Krein locator's coordinates known at a step parameter are loc.spectra[sigma] = (multipliers, coordinates).
    energy_max : if the step crosses it upwards, the branch is cut there: returns the located end
    point as well.  Returns (events, end) with end = (sigma, Point) or None.  An event whose
    location fails (the corrector does not converge inside the step) is kept, bracketed by the two
    points (``located`` False, orbit of the nearer point).
    """
    (pa, slope_a), (pb, slope_b) = a, b
    events, end = [], None
    if energy_max is not None and pa.energy < energy_max <= pb.energy:
        target = energy_max * (1 + 2 * STABILITY.event_rtol)    # the end point is at or just above energy_max
        try:
            sig = loc.root(lambda x: loc.energy(x) - target, 0.0, s, pa.energy - target, pb.energy - target)
            end = (sig, record(sig))
            s, pb, slope_b = sig, end[1], loc.slope(sig)
        except CorrectorFailure:
            pass
    fold = None
    if slope_a * slope_b < 0:
        detail = "energy maximum" if slope_a > 0 else "energy minimum"
        try:
            sig = loc.root(loc.slope, 0.0, s, slope_a, slope_b, converged=loc.fold_converged)
            fold = (sig, record(sig))
            events.append(event_record("fold", index, fold[1], detail))
        except CorrectorFailure:
            near = pa if abs(slope_a) < abs(slope_b) else pb
            events.append(event_record("fold", index, near, detail, located=False))
    if not (np.isnan(pa.floquet).any() or np.isnan(pb.floquet).any()) and pa.stable != pb.stable:
        pu = pb if pa.stable else pa      # the bracket's unstable end: its critical multiplier has left the circle
        kind = classify_multipliers(pu.floquet) or "branch_point"
        change = "loss" if pa.stable else "gain"
        ga, gb = real_crossing(pa.floquet), real_crossing(pb.floquet)
        located = True
        if fold is not None and kind == "branch_point" and _changes_at(loc, fold[0], s, pa.stable, pb.stable):
            # at an energy fold a pair of multipliers passes through +1 (the real-crossing test function is flat
            # there, so its own root would be poorly placed): the change is the fold's when the flags on the two
            # sides of the located fold are those of the step's two ends
            events[-1]["stability_change"] = change
            return events, end
        spread = _energy_spread(loc, fold[0]) if fold is not None and kind == "branch_point" else None
        if spread and _within_spread(loc, fold, s, pa.stable, spread):   # (the rule below, not located)
            return _the_folds(events, change, f"the multiplier through +1 crosses within the fold orbit's energy "
                                              f"spread {spread:.3g} J of the fold"), end
        try:
            if kind != "torus" and ga * gb < 0:      # a real pair: a smooth test function, regula falsi
                sig = loc.root(loc.real_crossing, 0.0, s, ga, gb)
            else:                                    # a Krein collision
                # the Krein locator's coordinates at the two ends: kept with their multipliers (loc.spectra)
                rho_a, rho_b = (loc.spectra.get(float(x), (None, None))[1] for x in (0.0, s))
                rho_u = rho_b if pu is pb else rho_a
                if (_settings.STABILITY.krein_route == "local" and rho_u is not None
                        and np.any(np.abs(np.imag(rho_u)) > 1e-9)):
                    lo, hi = locate_collision(loc, 0.0, s, krein_candidates(rho_u),
                                              ends=[(pa.stable, rho_a), (pb.stable, rho_b)])
                else:           # the dense route, or no coordinates (e.g. Hill's method): bisection on the flag
                    lo, hi = loc.bisect(loc.stable, 0.0, s)
                # the bracket's end towards the step's unstable end (its spectrum is known, so the event's point
                # costs no eigenproblem), within the energy tolerance of the flag's change
                sig = max(lo, hi) if pa.stable else min(lo, hi)
            pe = record(sig)
        except CorrectorFailure:
            pe, located = pu, False
        if (located and fold is not None and kind == "branch_point"
                and abs(sig - fold[0]) <= STABILITY.fold_merge * abs(s)):
            # the real-crossing test function is flat at a fold, so its root lands near it, not on it: the fold's
            # (by the distance along the branch, not by energy, which is flat there)
            events[-1]["stability_change"] = change
            return events, end
        if located and spread and abs(pe.energy - fold[1].energy) <= spread:
            # an approximate orbit (harmonic balance) defines its energy only to its spread over the period; a +1
            # crossing closer to the fold than that is the fold's pair, displaced by the truncation (NLvib's beam,
            # example 09, H = 5: 1e-4 relative past its 5:1 tongue's energy maximum, spread 3e-3)
            return _the_folds(events, change, f"the multiplier through +1 located {abs(pe.energy - fold[1].energy):.3g}"
                                              f" J away, within the fold orbit's energy spread {spread:.3g} J"), end
        events.append(event_record(kind, index, pe, change_detail(kind, change, pu.floquet[0]), stability_change=change,
                                   **({} if located else dict(located=False))))
    return events, end


def change_detail(kind, change, critical):
    """The text of a classified stability change (``kind``: branch_point / period_doubling / torus; ``change``: "loss"
    or "gain") quoting ``critical``, the largest multiplier of the step's unstable end: the point after the event
    for a loss of stability, the point before it for a gain (the other end is stable: its multipliers lie on the
    unit circle)."""
    through = {"branch_point": "+1", "period_doubling": "-1", "torus": "a complex pair"}[kind]
    end = "next point" if change == "loss" else "previous point"
    return f"{change} of stability, multiplier through {through} ({end}: {critical:.5g})"


def _energy_spread(loc, sigma):
    """The problem's energy_spread (J) of the orbit at sigma, or None (exact orbits: shooting)."""
    spread = getattr(loc.problem, "energy_spread", None)
    if spread is None:
        return None
    try:
        value = spread(loc.at(sigma)[0])
    except CorrectorFailure:
        return None
    return float(value) if value is not None and np.isfinite(value) and value > 0 else None


def _the_folds(events, change, note):
    """The step's stability change given to its fold (the last event), with a note on why: the events."""
    events[-1]["stability_change"] = change
    events[-1]["note"] = note
    return events


def _within_spread(loc, fold, s, stable_a, spread):
    """Does the step's stability flag (stable at a = sigma 0 for stable_a, else at b = sigma s) change within the fold
    orbit's energy spread (J) of the fold (sigma, point)?  Where the energy has moved from the fold's
    by the spread on each side of it (or at the step's end, if it has not), the flags are those of the step's ends,
    so the change lies between, at energies within the spread (the fold is the step's energy extremum).  Corrector
    points and two multiplier sets: the crossing itself need not be located (~10-20 eigenproblems at a fold, where
    the multiplier 1 is four-fold)."""
    sigma, point = fold
    Ef = point.energy

    def away(end):
        g_end = abs(loc.energy(end) - Ef) - spread
        if g_end <= 0:
            return end
        return loc.root(lambda x: abs(loc.energy(x) - Ef) - spread, sigma, end, -spread, g_end)

    try:
        left, right = away(0.0), away(s)
        return loc.stable(left) == stable_a and loc.stable(right) != stable_a
    except CorrectorFailure:
        return False


def _changes_at(loc, sigma, s, stable_a, stable_b, reach=STABILITY.fold_reach):
    """Does the stability flag change at sigma (within reach x the step s): do points on its two sides within
    that distance (known ones, e.g. the root finder's last iterates, or new ones at that distance) have the
    flags of the step's ends a (sigma = 0) and b (sigma = s)?"""
    delta = reach * abs(s)
    left, right = loc.around(sigma)
    if left is None or sigma - left > delta:
        left = max(sigma - delta, 0.0)
    if right is None or right - sigma > delta:
        right = min(sigma + delta, s)
    try:
        return loc.stable(left) == stable_a and loc.stable(right) == stable_b
    except CorrectorFailure:
        return False


def stability_changes(events):
    """The events where the stability changes (classified bifurcations, and folds where it changes)."""
    return [e for e in events if e.get("stability_change")]
