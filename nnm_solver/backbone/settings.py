r"""The backbone's settings: every threshold of the tongue passage and of the skeleton, written once, with the
measurement behind it.

``Follow()`` and ``Skip()`` are what a user passes as ``continue_nnm(..., tongues=...)``; both carry a
``SkeletonSettings`` (how the skeleton is stepped) and the labelling thresholds; ``Skip`` adds how tongues are jumped.
The objects are frozen: change one value with ``dataclasses.replace`` (or ``Skip(max_jumps=...)``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..errors import NNMInputError

__all__ = ["SkeletonSettings", "LabelSettings", "TongueBranchSettings", "Follow", "Skip", "TONGUE_MODES"]


@dataclass(frozen=True)
class SkeletonSettings:
    """How the skeleton (condensed HB stepped in the followed mode's modal amplitude a, skeleton.py) is computed.

    harmonics : odd harmonics of the skeleton's harmonic balance (9: the aircraft's mode 20 below 1e-6 of the
        exact frequency at 1 J; its truncation error is estimated per point, Skeleton.truncation_at);
    max_unknowns : where its condensed problem (n_s N_b + 2 unknowns) would be larger, it has fewer harmonics (two
        fewer at a time, at least 3): a nonlinearity on every element (a von Karman beam: n_s = 64 deformations for
        63 DOFs) makes the condensed problem as large as the full one, and with 9 harmonics (a full basis, N_b = 19)
        each Newton step on its 1218 unknowns took 1-2 s here; the 16-element beam's skeleton had not finished
        after 24 min.  At 3 harmonics (450 unknowns) it takes under 3 min; the labels then allow for the coarser
        skeleton's own truncation estimate.
    reach, follow_reach : the skeleton is stepped up to this multiple of the branch's energy_max with tongues
        skipped (the jumps' targets lie beyond the tongues) or followed (only labels are asked, up to energy_max).
    start_shift : it starts where its frequency has moved from the linear mode's by about this much.
    step_max, step_min : largest and smallest ratio a_{i+1} / a_i of its modal amplitude steps (halved towards
        step_min where refused); step_growth : the most a_{i+1} / a_i - 1 grows from one step to the next;
    dlnf_max : the largest move of ln f in a step (its spline interpolation between points then stays at 3e-7 on
        the 2-DOF benchmark, 7e-9 on NLvib's example 04; Skeleton.frequency_at);
    step_max_linear, linear_shift : steps up to step_max_linear while f is within linear_shift of the first point's.
    peak_run, peak_share : the energy falling over peak_run steps in a row with peak_share of the orbit kept by the
        followed mode (family_share) is the family's energy maximum (with less, a resonance).
    jumps : relative amplitude jumps tried where the family meets a resonance it does not pass smoothly;
    jump_shifts : relative frequency shifts of their guesses besides the trend's; jump_limit : the largest move
        accepted beyond the trend's; share_kept : the fraction of the fundamental share a landing orbit keeps.
    share_min : the family ends where other modes' higher harmonics take more than 1 - share_min of the orbit.
    fold_slope : at a fold in a with no partner, d ln E / d ln a below this (2 in the linear regime) means the
        energy turns back with the amplitude: the family's energy maximum.
    fold_probe_steps, fold_probe_drop, fund_share, fold_energy_rtol : past the end of the stepping the family is
        followed by pseudo-arclength for at most fold_probe_steps steps: its energy maximum when the energy falls
        fold_probe_drop below the largest on the way with the followed mode keeping fund_share of the fundamental; a
        1:1 resonance when the energy comes back above it (by fold_energy_rtol) or another mode takes the
        fundamental first; fold_probe_iterations : its corrector's iterations (the engine's, continuation/engine.py).
    max_switches, sheet_ratio : the stepping moves to the backbone's sheet (family_guide.py) at most max_switches
        times, and steps on from where that sheet begins by sheet_ratio (the backbone just past a tongue bends;
        with full steps its frequency between points is off by 1e-6).
    jump_factor, jump_floor : a step moving ln f by more than jump_factor x the previous step's + jump_floor is halved.
    max_points : the stepping's largest number of points.
    The one-harmonic guide (family_guide.py):
    dev_check, dev_check_rel : the guide is asked again when the distance from the one-harmonic family moved by
        dev_check, or dev_check_rel of it where larger (NLvib's beam, example 09, moves 3e-2 away by its own
        harmonics); dev_jump : a step moving that distance by more than jump_factor x the previous + dev_jump is
        halved; sheet_resolution : a switch is placed where the backbone's sheet begins to this ratio in a;
        energy_slack : an orbit of the backbone's sheet holds at most this much more energy than the tongue's at the
        same amplitude; jump_energy_power : a jump of 1 + delta in a raises the energy at most
        (1 + delta) ** jump_energy_power (a hardening cubic family: E ~ a^4);
        guide_trust, sheet_frequency : the guide arbitrates only within guide_trust of the skeleton's frequency (the
        soft 3-DOF chain's mode 1 moves 18 % away near the one-harmonic fold), between sheets within
        sheet_frequency of each other in ln f (the 2-DOF benchmark's tongue sheets 0.3-0.8 % from its backbone);
        guide_step_min, guide_step_max, guide_prediction : the guide's own steps (ratios of a), where its secant
        predictor's frequency is within guide_prediction (the step grown by at most guide_step_growth, as the
        predictor's error allows: it grows as the square of the step); guide_order : its orbits are interpolated by a polynomial
        of this degree in ln a (frequency to 5e-5 on the 2-DOF benchmark and NLvib's beam).
    """

    harmonics: int = 9
    max_unknowns: int = 500
    reach: float = 10.0
    follow_reach: float = 2.0
    start_shift: float = 1e-6
    step_max: float = 1.05
    step_min: float = 1.0005
    step_growth: float = 1.5
    dlnf_max: float = 0.005
    step_max_linear: float = 1.2
    linear_shift: float = 1e-4
    peak_run: int = 3
    peak_share: float = 0.98
    jumps: tuple = (0.01, 0.02, 0.05, 0.1, 0.2)
    jump_shifts: tuple = (0.0, -0.005, 0.005, -0.01, -0.02)
    jump_limit: float = 0.02
    share_kept: float = 0.85
    share_min: float = 0.5
    fold_slope: float = 4.0
    fold_probe_steps: int = 300
    fold_probe_drop: float = 0.1
    fund_share: float = 0.9
    fold_energy_rtol: float = 1e-9
    fold_probe_iterations: int = 20
    max_switches: int = 40
    sheet_ratio: float = 1.005
    jump_factor: float = 5.0
    jump_floor: float = 2e-3
    max_points: int = 3000
    max_jumps: int = 20
    dev_check: float = 2e-4
    dev_check_rel: float = 0.1
    dev_jump: float = 5e-4
    sheet_resolution: float = 1.01
    energy_slack: float = 0.01
    jump_energy_power: float = 6.0
    guide_trust: float = 0.02
    sheet_frequency: float = 0.03
    guide_step_min: float = 1.01
    guide_step_max: float = 2.0
    guide_step_growth: float = 2.0
    guide_prediction: float = 1e-3
    guide_order: int = 3


@dataclass(frozen=True)
class LabelSettings:
    """How a point is labelled against the skeleton (labels.py).

    on_family : a point whose frequency lies within this relative distance of the skeleton's at its energy (plus
        twice its own estimated error and twice the skeleton's truncation estimate there) is on the backbone
        family; beyond, it is in a tongue.  1e-4 is the accuracy asked of the default branch (the guide's "about
        1e-4 in frequency"): on the aircraft's mode 20 the points of three methods on the family lie within 3e-5
        of the skeleton, those on a 3:1 tongue's sheet 1.4e-4 to 5e-3 away.
    linear_regime : below this harmonic fraction and relative frequency shift from the linear mode a point is on
        the backbone without asking the skeleton (the skeleton starts where the shift is start_shift).
    lock_window, lock_ratio : a point whose frequency moved by less than lock_ratio of the family's move since the
        kept points of its run where the family moved by lock_window is locked in a tongue (labels.py; measured on
        the aircraft's mode 20: plateaus move < 1e-5 where the family moves 3e-3, its points on the family 0.8-1.2x
        the family's secant slope);
    share_drop : where only the skeleton's truncation estimate admits a point (dev beyond on_family + 2 errors),
        its fundamental share must lie within share_drop of the skeleton's (aircraft mode 20: 0.002-0.003 on the
        family, 0.005 at dev 5e-5 into its 3:1 tongue, 0.014 on the tongue's plateau at 3.4 J);
    run_length : the kept points remembered for the lock test;
    label_harmonics : highest harmonic looked at for a point's harmonic content.
    fold_content : a harmonic below this fraction of the fundamental is absent (a departure with no harmonic
        k >= 2 is a fold of the family, not a k:1 tongue).
    peak_content : a departure near the family's energy maximum with less than this fraction in any harmonic
        k >= 2 has no partner harmonic: the fold of the family itself.
    partner_share, partner_mismatch, partner_match : where the strongest partner harmonic k of mode j lies more than
        partner_mismatch from resonance (k f against j's frequency averaged along the orbit), the pair holding at
        least partner_share of its share whose k f lies nearest its mode's, within partner_match, names the tongue
        (content.tongue_partner; a clamped beam ROM's forced third harmonic of mode 3 lies 10-24 % off, the 5:1,
        9:1 and 7:1 it met 0.4-1 %).
    """

    on_family: float = 1e-4
    linear_regime: float = 1e-3
    lock_window: float = 3e-4
    lock_ratio: float = 0.3
    share_drop: float = 0.005
    run_length: int = 40
    label_harmonics: int = 25
    fold_content: float = 1e-6
    peak_content: float = 1e-3
    partner_share: float = 0.1
    partner_mismatch: float = 0.08
    partner_match: float = 0.03


@dataclass(frozen=True)
class TongueBranchSettings:
    """When ``continue_tongue`` (driver/tongue_branch.py) stops: after back_on_backbone consecutive points back on
    the backbone below the tongue's entry (a tongue that is a loop off the backbone), a point lying on the
    backbone's frequency-energy curve when within on_backbone_rtol of its frequency (the backbone's own accuracy
    target, 1e-4)."""

    back_on_backbone: int = 3
    on_backbone_rtol: float = 1e-4


@dataclass(frozen=True)
class Follow:
    """``tongues=Follow()``: the continuation follows the internal-resonance tongues it meets; points are
    labelled ``backbone`` or ``tongue k:1`` against the skeleton (labels.py).

    max_order : the highest order k of a k:1 tongue followed from the backbone; a departure from the backbone into a
        tongue of higher order is jumped as ``Skip()`` jumps (its defaults), the tongue listed in branch.tongues and
        computable with ``continue_tongue``; None follows every tongue (the seed paper's FEP of the 2-DOF benchmark,
        ``tongues="follow-all"``).  Once inside a followed tongue every point is kept.  3, because the low-order
        resonances (1:1, 2:1, 3:1) are the ones that carry a branch's energy (the 2-DOF benchmark's 3:1, the
        aircraft's mode 20 with mode 42) while a thin structure's NNM 1 sweeps through tongues of every higher order
        as its tension stiffens it: the hinged von Karman beam (1 m x 10 mm x 20 mm steel) enters a 5:1 with mode 3
        at 1.15 thicknesses (3.41 J) that it follows past 23.87 J (two thicknesses) without coming back, its points
        there 21-110 % off the closed-form backbone; with the 5:1 jumped its backbone is within 6.8e-5 of the closed
        form up to two thicknesses (benchmarks/README.md, "von Karman beam").
    """

    skeleton: SkeletonSettings = field(default_factory=SkeletonSettings)
    labels: LabelSettings = field(default_factory=LabelSettings)
    max_order: int | None = 3
    name = "follow"

    def __post_init__(self):
        if self.max_order is not None and (isinstance(self.max_order, bool) or int(self.max_order) != self.max_order
                                           or self.max_order < 1):
            raise NNMInputError(f"Follow.max_order must be a positive integer or None, got {self.max_order!r}")

    @property
    def reach(self):
        return self.skeleton.follow_reach


@dataclass(frozen=True)
class Skip:
    """``tongues=Skip()``: the branch is the backbone family.  Where a point leaves the family (labels.py) the
    continuation jumps to the family beyond the tongue, from the skeleton's orbits above the departure, corrected
    by the branch's own method on the energy level set (jumps.py); the branch ends where the skeleton ends
    (policy.py).

    jumps : the relative energy jumps tried from a departure at E_0 (J): the skeleton's orbits at E_0 (1 + delta)
        (at most 7.5 % apart below 20 %: on the aircraft's mode 20 at 4.64 J the shooting landed from the skeleton's
        orbit at 5.03 J, not from those at 4.87, 4.97 or 5.10 J),
        nearest first, each with the skeleton's next own point above it (jumps.candidates), corrected by the
        branch's own method (one corrector run each: a failed jump costs at most 2 len(jumps) corrector runs).  A tongue wider than the largest is the end of the family, not a tongue to jump
        (the 2-DOF benchmark's 5:1 with its hardening partner spans 2.7e4..5e4 J of its backbone);
    near_end : a branch whose jumps find no landing, or whose continuation cannot go on, within this fraction below
        the skeleton's last energy ends as its family ends there (escape or tongue); further below it ends 'tongue'
        saying that no landing was found;
    same_tongue : a departure into a tongue of the same order and partner at most this fraction above the last
        landing beyond it is that tongue again (one record, its re-entries counted, longer jumps tried each time);
    max_jumps : jumps per branch (a branch re-entering tongues more often than this ends 'tongue', saying so).
    """

    skeleton: SkeletonSettings = field(default_factory=SkeletonSettings)
    labels: LabelSettings = field(default_factory=LabelSettings)
    jumps: tuple = (0.005, 0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.5, 0.75, 1.0)
    same_tongue: float = 0.1
    near_end: float = 0.1
    max_jumps: int = 60
    name = "skip"

    @property
    def reach(self):
        return self.skeleton.reach


#: the names accepted by continue_nnm(..., tongues=<name>)
TONGUE_MODES = {"follow": Follow, "follow-all": lambda: Follow(max_order=None), "skip": Skip}
