r"""The backbone's skeleton: the NNM family by single-harmonic balance, condensed onto the elements.

With the fundamental harmonic only (H = 1) the harmonic-balance equations hold no internal resonance
(a k:1 resonance needs the k-th harmonic), so their branch from the linear mode is a smooth curve in
energy: the backbone without its tongues.  Condensed onto the nonlinear elements
(orbits/condensed_hb.py) it costs n_s + 2 unknowns a point whatever the model size, so it is computed
alongside a branch, up to well beyond the branch's energy_max.

Where the full branch (any method, any number of harmonics) enters a k:1 tongue with a partner mode of
frequency f_p, the resonance band is where k f(E) crosses f_p; the skeleton says at which energies the
family has left that band (``targets``), and its orbit there (``orbit_at``) is the first guess from which
the branch's own method finds the backbone beyond the tongue (tongue_skip.py).  Where the skeleton turns
back in energy (a softening family approaching a saddle: the single-harmonic family's energy maximum),
there is no backbone at higher energy (``energy_peak``).

The skeleton is a guide, not the answer: its frequencies differ from the branch's by the truncation to
one harmonic (for the Paris-like aircraft's mode 20: 1e-4 at 1 J, 0.25 % at 12 J).
"""
from __future__ import annotations

import math
import threading
import weakref

import numpy as np

__all__ = ["Skeleton", "skeleton"]

#: the skeleton is computed up to this multiple of the branch's energy_max
REACH = 10.0

#: the skeleton is at a k:1 band where k f is within this relative distance of the partner's frequency
ENTRY_BAND = 0.01

#: harmonics of the family's orbit refined from the skeleton before the branch's own method corrects it
FAMILY_HARMONICS = 9

_cache = weakref.WeakKeyDictionary()
_lock = threading.Lock()


class Skeleton:
    """The single-harmonic backbone of one mode: energies E (J, rising), frequencies f (Hz), initial
    displacements x0 (m) of its orbits (at rest at t = 0), from a condensed HB Branch ``branch``.

    energy_peak : the skeleton's largest energy when it turned back (a family that ends: no backbone above
    it), else None.
    """

    def __init__(self, branch):
        E, f = np.asarray(branch.energy), np.asarray(branch.frequency_hz)
        rising = np.flatnonzero(np.diff(E) <= 0)
        end = int(rising[0]) + 1 if len(rising) else len(E)
        self.energy_peak = float(E[end - 1]) if end < len(E) or branch.status == "escape" else None
        self.energy, self.frequency_hz = E[:end], f[:end]
        self.x0 = np.asarray(branch.x0[:end])
        self.branch = branch
        self.status, self.message = branch.status, branch.message

    def frequency_at(self, E):
        """Skeleton frequency (Hz) at energy E (J), interpolated in log E; NaN outside its range."""
        if len(self.energy) < 2 or not self.energy[0] <= E <= self.energy[-1]:
            return float("nan")
        return float(np.interp(math.log(E), np.log(self.energy), self.frequency_hz))

    def orbit_at(self, E):
        """(x0 (m, at rest), T (s)) of the skeleton orbit at energy E, or None outside its range."""
        if len(self.energy) < 2 or not self.energy[0] <= E <= self.energy[-1]:
            return None
        x = np.log(self.energy)
        j = int(np.clip(np.searchsorted(x, math.log(E)) - 1, 0, len(x) - 2))
        t = (math.log(E) - x[j]) / (x[j + 1] - x[j])
        return (1 - t) * self.x0[j] + t * self.x0[j + 1], 1.0 / self.frequency_at(E)

    def family_orbit(self, system, E, settings, tol, harmonics=FAMILY_HARMONICS):
        """(problem, u): the orbit of the family at energy E (J) with ``harmonics`` (condensed HB on ``system``,
        the branch's modal system), corrected on the energy level set from the skeleton's orbit there (its
        fundamental); None where that does not converge.  A first guess for the branch's own method, close
        to it by the truncation of the higher harmonics only."""
        from ..orbits.condensed_hb import CondensedHBProblem
        from ..orbits.hb_basis import HBBasis
        from .tongue_skip import level_set
        start = self.orbit_at(E)
        if start is None:
            return None
        x0, T = start
        kind = "odd" if system.elements.odd else "full"
        prob = CondensedHBProblem(system, self.branch.mode - 1, HBBasis(harmonics, kind))
        q0 = system.to_modal(x0)
        u, _ = level_set(prob, prob.from_state(q0, np.zeros_like(q0), T), settings, min(tol, 1e-9))
        return None if u is None else (prob, u)

    def targets(self, E_entry, k, f_partner, margins=(0.003, 0.01, 0.03, 0.1)):
        """Energies (J) above E_entry where the skeleton's k f crosses and leaves the k:1 band around f_partner
        (Hz, the partner's linear frequency) by the relative ``margins``, on the side the family moves to;
        [] when the skeleton does not cross it above E_entry."""
        E, f = self.energy, self.frequency_hz
        above = E > E_entry
        if k < 2 or not np.any(above) or not f_partner > 0:
            return []
        kf = k * f[above] / f_partner - 1.0                 # relative distance of k f from the partner
        side = np.sign(kf[-1])
        at_entry = k * self.frequency_at(E_entry) / f_partner - 1.0
        if np.all(np.sign(kf) == side) and not abs(at_entry) < ENTRY_BAND:
            # the skeleton neither crosses the band nor enters it where the branch did: the partner's frequency has moved with the amplitude (a
            # strongly nonlinear partner, e.g. the 2-DOF benchmark's) and the linear one says nothing; the
            # tongue is traversed or jumped by rescaled backbone orbits (tongue_skip.py)
            return []
        out = []
        for m in margins:
            past = np.flatnonzero((np.sign(kf) == side) & (np.abs(kf) >= m))
            if len(past):
                E_t = float(E[above][past[0]])
                if not out or E_t > out[-1] * (1 + 1e-6):
                    out.append(E_t)
        return out


def skeleton(model, mode, energy_max, compute):
    """The Skeleton of linear mode ``mode`` (1-based) of ``model`` up to REACH x energy_max (J), cached per
    model and mode (a cached one that reaches far enough is reused).  compute(model, mode, E) returns the
    condensed single-harmonic HB Branch to E (the driver's continue_nnm; driver/api.py)."""
    with _lock:
        for (m, reach), sk in _cache.get(model, {}).items():
            if m == mode and (reach >= REACH * energy_max or sk.energy_peak is not None):
                return sk
    sk = Skeleton(compute(model, mode, REACH * energy_max))
    with _lock:
        _cache.setdefault(model, {})[(mode, REACH * energy_max)] = sk
    return sk
