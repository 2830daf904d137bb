r"""The backbone's decision at each converged point: keep it, jump over the tongue it entered, or finish.

The algorithm (``tongues=Skip()``), for each point the continuation gives, in energy order along the family:

1. Label it against the skeleton (labels.py): on the backbone family within the accuracy both computations
   estimate, or off it.
2. On the family and above the last kept point in energy: **Keep** it.
3. Off the family (or turned back in energy: the backbone continued in energy has no fold): it entered a tongue.
   **Jump**: the skeleton's orbits above the departure (jumps.candidates) are the targets, tried nearest first; the first whose corrected orbit is on the family (``landed``) is where the
   continuation restarts.  The tongue is recorded (results/tongues.py: order, partner mode, entry and inside
   orbits, how it was passed); a departure into the tongue just passed adds a re-entry to its record.
   With no target left below the family's end (above its energy maximum, or past the resonance that ends it, as the
   skeleton says): **Finish** with the family's end (``escape`` at a softening family's energy maximum, ``tongue``
   where a k:1 resonance ends it).
4. No target lands (``no_landing``), or the continuation cannot go on (``stopped``): where the skeleton ends within
   reach, that is the family's end (its status, its message); else ``tongue``, saying that no landing was found.

``tongues=Follow()`` keeps every point with its label, except a departure from the backbone into a tongue of order
above ``Follow.max_order`` (3 by default): that one is jumped as above, and the branch goes on along the backbone.  A policy only reads values and returns decisions; the
iterator (driver/iterator.py) does what they say.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..results.tongues import TongueRecord
from .content import partner_mode
from .jumps import candidates
from .settings import Follow, Skip

__all__ = ["Keep", "Jump", "Finish", "FollowPolicy", "SkipPolicy", "policy_for", "family_end_status",
           "jumped_in_follow"]


@dataclass(frozen=True)
class Keep:
    """Keep the point (a backbone point, or any point in follow mode)."""


@dataclass(frozen=True)
class Jump:
    """Leave the point out and jump: try the skeleton's energies ``targets`` (J) in turn; ``record`` is the
    tongue's record (new, or the re-entered one with ``index`` its place in branch.tongues), ``base`` the energy
    the landing must exceed (J)."""

    record: TongueRecord
    targets: tuple
    base: float
    index: int = -1


@dataclass(frozen=True)
class Finish:
    """End the branch with ``status`` and ``message``; ``record`` (or None) is added to (index -1) or replaces
    (index >= 0) branch.tongues."""

    status: str
    message: str
    record: TongueRecord | None = None
    index: int = -1


def family_end_status(skeleton):
    """The status of a branch that ends where its family ends: 'escape' at a softening family's energy maximum,
    'tongue' where a k:1 resonance ends it; None when the skeleton reached its reach (the family goes on)."""
    if skeleton is None or skeleton.end == "reach":
        return None
    return "escape" if skeleton.end == "peak" else "tongue"


def _at(p):
    return f"E = {p.energy:.4g} J, f = {p.frequency_hz:.5g} Hz"


def _resonance(record):
    if record.label == "fold":
        return "a fold of its family (its energy turns back with no harmonic k >= 2: no internal resonance)"
    partner = f" with mode {record.partner_mode}" if record.partner_mode else ""
    return f"the {record.order}:1 internal-resonance tongue{partner}"


class FollowPolicy:
    """tongues=Follow(): every point is kept (its label says where it is), except a departure from the backbone
    into a tongue of order above ``settings.max_order``: that one is jumped by a SkipPolicy with Skip's defaults
    (composition: its landing test, its records and its end decisions), so the branch goes on along the backbone.
    With no skeleton (none could be computed, or no nonlinear element) nothing can be jumped: every point is kept."""

    def __init__(self, settings=Follow(), skeleton=None, skeleton_failure="", mode=1):
        self.settings, self.skeleton = settings, skeleton
        self.mode = int(mode)
        self.jumper = (SkipPolicy(Skip(skeleton=settings.skeleton, labels=settings.labels), skeleton,
                                  skeleton_failure, mode)
                       if settings.max_order is not None and skeleton is not None else None)

    def decide(self, point, verdict, content, Q, last, index, tongues):
        if not jumped_in_follow(self.settings, self.jumper is not None, verdict, content, last):
            return Keep()
        return self.jumper.decide(point, verdict, content, Q, last, index, tongues)

    def landed(self, verdict, energy, base):
        return self.jumper.landed(verdict, energy, base)

    def recorded(self, record):
        return self.jumper.recorded(record)

    def no_landing(self, last, record, tried, index=-1):
        """Skip's end where no landing is found, its message saying that following every tongue goes on."""
        end = self.jumper.no_landing(last, record, tried, index)
        return Finish(end.status, f"{end.message} (Follow(max_order={self.settings.max_order}) jumps tongues of "
                                  f"higher order; tongues='follow-all', nnm-solve --tongues follow-all, follows "
                                  f"them)", end.record, end.index)

    def stopped(self, last, reason, index):
        return None

    @staticmethod
    def note(points):
        """The 'done' message's note for a branch whose last points are off the backbone family."""
        if not points or points[-1].label == "backbone":
            return ""
        i = len(points) - 1
        while i > 0 and points[i - 1].label != "backbone":
            i -= 1
        p = points[i]
        # the tongue it entered (where it left the family); a resonance met inside it is the last points' label
        last = "" if points[-1].label == p.label else f", its last points labelled '{points[-1].label}'"
        return (f", inside a {p.label.split()[-1]} tongue: the points from {_at(p)} on are off the backbone "
                f"family{last} (tongues='skip', nnm-solve --tongues skip, follows the backbone)")


class SkipPolicy:
    """tongues=Skip() (module docstring).  settings : Skip; skeleton : the branch's Skeleton (or None: then no
    tongue can be jumped, and a departure ends the branch 'tongue', saying why)."""

    def __init__(self, settings=Skip(), skeleton=None, skeleton_failure="", mode=1):
        self.settings, self.skeleton = settings, skeleton
        self.mode = int(mode)                  # the followed mode (1-based)
        self.skeleton_failure = skeleton_failure
        self.jumps = 0

    @staticmethod
    def note(points):
        return ""

    def decide(self, point, verdict, content, Q, last, index, tongues):
        """Keep, Jump or Finish for ``point`` (its Verdict, Content, modal orbit Q), ``last`` the last kept point
        (or None), index its would-be index, tongues the records so far."""
        if last is None or (verdict.on_family and point.energy >= last.energy * (1 - 1e-12)):
            return Keep()
        record = self._record(point, verdict, content, Q, last, index)
        sk = self.skeleton
        previous = tongues[-1] if tongues else None
        again = (previous is not None and previous.order == record.order
                 and previous.partner_mode == record.partner_mode and previous.exit_energy is not None
                 and last.energy <= previous.exit_energy * (1 + self.settings.same_tongue))

        base = last.energy
        if self.jumps >= self.settings.max_jumps:
            return Finish("tongue", f"the backbone left its family {self.jumps} times (Skip.max_jumps); the last "
                                    f"departure into {_resonance(record)} at {_at(last)}; the points on the backbone "
                                    f"below are kept", record)
        # a re-entry of the tongue just passed: one record, the shortest jumps no more tried (no crawl along its edge)
        jumps, index = self.settings.jumps, -1
        if again:
            jumps = jumps[min(previous.reentries + 1, 2):]
            record, index = previous.replace(reentries=previous.reentries + 1), len(tongues) - 1
            base = max(base, previous.exit_energy)          # beyond the last landing: progress
        targets = tuple(candidates(sk, base, jumps))
        if not targets and verdict.beyond_end:
            return self._family_end(last, record, f"the branch left its family past the family's end at {_at(point)}",
                                    index)
        if not targets:
            return self.no_landing(last, record, (), index)
        self.jumps += 1
        return Jump(record, targets, base, index)

    @staticmethod
    def recorded(record):
        """Is a passed departure a tongue to list in branch.tongues?  Not a step that left a steep part of the
        family with no partner harmonic (order 1, no partner: nothing resonates), only jumped back onto it."""
        return record.order >= 2 or record.partner_mode > 0

    def landed(self, verdict, energy, base):
        """Is a jump's corrected orbit (its Verdict, energy J) on the family above ``base`` (J)?"""
        return verdict.on_family and verdict.dev is not None and energy > base

    def no_landing(self, last, record, tried, index=-1):
        """No target landed on the family (tried: the energies tried, J): the family's end where the skeleton ends
        within reach, else 'tongue' saying so."""
        sk = self.skeleton
        status = family_end_status(sk)
        if status is not None and len(sk.energy) and last.energy >= (1 - self.settings.near_end) * sk.energy[-1]:
            return self._family_end(last, record, f"the branch entered {_resonance(record)} at {_at(last)}",
                                    index)
        if sk is None:
            why = f"no skeleton to jump from ({self.skeleton_failure or 'the model has no nonlinear element'})"
        elif tried:
            why = (f"none of the skeleton's {len(tried)} orbits from {tried[0]:.4g} to {tried[-1]:.4g} J landed on "
                   f"the family")
        else:
            why = f"the skeleton has no orbit of the family up to {1 + self.settings.jumps[-1]:g} x that energy"
        return Finish("tongue", f"the backbone entered {_resonance(record)} at {_at(last)} and could not be jumped "
                                f"over ({why}); the points on the backbone below it are kept",
                      record.replace(note=why), index)

    def stopped(self, last, reason, index):
        """The continuation could not go on after ``last`` (reason: the engine's): Finish at the family's end when
        the skeleton ends within reach of it, else None (the iterator reports 'failed')."""
        sk = self.skeleton
        status = family_end_status(sk)
        if status is None or not len(sk.energy) or last.energy < (1 - self.settings.near_end) * sk.energy[-1]:
            return None
        record = TongueRecord(order=sk.partner[0], partner_mode=sk.partner[1], entry_index=index,
                              entry_energy=float(last.energy), entry_frequency_hz=float(last.frequency_hz))
        return self._family_end(last, record, f"the continuation could not go beyond {_at(last)} ({reason})")

    def _family_end(self, last, record, what, index=-1):
        sk = self.skeleton
        status = family_end_status(sk)
        if status == "escape":            # a tongue met at the peak is recorded; the family's own fold is not one
            return Finish("escape", f"{what}, at its family's energy maximum {sk.energy_peak:.4g} J (its skeleton: "
                                    f"{sk.message}): no backbone exists above it, the structure escapes; the "
                                    f"points on the backbone below are kept",
                          record.replace(family_end=True, note=sk.message) if record.order >= 2 else None, index)
        if status == "tongue":
            k, partner = sk.partner
            if not record.partner_mode and partner:   # no partner harmonic in the orbit: the skeleton's resonance
                record = record.replace(order=k, partner_mode=partner)
            named = f"the {k}:1 internal resonance with mode {partner}" if partner else "a resonance"
            return Finish("tongue", f"{what}, where the backbone family itself ends in {named} (its skeleton: "
                                    f"{sk.message}): no backbone beyond it; the points on the backbone below are kept",
                          record.replace(family_end=True, note=sk.message), index)
        return Finish("tongue", f"{what}; the points on the backbone below are kept", record, index)

    def _record(self, point, verdict, content, Q, last, index):
        """The TongueRecord of a departure from ``last`` (index - 1) into ``point`` (its Verdict names the order)."""
        k = verdict.order or content.order
        mode, mac = partner_mode(Q, k, self.mode - 1) if Q is not None and k >= 2 else (0, math.nan)
        return TongueRecord(order=k, partner_mode=mode, partner_mac=mac, entry_index=index - 1,
                            entry_energy=float(last.energy), entry_frequency_hz=float(last.frequency_hz),
                            entry_period=float(last.period), entry_x0=tuple(map(float, last.x0)),
                            entry_v0=tuple(map(float, last.v0)), inside_x0=tuple(map(float, point.x0)),
                            inside_v0=tuple(map(float, point.v0)), inside_period=float(point.period))


def jumped_in_follow(settings, can_jump, verdict, content, last):
    """Follow(): is the departure into ``verdict``'s tongue one to jump?  Only a departure from a backbone point
    (``last``: the last kept point; inside a followed tongue every point is kept) into a tongue whose order (the
    label's k, else the orbit's Content) exceeds settings.max_order, when there is a skeleton to jump from."""
    if not can_jump or last is None or verdict.on_family or last.label != "backbone":
        return False
    return (verdict.order or content.order) > settings.max_order


def policy_for(settings, skeleton, skeleton_failure="", mode=1):
    """The policy object of a tongues setting (Follow or Skip) for the followed mode (1-based)."""
    if isinstance(settings, Skip):
        return SkipPolicy(settings, skeleton, skeleton_failure, mode)
    return FollowPolicy(settings, skeleton, skeleton_failure, mode)
