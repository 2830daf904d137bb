"""The backbone's decisions (nnm_solver/backbone/policy.py, labels.py) on canned skeletons and points: keep, jump,
finish; one record per tongue re-entered; the family's end; the lock test.  No continuation runs here."""
import math

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.backbone.content import Content
from nnm_solver.backbone.labels import FamilyLabels, Verdict
from nnm_solver.backbone.policy import Finish, FollowPolicy, Jump, Keep, SkipPolicy
from nnm_solver.results.tongues import TongueRecord


class CannedSkeleton:
    """A skeleton f(E) = f0 (1 - c ln(E / E0)) on [E_lo, E_hi], ending as told (the attributes the policy and the
    labels read)."""

    def __init__(self, E_lo=0.1, E_hi=10.0, f0=10.0, c=0.01, end="reach", partner=(1, 0), energy_peak=None):
        self.energy = np.geomspace(E_lo, E_hi, 60)
        self.f0, self.c, self.E0 = f0, c, E_lo
        self.frequency_hz = f0 * (1 - c * np.log(self.energy / E_lo))
        self.end, self.partner, self.energy_peak = end, partner, energy_peak
        self.sheet_starts, self.message, self.mode = [], f"canned family ending {end}", 1

    def covers(self, E):
        return self.energy[0] <= E <= self.energy[-1]

    def frequency_at(self, E):
        return self.f0 * (1 - self.c * math.log(E / self.E0)) if self.covers(E) else math.nan

    def slope(self, E1, E2):
        return (math.log(self.frequency_at(E2)) - math.log(self.frequency_at(E1))) / math.log(E2 / E1)

    def log_frequency(self, E):
        return math.log(self.frequency_at(E))

    def interpolation_error(self, E):
        return 0.0

    def frequency_of_orbit(self, E):
        return self.frequency_at(E)

    def truncation_at(self, E):
        return 0.0

    def share_at(self, E):
        return 1.0


class P:
    """A canned point (energy J, frequency Hz)."""

    def __init__(self, E, f):
        self.energy, self.frequency_hz, self.period = E, f, 1 / f
        self.x0, self.v0 = np.zeros(2), np.zeros(2)


ON = Content(k=3, fraction=1e-3, partner_k=3, share=0.999)


def labels(sk):
    return FamilyLabels(sk, sk.f0, sk.f0)


def test_a_point_on_the_family_is_kept_one_off_it_jumps_to_the_skeleton_beyond():
    sk = CannedSkeleton()
    lab, pol = labels(sk), SkipPolicy(nnm.Skip(), sk, mode=1)
    last = P(1.0, sk.frequency_at(1.0))
    on = P(1.1, sk.frequency_at(1.1) * (1 + 5e-5))
    v = lab.verdict(on.energy, on.frequency_hz, ON)
    assert v.on_family and v.text == "backbone" and v.dev == pytest.approx(5e-5, rel=1e-6)
    assert isinstance(pol.decide(on, v, ON, None, last, 5, []), Keep)
    off = P(1.1, sk.frequency_at(1.1) * (1 + 3e-4))          # 3e-4 off: in a tongue
    v = lab.verdict(off.energy, off.frequency_hz, ON)
    assert not v.on_family and v.text == "tongue 3:1"
    d = pol.decide(off, v, ON, None, last, 5, [])
    assert isinstance(d, Jump) and d.index == -1 and d.base == 1.0
    grid = [1.0 * (1 + x) for x in nnm.Skip().jumps if sk.covers(1 + x)]
    assert set(grid) <= set(d.targets) and list(d.targets) == sorted(d.targets)     # the grid, each with the
    nodes = [t for t in d.targets if t not in grid]                                # skeleton's next point
    assert nodes and all(np.any(np.isclose(sk.energy, t)) for t in nodes)
    assert d.record.order == 3 and d.record.entry_energy == 1.0 and d.record.entry_index == 4


def test_the_bias_is_the_methods_at_each_points_own_time_step():
    """f_method as a function of the steps per period (Newmark's linear frequency, relative error -(omega h)^2 / 12):
    a point computed with 364 steps (the accuracy target raised them from 100) is measured with the bias at 364
    steps, -2.5e-5, not at 100 (-3.3e-4, which put it 3e-4 off the family: a tongue)."""
    sk = CannedSkeleton()
    lab = FamilyLabels(sk, sk.f0, lambda steps: sk.f0 * (1 - (2 * math.pi / steps) ** 2 / 12), order=2)
    assert lab.offset(100) == pytest.approx(-3.29e-4, rel=1e-2) and lab.offset(364) == pytest.approx(-2.48e-5, rel=1e-2)
    f = sk.frequency_at(2.0) * (1 + lab.offset(364))
    v = lab.verdict(2.0, f, ON, steps=364)
    assert v.text == "backbone" and v.dev == pytest.approx(0.0, abs=1e-12)
    assert lab.verdict(2.0, f, ON, steps=100).text == "tongue 3:1"
    # one frequency (a method without time step): the same bias whatever the steps
    one = FamilyLabels(sk, sk.f0, sk.f0 * (1 - 3.29e-4))
    assert one.bias(None, 364) == one.bias(None, 100) == one.offset() == pytest.approx(-3.29e-4)


def test_the_tongue_just_passed_entered_again_is_one_record_with_longer_jumps():
    sk = CannedSkeleton()
    lab, pol = labels(sk), SkipPolicy(nnm.Skip(), sk, mode=1)
    passed = TongueRecord(order=3, entry_energy=1.0, skipped=True, exit_energy=1.02, exit_frequency_hz=9.9)
    last = P(1.02, sk.frequency_at(1.02))
    off = P(1.03, sk.frequency_at(1.03) * 1.001)
    d = pol.decide(off, lab.verdict(off.energy, off.frequency_hz, ON), ON, None, last, 9, [passed])
    assert isinstance(d, Jump) and d.index == 0 and d.record.reentries == 1 and d.record.exit_energy == 1.02
    assert d.targets[0] == pytest.approx(1.02 * (1 + nnm.Skip().jumps[1]))        # the shortest jump is not tried
    other = Content(k=5, fraction=1e-2, partner_k=5, share=0.99)                    # another order: a new record
    d = pol.decide(off, lab.verdict(off.energy, off.frequency_hz, other), other, None, last, 9, [passed])
    assert isinstance(d, Jump) and d.index == -1 and d.record.order == 5
    far = P(5.0, sk.frequency_at(5.0) * 1.001)                                      # far above: the same order anew
    d = pol.decide(far, lab.verdict(far.energy, far.frequency_hz, ON), ON, None, P(4.9, 9.0), 30, [passed])
    assert d.index == -1


@pytest.mark.parametrize("end, status", [("stuck", "tongue"), ("locked", "tongue"), ("peak", "escape")])
def test_where_no_target_is_left_the_branch_ends_as_its_family_ends(end, status):
    sk = CannedSkeleton(E_hi=2.0, end=end, partner=(3, 7), energy_peak=2.0 if end == "peak" else None)
    lab, pol = labels(sk), SkipPolicy(nnm.Skip(), sk, mode=1)
    last = P(1.999, sk.frequency_at(1.999))
    beyond = P(2.5, 9.0)
    v = lab.verdict(beyond.energy, beyond.frequency_hz, ON)
    assert v.beyond_end and v.dev == math.inf
    d = pol.decide(beyond, v, ON, None, last, 40, [])
    assert isinstance(d, Finish) and d.status == status and "canned family ending" in d.message
    if status == "tongue":
        assert d.record.family_end and "mode 7" in d.message
    # the continuation stopping there ends the same way; far below the end it is a failure ('failed': None)
    assert pol.stopped(last, "no convergence", 40).status == status
    assert pol.stopped(P(0.2, sk.frequency_at(0.2)), "no convergence", 3) is None


def test_without_a_skeleton_a_departure_ends_the_branch_saying_why():
    pol = SkipPolicy(nnm.Skip(), None, "the skeleton could not be computed: singular", mode=1)
    d = pol.decide(P(1.1, 9.0), Verdict("tongue 3:1"), ON, None, P(1.0, 9.1), 3, [])
    assert isinstance(d, Finish) and d.status == "tongue" and "singular" in d.message


def test_follow_keeps_every_point_and_notes_where_the_last_ones_are():
    pol = FollowPolicy()
    assert isinstance(pol.decide(P(1, 1), Verdict("tongue 3:1"), ON, None, P(0.9, 1), 1, []), Keep)
    a, b = P(1, 1), P(2, 1)
    a.label, b.label = "backbone", "tongue 3:1"
    assert "off the backbone family" in pol.note([a, b]) and pol.note([a]) == ""


def test_follow_jumps_a_departure_into_a_tongue_above_its_order_and_keeps_the_rest():
    """Follow() (max_order 3): a departure from the backbone into a 5:1 is jumped as Skip jumps it; into a 3:1 it is
    kept; inside a followed tongue every point is kept, whatever its label; Follow(max_order=None) keeps all."""
    sk = CannedSkeleton()
    lab = labels(sk)
    last = P(1.0, sk.frequency_at(1.0))
    last.label = "backbone"
    off = P(1.1, sk.frequency_at(1.1) * (1 + 3e-4))
    five = Content(k=5, fraction=1e-2, partner_k=5, share=0.99)
    v3, v5 = lab.verdict(off.energy, off.frequency_hz, ON), lab.verdict(off.energy, off.frequency_hz, five)
    assert v3.order == 3 and v5.order == 5
    pol = FollowPolicy(nnm.Follow(), sk, mode=1)
    assert isinstance(pol.decide(off, v3, ON, None, last, 5, []), Keep)
    d = pol.decide(off, v5, five, None, last, 5, [])
    assert isinstance(d, Jump) and d.record.order == 5 and d.base == 1.0
    assert d.targets == SkipPolicy(nnm.Skip(), sk, mode=1).decide(off, v5, five, None, last, 5, []).targets
    end = pol.no_landing(last, d.record, (1.105, 1.2))            # no target landed: the end says how to follow it
    assert isinstance(end, Finish) and end.status == "tongue" and "follow-all" in end.message
    inside = P(1.0, sk.frequency_at(1.0) * 1.001)
    inside.label = "tongue 3:1"                          # the last kept point is inside a followed 3:1 tongue
    assert isinstance(pol.decide(off, v5, five, None, inside, 9, []), Keep)
    assert isinstance(FollowPolicy(nnm.Follow(max_order=None), sk).decide(off, v5, five, None, last, 5, []), Keep)
    assert isinstance(FollowPolicy(nnm.Follow(), None).decide(off, v5, five, None, last, 5, []), Keep)  # no skeleton
    assert isinstance(FollowPolicy(nnm.Follow(max_order=5), sk).decide(off, v5, five, None, last, 5, []), Keep)
    with pytest.raises(nnm.NNMInputError, match="max_order"):
        nnm.Follow(max_order=0)


def test_a_frequency_locked_while_the_family_moves_is_a_tongue():
    """Within the distance tolerance but locked (the frequency stays while the family's falls): off the family."""
    sk = CannedSkeleton(c=0.05)
    lab = labels(sk)
    run = [(1.0, sk.frequency_at(1.0))]
    moving = sk.frequency_at(1.1)
    assert not lab.locked(1.1, moving, run)
    assert lab.locked(1.1, run[0][1], run)                      # no move at all where the family moved 0.5 %
    assert not lab.locked(1.0001, run[0][1], run)              # the family's move below lock_window: no verdict
    assert lab.verdict(1.1, run[0][1], ON, run=run).text == "tongue 3:1"


def test_records_read_as_mappings_and_round_trip():
    t = TongueRecord(order=3, partner_mode=42, entry_energy=1.5, entry_x0=(1.0, 2.0))
    assert t["label"] == "tongue 3:1" and t["ratio"] == [3, 1] and t.get("exit_energy") is None
    assert dict(t)["entry_x0"] == [1.0, 2.0] and "exit_energy" not in t
    assert TongueRecord.from_mapping(t.as_dict()) == t
    assert TongueRecord(order=1).label == "fold" and TongueRecord(order=1, partner_mode=18).label == "tongue 1:1"
