r"""Point labels from the dynamics: on the backbone family, or in a k:1 internal-resonance tongue.

A fixed share of a higher harmonic cannot tell the two apart: a family whose third harmonic grows gradually (a
smooth 3:1 mixing) is still the backbone, and a tongue locked in frequency can hold a small share.  What tells them
apart is the frequency: inside a tongue the orbit's frequency locks to the partner's (f ~ f_p / k) while the
backbone family's goes on moving with the energy.  The family's frequency at each energy is the skeleton's
(skeleton.py: harmonic balance condensed onto the elements, stepped in modal amplitude, which steps over narrow
tongues).  A point at energy E (J) with frequency f (Hz) is measured by

    dev = | f / f_skeleton(E) - 1 - bias |,

bias being the branch's own offset from the exact linear frequency at the linear mode (the skeleton is exact there;
Newmark's period error grows for the orbit's harmonic k as k^p for an integrator of order p: bias = b0 sum_k w_k
k^p, w_k the harmonics' shares of the orbit's kinetic energy), b0 = f_method / f_linear - 1 at the point's own time
step (point.steps: the freq_tol refinement raises the steps along a branch, and |b0| falls as steps^-p with them:
Newmark's -3.3e-4 at 100 steps a period, -2.5e-5 at 364), and it is on the family when

    dev <= on_family + 2 (its own estimated error) + 2 (the skeleton's truncation estimate at E),

where a point in doubt (dev above the first two terms) is measured against the skeleton's own orbit at its energy
(its interpolated orbit corrected on the energy level set: no interpolation error; where that does not converge
onto the family, the interpolated frequency, with no widening),

so that a label is a claim within the accuracy the two computations say they have (beyond the first three terms, where
only the skeleton's truncation widens it, its fundamental share must also lie within share_drop of
the skeleton's: a partner taking a share the family does not have is a tongue's entrance), and its frequency is not
locked: since the kept points of its run (no jump between) where the family's frequency moved by at least
lock_window (the skeleton's secant slope, labels.Verdict), its own moved by at least lock_ratio of that.  Inside a
tongue the frequency locks to the partner's (k f = f_p) while the energy grows: on the aircraft's mode 20 between
3 and 5 J such plateaus (f constant to 1e-5 over 10-15 % in energy, where the family moves 0.3-0.5 %) lie within the
skeleton's own truncation estimate there (4e-3), so the distance alone cannot tell them.  Otherwise it is labelled
``"tongue k:1"``, k the harmonic the partner modes carry most (content.py), unless that one is forced far from
resonance and another meets its partner's frequency averaged along the orbit (content.tongue_partner).  The largest one can be a harmonic the family carries anyway: a clamped beam's mode 3 carries NNM 1's
third harmonic everywhere, and its 9:1 tongue with mode 5 was labelled 3:1.  Above the family's energy maximum (a
softening family's saddle) or above where the family ends in a k:1 resonance (the skeleton ended ``locked`` or
``stuck``) every point is off the family (dev = inf).  Where no skeleton covers the energy (no nonlinear elements,
below the skeleton's first point) the harmonic content alone decides (dev None).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .content import tongue_partner
from .settings import LabelSettings

__all__ = ["Verdict", "FamilyLabels"]


@dataclass(frozen=True)
class Verdict:
    """A point's label: text ('backbone' or 'tongue k:1'), dev (relative frequency distance from the family; None
    where not measured, inf beyond the family's end), tolerance (the dev below which it is on the family),
    on_family, and order (the k of 'tongue k:1'; 0 on the family)."""

    text: str
    dev: float | None = None
    tolerance: float = 0.0
    beyond_end: bool = False
    order: int = 0

    @property
    def on_family(self):
        return self.text == "backbone"


class FamilyLabels:
    """Labels a branch's points against its skeleton (module docstring).  skeleton : the Skeleton or None;
    f_linear : the followed linear mode's frequency (Hz); f_method : the same as the branch's method computes it,
    either a function of the time steps per period returning it (Hz; shooting: 1 / the integrator's discrete linear
    period at that step, so that each point is measured at its own, point.steps) or one frequency (Hz: a method
    without time step; None: f_linear, no offset); order : the integrator's order (0: no time step).  The ``steps``
    of offset, bias, deviation and verdict are a point's time steps per period (point.steps; 0: a method without
    time step, with one frequency f_method)."""

    def __init__(self, skeleton, f_linear, f_method=None, order=0, settings=LabelSettings()):
        self.skeleton = skeleton
        self.settings = settings
        self.f_linear = float(f_linear)
        self.f_method = f_method
        self.order = int(order)

    def offset(self, steps=0):
        """b0: the method's relative offset from the exact linear frequency at the linear mode, f_method / f_linear
        - 1, with ``steps`` time steps per period (0: one frequency f_method for every point)."""
        f = self.f_method
        if f is None:
            return 0.0
        return float(f(steps) if callable(f) else f) / self.f_linear - 1.0

    def bias(self, amps=None, steps=0):
        """The method's relative frequency offset for an orbit of harmonic amplitudes ``amps`` computed with
        ``steps`` time steps per period (the module docstring's b0 sum_k w_k k^p)."""
        b0 = self.offset(steps)
        if amps is None or not b0 or len(amps) < 2:
            return b0
        k = np.arange(len(amps), dtype=float)
        w = (k * np.asarray(amps)) ** 2
        return b0 * float(np.sum(w * k ** self.order) / max(np.sum(w), 1e-300))

    def deviation(self, energy, frequency_hz, amps=None, steps=0):
        """dev of a point (computed with ``steps`` time steps per period), or None when no skeleton covers its
        energy."""
        sk = self.skeleton
        if sk is None or not sk.covers(energy):
            return None
        return abs(frequency_hz / sk.frequency_at(energy) - 1.0 - self.bias(amps, steps))

    def locked(self, energy, frequency_hz, run):
        """Is the frequency locked (module docstring)?  run : (energy J, frequency Hz) of the kept points since the
        last jump, oldest first."""
        s, sk = self.settings, self.skeleton
        if not run or not sk.covers(energy):
            return False
        lnE, b = math.log(energy), sk.log_frequency(energy)        # (sk.slope(E0, energy)'s numbers, b once)
        for E0, f0 in reversed(run):
            if not sk.covers(E0) or E0 == energy:
                return False
            slope = float((b - sk.log_frequency(E0)) / (lnE - math.log(E0)))
            if not math.isfinite(slope):
                return False
            expected = slope * math.log(energy / E0)
            if abs(expected) >= s.lock_window:
                return abs(math.log(frequency_hz / f0)) < s.lock_ratio * abs(expected)
        return False

    def verdict(self, energy, frequency_hz, content, error=0.0, run=(), reference_hz=None, falling=False, steps=0):
        """The Verdict of a point of energy (J), frequency (Hz), Content (content.py) and estimated relative
        frequency error (NaN or inf: unknown or not resolved, taken as 0; the branch's freq_error says it); run : the kept points of its run
        (``locked``); reference_hz : the frequency of the skeleton's own orbit at that energy (a jump's landing),
        instead of its interpolated one; falling : its energy is below the branch's point before it (the backbone
        continued in energy has no fold: past one the branch is off the family, e.g. in a 1:1 resonance); steps :
        the time steps per period it was computed with (point.steps; the bias is the method's at that step)."""
        s, sk = self.settings, self.skeleton
        shift = frequency_hz / self.f_linear - 1.0
        if content.fraction < s.linear_regime and abs(shift - self.offset(steps)) < s.linear_regime and (
                sk is None or not len(sk.energy) or energy <= sk.energy[-1]):
            return self._by_content(content)
        if sk is None:
            return self._by_content(content)
        if sk.energy_peak is not None and energy > sk.energy_peak:
            k = content.order                                        # above the family's energy maximum
            return Verdict(f"tongue {k}:1", math.inf, beyond_end=True, order=k)
        if sk.end in ("stuck", "locked") and len(sk.energy) and energy > sk.energy[-1]:
            # beyond where the family passes into (or stops at) a k:1 resonance: its orbits there are that
            # resonance's, not the backbone family's
            k_end = sk.partner[0] if sk.partner[1] else content.order
            return Verdict(f"tongue {k_end}:1", math.inf, beyond_end=True, order=k_end)
        dev = self.deviation(energy, frequency_hz, content.amplitudes, steps)
        if dev is None or not math.isfinite(dev):
            return self._by_content(content)
        err = error if math.isfinite(error) else 0.0
        strict = s.on_family + 2 * err
        if reference_hz is None and dev > strict:
            # in doubt: against the skeleton's own orbit at that energy (no interpolation error)
            reference_hz = sk.frequency_of_orbit(energy)
            if not math.isfinite(reference_hz):
                reference_hz = None            # no own orbit of the family there: the interpolated frequency, strictly
        if reference_hz is not None:           # the skeleton's own orbit at that energy (a jump's landing, or above)
            dev = abs(frequency_hz / reference_hz - 1.0 - self.bias(content.amplitudes, steps))
        trunc = sk.truncation_at(energy) if dev > strict else 0.0   # a solve per skeleton point: asked here only
        tol = strict + 2 * (trunc if math.isfinite(trunc) else 0.0)
        drop = sk.share_at(energy) - content.share if content.amplitudes is not None else 0.0
        on = (dev <= strict or (dev <= tol and not drop > s.share_drop)) and not falling and not (
            run and self.locked(energy, frequency_hz, run))
        if on:
            return Verdict("backbone", dev, tol)
        k = self.tongue_order(frequency_hz, content)
        return Verdict(f"tongue {k}:1", dev, tol, order=k)

    def tongue_order(self, frequency_hz, content):
        """The k of the k:1 tongue a point of frequency (Hz) and Content off the family is in: content.order, the
        harmonic the partners carry most, unless content.tongue_partner (on the skeleton's modal system) names
        another."""
        sk = self.skeleton
        s = self.settings
        found = (tongue_partner(content, frequency_hz, sk.problem.sys, s.partner_share, s.partner_mismatch,
                                s.partner_match) if sk is not None and content.orbit is not None else None)
        return found[0] if found is not None else content.order

    @staticmethod
    def _by_content(content):
        """The Verdict where no skeleton says more: the content label (content.py)."""
        return Verdict(content.label, order=content.k if content.label != "backbone" else 0)
