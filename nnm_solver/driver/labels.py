r"""Point labels from the dynamics: on the backbone family, or in a k:1 internal-resonance tongue.

A fixed share of a higher harmonic cannot tell the two apart: a family whose third harmonic grows
gradually (a smooth 3:1 mixing, fundamental share 0.6-0.9) is still the backbone, and a tongue locked in
frequency can hold a small share.  What tells them apart is the frequency: inside a tongue the orbit's
frequency locks to the partner's (f ~ f_p / k) while the backbone family's goes on moving with the
energy.  The family's frequency at each energy is the skeleton's (skeleton.py: harmonic balance
condensed onto the elements, stepped in modal amplitude, which steps over narrow tongues).  So a point
at energy E with frequency f is measured by

    dev = | f / f_skeleton(E) - (1 + bias sum_k w_k k^p) |,

bias being the branch's own offset from the exact linear frequency at the linear mode (the skeleton is
exact there: Newmark's period error, 8e-5 at 200 steps a period; zero for harmonic balance), which grows
for the orbit's harmonic k as k^p for an integrator of order p (w_k: the harmonics' shares of the orbit's
kinetic energy, (k a_k)^2 normalised), and labelled

* ``"tongue k:1"`` when dev > OFF_FAMILY (off the family, whatever the harmonic share), or when dev >
  ON_FAMILY and either the strongest harmonic k >= 2 carries RESONANCE_FRACTION of the amplitude or the
  point's fundamental share is SHARE_DROP below the family's at the same energy (the frequency leaves the
  family while a partner takes a share the family does not have: a tongue's entrance; the thresholds
  widened by twice the skeleton's estimated truncation error at that energy, skeleton.py);
* ``"backbone"`` otherwise (on the family, whatever the share);
* ``"tongue k:1"`` above the family's energy maximum (a softening family's saddle: no backbone there), and
  above the energy where the family ends in a k:1 resonance (the skeleton ended ``locked`` or ``stuck``:
  the branch's orbits there are that resonance's, e.g. the frequency locked while the energy grows; ``"tongue
  1:1"`` where another mode took the fundamental over).

Where no skeleton covers the energy (no nonlinear elements, beyond its end) the harmonic share alone
decides (tongue_skip.harmonic_label).
"""
from __future__ import annotations

import math

import numpy as np

from ..analysis.harmonics import RESONANCE_FRACTION
from .tongue_skip import FOLD_CONTENT, fundamental_share

__all__ = ["FamilyLabels", "OFF_FAMILY", "ON_FAMILY", "SHARE_DROP"]

#: relative frequency distance from the family beyond which a point is in a tongue
OFF_FAMILY = 1e-3

#: relative frequency distance within which a point with a strong higher harmonic is still on the family
ON_FAMILY = 1e-4


#: a point whose fundamental share is this far below the family's (and dev > ON_FAMILY) is in a tongue
SHARE_DROP = 0.02

#: below this harmonic fraction and relative frequency shift from the linear mode a point is backbone
#: without asking the skeleton (the linear regime)
LINEAR_REGIME = 1e-3


def _order(k, fraction):
    """The order of the tongue a point off the family is in: its strongest harmonic k >= 2, or 1 (a 1:1
    resonance, another mode at the fundamental) when no harmonic k >= 2 is present (below FOLD_CONTENT: a
    single-harmonic balance, or round-off)."""
    return max(k, 2) if fraction >= FOLD_CONTENT else 1


class FamilyLabels:
    """Labels a branch's points against its skeleton.  skeleton : a callable returning the Skeleton (or
    None), called the first time a point leaves the linear regime; f_linear : the followed linear mode's
    frequency (Hz); f_method : the same as the branch's method computes it (Newmark's, at its time step)."""

    def __init__(self, skeleton, f_linear, f_method=None, order=0):
        self._skeleton = skeleton
        self.f_linear = float(f_linear)
        self._bias = 0.0 if f_method is None else float(f_method) / self.f_linear - 1.0
        self.order = int(order)

    def bias(self, amps=None):
        """The method's relative frequency offset for an orbit of harmonic amplitudes ``amps`` (module docstring)."""
        if amps is None or not self._bias or len(amps) < 2:
            return self._bias
        k = np.arange(len(amps), dtype=float)
        w = (k * np.asarray(amps)) ** 2
        return self._bias * float(np.sum(w * k ** self.order) / max(np.sum(w), 1e-300))

    @staticmethod
    def _share_drop(sk, energy, amps):
        """How far the point's fundamental share is below the family's at its energy (0 when unknown)."""
        if amps is None:
            return 0.0
        drop = sk.share_at(energy) - fundamental_share(amps)
        return drop if math.isfinite(drop) else 0.0

    def deviation(self, energy, frequency_hz, amps=None):
        """dev (module docstring) of a point, or None when no skeleton covers its energy."""
        sk = self._skeleton() if self._skeleton is not None else None
        if sk is None or not sk.covers(energy):
            return None
        return abs(frequency_hz / sk.frequency_at(energy) - 1.0 - self.bias(amps))

    def label(self, energy, frequency_hz, content_label, k, fraction, amps=None):
        """(label, dev): the point's label (module docstring) from its energy (J), frequency (Hz) and harmonic
        content (harmonic_label's label, strongest harmonic k >= 2 and its fraction, the harmonics' amplitudes)."""
        shift = frequency_hz / self.f_linear - 1.0
        if fraction < LINEAR_REGIME and abs(shift - self._bias) < LINEAR_REGIME:
            return content_label, None
        sk = self._skeleton() if self._skeleton is not None else None
        if sk is not None and sk.energy_peak is not None and energy > sk.energy_peak:
            return f"tongue {_order(k, fraction)}:1", math.inf      # above the family's energy maximum: no backbone

        if sk is not None and sk.end in ("stuck", "locked") and len(sk.energy) and energy > sk.energy[-1]:
            # beyond where the family passes into (or stops at) a k:1 resonance: what the branch finds there is
            # that resonance's tongue, not the backbone family (its skeleton does not go on)
            k_end = sk.partner[0] if sk.partner[1] else _order(k, fraction)    # 1:1 with a named partner mode
            return f"tongue {k_end}:1", math.inf
        dev = self.deviation(energy, frequency_hz, amps)
        if dev is None or not math.isfinite(dev):
            return content_label, None
        if dev <= ON_FAMILY:           # on the family whatever the widening below (it only raises the thresholds)
            return "backbone", dev
        # the skeleton's own truncation error widens both thresholds (a solve per skeleton point: asked only here)
        err = sk.truncation_at(energy)
        err = 2 * err if math.isfinite(err) else 0.0
        if dev > OFF_FAMILY + err or (dev > ON_FAMILY + err and (
                fraction >= RESONANCE_FRACTION or self._share_drop(sk, energy, amps) > SHARE_DROP)):
            return f"tongue {_order(k, fraction)}:1", dev
        return "backbone", dev
