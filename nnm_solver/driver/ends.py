r"""Honest ends of a backbone: where and why a branch that did not reach energy_max on its family ends.

The branch's skeleton (skeleton.py) knows how the backbone family itself ends: at its energy maximum
(``peak``: a softening family approaching a saddle, no backbone above it) or in a k:1 internal resonance
(``locked``: a partner mode takes the orbit over; ``stuck``: no solution at a larger amplitude).  A branch
whose continuation stops near there (above PEAK_NEAR of that energy) ends where its family ends, and says
so, instead of ``failed`` or ``done``:

* ``escape``: a tongue that cannot be jumped, a continuation that cannot go on, or one whose energy turns
  back with no tongue's harmonic (the fold of the family itself), just below the family's energy maximum;
* ``tongue``: the continuation cannot go on where the family meets its final k:1 resonance (a record with
  ``family_end`` is added to ``branch.tongues``), or it cannot leave a tongue it entered (energy_max or
  max_points inside it), with the skeleton's word when the family itself ends there;
* ``done`` in follow mode with its last points in a tongue: the message says that they are off the family.

These functions only build the statuses, messages and records; the iterator (iterator.py) finishes with them.
"""
from __future__ import annotations

__all__ = ["PEAK_NEAR", "AT_PEAK", "resonance", "off_family_note", "escape_below_peak", "escape_at_peak", "inside_tongue",
           "family_end"]

#: a tongue entered, or a continuation stopped, above this fraction of the skeleton's energy maximum (or end)
#: is "at" the end of the family
PEAK_NEAR = 0.8

#: a fold of the branch is the family's own energy maximum (escape_at_peak) above this fraction of the skeleton's:
#: the skeleton resolves its maximum, and the branch's last point before the fold lies within a step of it, where the
#: energy is flat (a fold of the branch well below it is another, e.g. a narrow fold pair the family passes)
AT_PEAK = 0.95

#: a departure from the backbone near the family's energy maximum with less than this fraction of the orbit in any
#: harmonic k >= 2 has no partner harmonic: the fold of the family itself (escape_at_peak), not a tongue
PEAK_CONTENT = 1e-3


def off_family_note(points):
    """Follow mode: the note for a branch whose last points (Point, labelled) are off the backbone family."""
    if not points or points[-1].label == "backbone":
        return ""
    i = len(points) - 1
    while i > 0 and points[i - 1].label != "backbone":
        i -= 1
    p = points[i]
    return (f", inside a {points[-1].label.split()[-1]} tongue: the points from E = {p.energy:.4g} J "
            f"(f = {p.frequency_hz:.5g} Hz) on are off the backbone family (tongues='skip' follows the backbone)")


def resonance(label, record=None):
    """'tongue 3:1' (a tongue record's label) -> 'the 3:1 internal-resonance tongue' (and 'with mode p' when the
    record names its partner); 'fold' -> a fold of the family, which is not an internal resonance."""
    if label == "fold":
        return "a fold of its family (its energy turns back with no harmonic k >= 2: no internal resonance)"
    ratio = label.split()[-1] if label.startswith("tongue") else label
    partner = record.get("partner_mode", 0) if record is not None else 0
    return f"the {ratio} internal-resonance tongue" + (f" with mode {partner}" if partner else "")


def escape_below_peak(sk, tongue, bpoint):
    """Skip mode, a tongue that could not be jumped: the 'escape' message when it was entered just below
    the family's energy maximum (the skeleton's energy_peak), else None."""
    if sk is None or sk.energy_peak is None or not tongue["entry_energy"] >= PEAK_NEAR * sk.energy_peak:
        return None
    return (f"the backbone entered {resonance(tongue['label'], tongue)} at "
            f"E = {bpoint.energy:.4g} J, f = {bpoint.frequency_hz:.5g} Hz, just below the family's energy maximum "
            f"{sk.energy_peak:.4g} J (its skeleton: a softening family approaching a saddle): no backbone exists "
            f"above it, the structure escapes; the points on the backbone below are kept")


def escape_at_peak(sk, bpoint, point, fraction):
    """Skip mode: the 'escape' message when the continuation left the backbone (last backbone point ``bpoint``,
    first point off it ``point``) at the family's own energy maximum: the skeleton ended at its peak, ``bpoint``
    lies above AT_PEAK of it, and no harmonic k >= 2 carries more than PEAK_CONTENT of the orbit (``fraction``,
    tongue_skip.harmonic_content): no partner harmonic, not a tongue but the fold of the family itself (the point
    past it may lie below ``bpoint`` in energy, or just above it on the far side of the fold).  None otherwise."""
    if (sk is None or sk.energy_peak is None or not bpoint.energy >= AT_PEAK * sk.energy_peak
            or not fraction < PEAK_CONTENT):
        return None
    return (f"the backbone reached its family's energy maximum at E = {bpoint.energy:.4g} J, "
            f"f = {bpoint.frequency_hz:.5g} Hz (its skeleton: {sk.energy_peak:.4g} J, a softening family approaching "
            f"a saddle; no internal resonance there, the higher harmonics carry {100 * fraction:.2g} % of the orbit): "
            f"no backbone exists above it, the structure escapes; the points are kept")


def inside_tongue(sk, t, reached_energy_max, index, max_points=None):
    """Skip mode: the 'tongue' message for a continuation inside tongue t (record ``index`` of
    branch.tongues) that cannot come back onto the backbone.  ``t['hidden_points']``: the orbits the
    continuation computed inside the tongue since it entered it (not kept on the backbone branch); it
    stopped because it reached energy_max among them, or because they reached ``max_points``."""
    where = (f"the backbone entered {resonance(t['label'], t)} "
             f"at E = {t['entry_energy']:.4g} J, f = {t['entry_frequency_hz']:.5g} Hz")
    n = t["hidden_points"]
    orbits = f"{n} orbit{'s' if n != 1 else ''} computed inside it, not kept"
    why = (f"energy_max reached inside it; {orbits}" if reached_energy_max else
           f"max_points = {max_points} orbits computed inside it without coming back onto the backbone, not kept"
           if max_points is not None else orbits)
    family = ""
    if sk is not None and sk.end != "reach" and len(sk.energy) and (
            PEAK_NEAR * sk.energy[-1] <= t["entry_energy"] <= sk.energy[-1] / PEAK_NEAR):
        family = f"; the backbone family itself ends there ({sk.message})"
    return (f"{where} and could not be jumped over ({why}){family}; the points on the backbone below it are kept "
            f"(continue_tongue(branch, {index}) follows the tongue)")


def family_end(sk, last, reason, index):
    """The continuation failed after the point ``last`` (index ``index``) for ``reason``: where the backbone
    family itself ends there, (status, message, tongue record or None); else None (a numerical failure)."""
    if sk is None or sk.end == "reach" or not len(sk.energy):
        return None
    E_end = sk.energy_peak if sk.energy_peak is not None else float(sk.energy[-1])
    if not last.energy >= PEAK_NEAR * E_end:
        return None
    at = f"E = {last.energy:.4g} J, f = {last.frequency_hz:.5g} Hz"
    if sk.end == "peak":
        return "escape", (f"the continuation could not go beyond {at} ({reason}), just below the family's energy "
                          f"maximum {E_end:.4g} J (its skeleton: a softening family approaching a saddle): no "
                          f"backbone exists above it, the structure escapes; the points are kept"), None
    k, partner = sk.partner
    record = dict(ratio=[k, 1], order=k, label=f"tongue {k}:1", partner_mode=partner, partner_mac=float("nan"),
                  entry_energy=float(last.energy), entry_frequency_hz=float(last.frequency_hz), entry_index=index,
                  hidden_points=0, skipped=False, attempts=0, family_end=True,
                  note=f"the backbone family ends here: {sk.message}")
    return "tongue", (f"the backbone ends at {at}, where its family meets the {k}:1 internal resonance with mode "
                      f"{partner}: the continuation cannot go further ({reason}) and the family's skeleton ends "
                      f"there too ({sk.message}): no backbone beyond it; the points are kept"), record
