"""Skip mode (``tongues="skip"``): the branch follows the backbone family across internal-resonance tongues.

A mixin of the branch iterator (iterator.NNMIterator; attributes used: points, tongues, status, energy_max,
max_points, _tongue, _last_backbone, _problem, _system, _cs, _tol, _skeleton, _labels, _engine, _prev,
_refusals, _finish).  A point that leaves the backbone (tongue_skip.leaves_backbone) is hidden while the
tongue it entered is jumped over (tongue_skip.TongueSkipper, from the skeleton's orbits beyond the band or by
rescaled backbone orbits) or traversed unseen until the backbone resumes above its entry; a departure at the
family's own energy maximum with no partner harmonic ends the branch ``escape`` (ends.escape_at_peak), one where
its skeleton ends in a 1:1 resonance ends it ``tongue`` (ends.family_end), a tongue
re-entered MAX_STALLS times from the same orbit or one the continuation cannot leave ends it ``tongue``.
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.engine import pseudo_arclength
from .ends import PEAK_CONTENT, escape_at_peak, escape_below_peak, inside_tongue, resonance
from .tongue_skip import (TongueSkipper, harmonic_content, harmonic_label, leaves_backbone, same_tongue,
                          tongue_record, upward_tangent)

#: a tongue re-entered MAX_STALLS times from the same backbone energy (to STALL_RTOL) ends the branch
MAX_STALLS = 3
STALL_RTOL = 1e-9

__all__ = ["SkipMode", "MAX_STALLS", "STALL_RTOL"]


class SkipMode:
    """The skip mode's departures, jumps and traversals, for NNMIterator."""

    def _hidden(self, cp, point):
        """Skip mode: True if ``point`` is not a backbone point to return (the continuation jumped over
        a tongue, or is traversing one it could not jump over)."""
        t = self._tongue
        if t is not None:                       # traversing a tongue: back on the backbone above its entry?
            rising = point.energy > t["last_energy"]
            t["last_energy"] = point.energy
            trend_ok = (point.frequency_hz - t["entry_frequency_hz"]) * t["trend"] >= -1e-4 * t["entry_frequency_hz"]
            if rising and trend_ok and point.energy > t["entry_energy"] and not leaves_backbone(point, t["backbone"]):
                t.update(exit_energy=point.energy, exit_frequency_hz=point.frequency_hz)
                self._tongue = None
                self._prev = None              # no event is located across the tongue
                return False
            t["hidden_points"] += 1
            if point.energy >= self.energy_max or t["hidden_points"] >= self.max_points:
                self._inside_tongue(t, point)
                raise StopIteration
            return True
        if self._last_backbone is None or not leaves_backbone(point, self._last_backbone[1]):
            return False
        bpoint = self._last_backbone[1]
        sk = self._skeleton() if self._skeleton is not None else None
        fraction = harmonic_content(point)[1]
        at_peak = escape_at_peak(sk, bpoint, point, fraction)
        if at_peak is not None:                # the family's own fold at its energy maximum: no tongue to jump
            self._finish("escape", at_peak)
            raise StopIteration
        if (sk is not None and sk.partner[0] == 1 and sk.partner[1] and fraction < PEAK_CONTENT
                and self._family_ends("it turns back in energy with no harmonic k >= 2, into the 1:1 "
                                      "resonance")):
            raise StopIteration                # the family ends in a 1:1 resonance there: no tongue to jump over
        trend = np.sign(bpoint.frequency_hz - self.points[-2].frequency_hz) if len(self.points) > 1 else 0.0
        if self._skip(cp, point):
            return True
        if self.status != "running":           # no backbone above this tongue (an escape the skeleton knows)
            raise StopIteration
        t = self.tongues[-1]
        # the backbone resumes beyond the tongue with its frequency moving the same way as before it
        t.update(last_energy=point.energy, hidden_points=1, backbone=bpoint, trend=float(trend))
        self._tongue = t
        return True

    def _skip(self, cp, point):
        """Jump over the tongue that ``point`` entered (tongue_skip.py); True if the continuation now
        restarts beyond it."""
        bcp, bpoint = self._last_backbone
        Q = self._problem.modal_orbit(cp.u)
        k = int(point.label.split()[-1].split(":")[0]) if point.label.startswith("tongue") else (
            harmonic_label(Q)[1] if Q is not None else 1)
        tongue = tongue_record(self._system, Q, k, bpoint, point, len(self.points) - 1)
        self._last_backbone = None
        E_base = max(bpoint.energy, point.energy)
        partner = tongue.get("partner_mode", 0)
        partner_hz = math.sqrt(self._system.omega2[partner - 1]) / (2 * math.pi) if partner >= 1 else None
        skipper = TongueSkipper(self._problem, self._cs, self._tol, self._system, self._skeleton, self._labels)
        jumped = skipper.jump(bcp.u, bcp.tangent, bpoint.energy, E_base, None if tongue["order"] == 1 else k,
                              partner_hz)
        previous = self.tongues[-1] if self.tongues else None
        if previous is not None and same_tongue(previous, tongue):
            # the backbone seemed to resume but re-entered the tongue it was passing: one record, first entry
            previous["reentries"] = previous.get("reentries", 0) + 1
            last = previous.get("last_entry_energy", previous["entry_energy"])
            previous["stalls"] = previous.get("stalls", 0) + 1 if bpoint.energy <= last * (1 + STALL_RTOL) else 0
            previous["last_entry_energy"] = bpoint.energy
            previous.pop("exit_energy", None)
            previous.pop("exit_frequency_hz", None)
            tongue = previous
            if tongue["stalls"] >= MAX_STALLS:
                # the jumps land on the orbit they started from: no progress, the family ends at this tongue
                tongue.update(skipped=False, note=f"re-entered {tongue['stalls']} times from the same orbit")
                self._finish("tongue", f"the backbone re-entered {resonance(tongue['label'], tongue)} at "
                             f"E = {bpoint.energy:.4g} J, f = "
                             f"{bpoint.frequency_hz:.5g} Hz {tongue['stalls']} times from the same orbit (the jumps "
                             f"over it land where they started): no backbone above it was found, the branch ends "
                             f"there; the points on the backbone below are kept")
                self._last_backbone = None
                return False
        else:
            self.tongues.append(tongue)
        tongue["attempts"] = tongue.get("attempts", 0) + skipper.attempts     # orbits corrected to jump it
        if jumped is None:
            tongue.update(skipped=False, note="no backbone orbit found by a jump: passed by traversing the tongue")
            escape = escape_below_peak(self._skeleton() if self._skeleton is not None else None, tongue, bpoint)
            if escape is not None:
                self._finish("escape", escape)
            return False
        u, J, how = jumped
        tongue.update(skipped=True, exit_energy=float(self._problem.energy(u)), jump=how)
        self._engine.restart(pseudo_arclength(self._problem, u, upward_tangent(self._problem, u, J, bcp.tangent),
                                              self._cs, self._tol))
        self._prev = None          # no events are located across the jump
        self._refusals = 0
        return True

    def _inside_tongue(self, t, point):
        """Skip mode: the continuation is inside tongue t and cannot come back onto the backbone (it reached
        energy_max or max_points inside it): status 'tongue' (ends.py)."""
        self._finish("tongue", inside_tongue(self._skeleton() if self._skeleton is not None else None, t,
                                             point.energy >= self.energy_max, len(self.tongues) - 1,
                                             self.max_points))
