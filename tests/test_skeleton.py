"""The backbone past internal resonances (issue 29): the skeleton (condensed HB stepped in modal amplitude), jumps
from it, labels from the dynamics, honest ends."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.driver.api import _skeleton_system
from nnm_solver.backbone.skeleton import skeleton


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


#: a softening chain: f2 / f1 = 2.91, so its backbone meets 3:1 (with its partner's hardening... none: linear
#: partner) early and 5:1 just below the escape saddle of the cubic spring k3 = -1 N/m^3
K_SOFT = np.array([[1.3, -0.3], [-0.3, 10.9]])


def soft_chain():
    return nnm.Model(np.eye(2), K_SOFT, springs=[nnm.CubicSpring(dof=0, k3=-1.0)])


def saddle_energy():
    """Energy (J) of the static saddle of the soft chain (independent of any dynamics): K x = (x0^3, 0) gives
    x1 = 0.3 x0 / 10.9 and x0^2 = 1.3 - 0.09 / 10.9; E = x K x / 2 - x0^4 / 4."""
    x0 = np.sqrt(1.3 - 0.09 / 10.9)
    x = np.array([x0, 0.3 * x0 / 10.9])
    assert np.allclose(K_SOFT @ x, [x0 ** 3, 0.0])
    return 0.5 * x @ K_SOFT @ x - x0 ** 4 / 4


def test_skeleton_is_the_backbone_family_and_knows_where_the_band_is_left():
    """The 2-DOF benchmark's NNM 1: the skeleton (H = 9) reaches REACH x energy_max with rising energies, and its
    frequencies equal gauss6 shooting's (an independent method) to 1e-5 from 1e-3 to 1e3 J; its orbit at an energy,
    corrected, is there (frequency_of_orbit: the interpolated frequency to 1e-6)."""
    model = two_dof()
    sk = skeleton(model, 1, 3e5, _skeleton_system)
    assert sk.end == "reach" and np.all(np.diff(sk.energy) > 0) and sk.energy[-1] >= 3e6
    b = nnm.continue_nnm(model, 1, 1e3, integrator="gauss6", steps_per_period=100, floquet=False)
    dev = [abs(f / sk.frequency_at(E) - 1) for E, f in zip(b.energy, b.frequency_hz)]
    assert max(dev) < 1e-5 and set(b.labels) == {"backbone"}
    for E in (1.0, 30.0, 900.0):
        assert abs(sk.frequency_of_orbit(E) / sk.frequency_at(E) - 1) < 1e-6 and sk.is_family(E, sk.frequency_at(E))


def test_softening_chain_escape_just_above_a_five_to_one_tongue():
    """The soft chain: the default branch locks into a 3:1 tongue with mode 2 at 0.068 J (3 f = f2) and follows it
    to energy_max: those points are labelled tongue (the skeleton's family softens on), and 'done' says it ends
    inside a tongue.  tongues="skip" jumps the 3:1 from the skeleton, follows the softening backbone through the
    higher odd tongues with mode 2 that crowd below the family's energy maximum (k f = f2 as f falls towards 0 at the
    saddle) and ends 'escape' in one of them, near the static saddle energy.  Measured: the 5:1 at 0.4045 J jumped
    from the skeleton, escape in the 7:1 at 0.4169 J (the saddle 0.41715 J; before the skeleton's one-harmonic
    guide, escape in the 5:1 at 0.4061 J, the skeleton's peak then 0.4091 J)."""
    model = soft_chain()
    f1, f2 = model.linear_modes()[0]
    E_s = saddle_energy()
    default = nnm.continue_nnm(model, 1, 0.5, integrator="gauss6", steps_per_period=100, floquet=False)
    assert default.status == "done" and "off the backbone family" in default.message
    locked = default.energy > 0.07
    assert locked.sum() >= 3 and set(default.labels[locked]) == {"tongue 3:1"}
    assert np.all(np.abs(3 * default.frequency_hz[locked] / f2 - 1) < 3e-3)       # 3 f locked at f2
    assert set(default.labels[default.energy < 0.06]) == {"backbone"}
    skip = nnm.continue_nnm(model, 1, 0.5, integrator="gauss6", steps_per_period=100, floquet=False, tongues="skip")
    assert skip.status == "escape", skip.message
    k = int(skip.message.split(":1 internal-resonance")[0].split()[-1])
    assert k >= 5 and k % 2 == 1 and "mode 2" in skip.message and "energy maximum" in skip.message
    assert all(t["label"] == f"tongue {2 * i + 3}:1" for i, t in enumerate(skip.tongues))     # 3:1, 5:1, ... in turn
    assert set(skip.labels) == {"backbone"} and abs(skip.energy.max() / E_s - 1) < 0.05
    first = skip.tongues[0]
    assert first["label"] == "tongue 3:1" and first["skipped"] and "skeleton" in first["jump"]
    assert first["attempts"] <= 4 * (first["reentries"] + 1)          # a few orbits per jump (measured: 7 for 3 jumps)
    # the skip-backbone and the fixed-amplitude HB sweep (the skeleton) agree across both tongues
    sk = skeleton(model, 1, 0.5, _skeleton_system)
    dev = [abs(f / sk.frequency_at(E) - 1) for E, f in zip(skip.energy, skip.frequency_hz) if sk.covers(E)]
    assert len(dev) >= len(skip) - 2 and max(dev) < 1e-3 and np.median(dev) < 1e-5
    assert skip.frequency_hz.min() < 0.6 * f1                                      # far down the softening backbone


def test_two_dof_skip_backbone_traverses_its_three_to_one_tongue():
    """NNM 1 of the 2-DOF benchmark to 3e5 J with tongues="skip" (its partner hardens with the amplitude: the
    linear partner frequency does not locate the band, the skeleton gives no target).  gauss6: done, every
    point labelled backbone, the 3:1 tongue recorded and the 5:1 passed by rescaled orbits.  Harmonic balance
    (H = 9): done too, or, where a tongue cannot be jumped that way, the branch says so (status 'tongue', not
    'done' or 'failed')."""
    b = nnm.continue_nnm(two_dof(), 1, 3e5, tongues="skip", floquet=False, integrator="gauss6", steps_per_period=100)
    assert b.status == "done", b.message
    assert set(b.labels) == {"backbone"}
    labels = [t["label"] for t in b.tongues]
    assert labels[0] == "tongue 3:1" and "tongue 5:1" in labels
    # beyond a jump the continuation goes on up in energy: a restart along the old backbone's tangent could point
    # down at the landing orbit, re-enter the tongue just jumped and crawl on by one jump per point (measured:
    # the 9:1 tongue entered 10 times, 20 times with HB; now at most 4, the 3:1's, whose partner hardens so that
    # the skeleton gives no target beyond it)
    assert max(t.get("reentries", 0) for t in b.tongues) <= 5, [(t["label"], t.get("reentries")) for t in b.tongues]
    for kw in (dict(condensed=True), dict()):
        h = nnm.continue_nnm(two_dof(), 1, 3e5, tongues="skip", floquet=False, method="hb", freq_tol=None, harmonics=9, **kw)
        assert h.status in ("done", "tongue"), h.message
        if h.status == "tongue":
            assert "5:1" in h.message and "mode 2" in h.message and h.energy.max() < 3e5
        assert h.tongues[0]["label"] == "tongue 3:1" and set(h.labels) == {"backbone"}
        assert max(t.get("reentries", 0) for t in h.tongues) <= 5, [(t["label"], t.get("reentries")) for t in h.tongues]


@pytest.mark.slow
def test_aircraft_mode_20_skip_backbone_jumps_its_first_tongue_from_the_skeleton():
    """The Paris-like aircraft's mode 20 with the default settings (gauss6 at 100 steps): its 3:1 tongues with mode
    42 are jumped from the skeleton's orbits; the backbone softens beyond -4 % on points labelled backbone before its
    family ends in that 3:1 resonance (status 'tongue', the family's end near 5.2 J)."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    f20 = model.linear_modes()[0][19]
    b = nnm.continue_nnm(model, 20, 12.0, tongues=nnm.Skip(), floquet=False)
    # its family ends in a 3:1 with mode 42 or, past it, with mode 41 (0.937 x 3 f20): which of the two narrow
    # resonances takes the orbit over changes with round-off (the shipped run with multipliers: 42 at 6.2 J)
    assert b.status == "tongue" and ("mode 42" in b.message or "mode 41" in b.message), b.message
    first = b.tongues[0]
    assert first["label"] == "tongue 3:1" and first["skipped"] and "skeleton" in first["jump"], first.get("jump")
    assert set(b.labels) == {"backbone"} and b.frequency_hz.min() / f20 - 1 < -0.04


@pytest.mark.slow
def test_aircraft_mode_10_ends_where_its_family_ends_not_failed():
    """The aircraft's mode 10 (default settings, to 200 J): its skeleton (H = 9) ends at an internal resonance
    (builder 1.3: a 3:1 with mode 14 near 12 J) and the shooting continuation cannot go beyond it.  The branch says
    so (status 'tongue', the family's end and the skeleton's partner named, the last record of branch.tongues not
    jumped) instead of 'failed', and its points below 80 % of its last energy lie on the skeleton to 1e-5."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    b = nnm.continue_nnm(model, 10, 200.0, tongues=nnm.Skip(), floquet=False)
    sk = skeleton(model, 10, 200.0, _skeleton_system)
    # near 12 J the family meets the 3:1 with mode 14 just below its energy maximum: by round-off (numpy/scipy
    # builds) the skeleton ends there 'stuck'/'locked' with the partner named or at its 'peak' (the fold of the
    # family), and the branch 'tongue' (the partner named) or 'escape' (the family's energy maximum named)
    assert sk.end in ("stuck", "locked", "peak"), sk.end
    if sk.end == "peak":
        assert b.status in ("escape", "tongue") and "family" in b.message, b.message
    else:
        # the skeleton's end is named; the continuation may stop in a narrower resonance just below it (builder
        # 1.3: a 9:1 with mode 32 near 12 J, jumped or not depending on round-off), never beyond it
        assert sk.partner[0] >= 3
        assert b.status == "tongue" and "family" in b.message and f"mode {sk.partner[1]}" in b.message, b.message
    assert b.status != "failed" and not b.tongues[-1]["skipped"] and b.energy.max() <= sk.energy[-1] * (1 + 1e-6)
    assert b.energy.max() >= 0.8 * sk.energy[-1]
    low = [abs(b.frequency_hz[i] / sk.frequency_at(b.energy[i]) - 1) for i in range(len(b))
           if b.energy[i] < 0.8 * b.energy.max()]
    assert len(low) >= 8 and max(low) < 1e-5
    if b.tongues[-1].get("family_end"):
        with pytest.raises(nnm.NNMInputError, match="family ends"):
            nnm.continue_tongue(b, len(b.tongues) - 1)


def test_two_dof_hb_skip_jumps_the_three_to_one_onto_the_backbone_the_default_branch_returns_to():
    """Harmonic balance (H = 9, condensed) to 2e4 J: the default branch traverses the 3:1 tongue (its points there
    labelled tongue, off the skeleton by ~1 %) and comes back onto the backbone; tongues="skip" jumps the tongue
    from the skeleton's orbit in at most 3 attempts.  Above the tongue both branches lie on the same family: the
    skip branch's points and the default branch's backbone (an independent path through the tongue) lie on the
    skeleton's family to 1e-6 (from 10 % above the last landing: next to a tongue, 1e-5 to 1e-4)."""
    default = nnm.continue_nnm(two_dof(), 1, 2e4, method="hb", freq_tol=None, harmonics=9, condensed=True, floquet=False)
    assert default.status == "done" and "tongue 3:1" in set(default.labels)
    assert default.labels[-1] == "backbone" and "off the backbone" not in default.message
    skip = nnm.continue_nnm(two_dof(), 1, 2e4, method="hb", freq_tol=None, harmonics=9, condensed=True, tongues="skip", floquet=False)
    assert skip.status == "done", skip.message
    t = skip.tongues[0]
    assert t["label"] == "tongue 3:1" and t["partner_mode"] == 2 and t["skipped"] and "skeleton" in t["jump"]
    assert t["attempts"] <= 3 and set(skip.labels) == {"backbone"}
    back = np.flatnonzero(default.labels == "backbone")
    above = back[back > np.flatnonzero(default.labels != "backbone").max()]       # after the traversal
    sk = skeleton(two_dof(), 1, 2e4, _skeleton_system, 9)
    on_family = [abs(b.frequency_hz[i] / sk.frequency_at(b.energy[i]) - 1) for b, idx in
                 ((default, above), (skip, np.flatnonzero(skip.energy > 1.1 * skip.tongues[-1]["exit_energy"])))
                 for i in idx]
    assert len(above) >= 3 and len(on_family) >= 6 and max(on_family) < 1e-6


def test_is_fold_tells_a_missing_harmonic_from_a_partner_harmonic():
    """tongue_skip.is_fold: an orbit with no third harmonic (a single-harmonic balance) has no 3:1 partner to
    name; a third harmonic of 1e-3 of the fundamental is one."""
    from nnm_solver.backbone.content import is_fold
    t = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
    Q = np.column_stack([np.cos(t), 0.1 * np.cos(t)])
    assert is_fold(Q, 3)
    Q[:, 1] += 1e-3 * np.cos(3 * t)
    assert not is_fold(Q, 3) and not is_fold(Q, 1)


def test_single_harmonic_backbones_end_at_their_fold_not_in_a_tongue_with_their_own_mode():
    """Condensed HB at H = 1 (no harmonic k >= 2: no k:1 internal resonance can exist) on the shipped aircraft,
    tongues='skip'.  Modes 20 and 10 soften up to the springs' saddle, where the single-harmonic family folds (its
    skeleton at H = 1 ends at its energy maximum, end 'peak', the amplitude stepping failing with no partner in
    the orbit): status 'escape', no tongue recorded, every point backbone.  It used to record a '3:1 tongue with
    mode 20' there (the argmax of round-off harmonics) and, on a slower solver path, jump onto another family
    above the saddle and report 'done'.  Mode 19's branch turns back below its family's end: such departures are
    recorded as 'fold' (order 1, no partner) or, where the skeleton ends in a 1:1 resonance, as that resonance with
    its partner (builder 1.4: mode 18), never as a tongue with its own mode."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    f_lin = model.linear_modes()[0]
    for mode in (20, 10):
        b = nnm.continue_nnm(model, mode, 20.0, method="hb", freq_tol=None, harmonics=1, condensed=True, floquet=False,
                             tongues="skip")
        sk = skeleton(model, mode, 20.0, _skeleton_system, 1)
        assert sk.end == "peak" and sk.energy_peak is not None, sk.message
        assert b.status == "escape" and "energy maximum" in b.message, b.message
        assert b.tongues == [] and set(b.labels) == {"backbone"}
        assert 0.8 * sk.energy_peak <= b.energy.max() <= sk.energy_peak * 1.01
        assert b.frequency_hz[-1] < 0.99 * f_lin[mode - 1] and abs(b.frequency_hz[0] / f_lin[mode - 1] - 1) < 1e-4
    b = nnm.continue_nnm(model, 19, 20.0, method="hb", freq_tol=None, harmonics=1, condensed=True, floquet=False, tongues="skip")
    # builder 1.4: its family ends in a 1:1 resonance with mode 18 (the skeleton's end, a family_end record)
    assert b.tongues and all((t["label"] == "fold" and t["order"] == 1 and t["partner_mode"] == 0)
                             or (t["label"] == "tongue 1:1" and t.get("family_end") and t["partner_mode"] not in (0, 19))
                             for t in b.tongues), [(t["label"], t["partner_mode"]) for t in b.tongues]
    assert b.status in ("escape", "tongue") and "mode 19" not in b.message, b.message


@pytest.mark.parametrize("reach", [1e8, 1e9, 1e10])
def test_skeleton_starts_at_the_linear_mode_whatever_its_reach(reach):
    """The skeleton's first amplitude is 1e-6 of its reach in energy, lowered until the frequency is linear (to
    1e-8), then raised to where it has moved by START_SHIFT.  For a reach far above the family's interesting range
    (a tongue's continuation asks for 100x its entry energy, 10x that for the skeleton) that first amplitude has no
    solution from the linear guess: the start must go on lowering it (it stopped there, 'no harmonic-balance
    solution at the linear mode', leaving no skeleton).  The start is then the same whatever the reach."""
    from nnm_solver.backbone.skeleton import compute_skeleton
    from nnm_solver.backbone.settings import SkeletonSettings
    START_SHIFT = SkeletonSettings().start_shift
    from nnm_solver.model.modal import modal_system
    sk = compute_skeleton(modal_system(two_dof()), 1, reach)
    assert len(sk.energy) > 100 and "linear mode" not in sk.message
    shift = sk.frequency_hz[0] / (1 / (2 * np.pi)) - 1
    assert 0.1 * START_SHIFT < shift <= 2 * START_SHIFT and sk.energy[0] <= 1e-6 * reach
    other = compute_skeleton(modal_system(two_dof()), 1, 1e6)
    assert abs(sk.energy[0] / other.energy[0] - 1) < 1e-3


def test_a_follow_branch_skeleton_is_the_first_points_of_the_skip_one():
    """tongues='follow' steps the skeleton only to FOLLOW_REACH x energy_max (its labels), from the start of the
    REACH one (tongues='skip'): its points below energy_max are the longer one's, the same numbers, so the labels of
    a branch do not depend on the tongue mode it was computed in."""
    from nnm_solver.backbone.settings import SkeletonSettings
    FOLLOW_REACH, REACH = SkeletonSettings().follow_reach, SkeletonSettings().reach
    E_max = 3e5
    short = skeleton(two_dof(), 1, E_max, _skeleton_system, reach=FOLLOW_REACH)     # new models: no cache shared
    long_ = skeleton(two_dof(), 1, E_max, _skeleton_system, reach=REACH)
    assert short.end == "reach" and FOLLOW_REACH * E_max <= short.energy[-1] < REACH * E_max <= long_.energy[-1]
    k = int(np.searchsorted(short.energy, E_max))
    assert k > 100 and len(long_.energy) > len(short.energy)
    assert np.array_equal(short.energy[:k], long_.energy[:k]) and np.array_equal(short.frequency_hz[:k], long_.frequency_hz[:k])
    E = np.geomspace(1e-3, E_max, 40)
    assert [short.truncation_at(x) for x in E] == [long_.truncation_at(x) for x in E]


def test_two_dof_backbone_past_its_five_to_one_tongue_is_labelled_backbone():
    """Past the 5:1 tongue (entry fold 109148 J) the 2-DOF's NNM 1 backbone goes on at 0.2236 Hz at 1.5e5 J rising
    smoothly (HB with one harmonic, where no tongue exists, agrees to 1e-4 up to 4.4e5 J).  The follow branch's
    points there must be labelled backbone whatever energy_max; with 1e6 J they were labelled 'tongue 1:1' (the
    skeleton, stepped onto a tongue's sheet, ended 'locked' at 1.32e5 J) before the one-harmonic guide."""
    model = two_dof()
    b = nnm.continue_nnm(model, 1, 1e6, floquet=False)
    h1 = nnm.continue_nnm(model, 1, 2e6, method="hb", freq_tol=None, harmonics=1, floquet=False)
    E, f = np.asarray(b.energy), np.asarray(b.frequency_hz)
    beyond = np.flatnonzero((E > 1.4e5) & (E < 4.5e5) & (np.arange(len(E)) > np.argmax(E > 1.0914e5)))
    f1 = np.interp(E[beyond], h1.energy, h1.frequency_hz)
    on = beyond[np.abs(f[beyond] / f1 - 1) < 1e-3]          # the branch's points on the one-harmonic backbone
    assert len(on) >= 2
    assert all(b.labels[i] == "backbone" for i in on)


@pytest.mark.parametrize("reach", [3e6, 1e7, 1e8, 1e9])
def test_two_dof_skeleton_past_its_tongues_is_the_same_backbone_whatever_its_reach(reach):
    """The 2-DOF's NNM 1 meets its 3:1 (~2 kJ), 5:1 (~5e4 J) and further tongues (~4e5 J, ~6e6 J) on the way up.
    Whatever the reach (which places the steps), the skeleton reaches it and, away from those tongues, lies on
    one family: near the one-harmonic family's (no tongue possible there; 1e-3, measured 1.7e-4 to 3.6e-4) with
    less than 0.5 % of the orbit in partner harmonics, and, at 1.5e5 and 1e6 J, shooting's
    backbone past the 5:1 tongue (the follow branch's 0.223604 Hz at 1.47e5 J; HB H = 9 of the guide's scan,
    0.224278 Hz at 1e6 J) to 1e-4.  Before the guide the skeleton jumped onto orbits at 0.2249 Hz with 10 % of a
    partner harmonic past 1.3e5 J (reaches 3e6, 1e8, 1e9 J) or ended 'locked' there (1e7 J)."""
    from nnm_solver.backbone.amplitude_family import family_share
    from nnm_solver.backbone.settings import SkeletonSettings
    from nnm_solver.backbone.skeleton import compute_skeleton
    from nnm_solver.model.modal import modal_system
    sk = compute_skeleton(modal_system(two_dof()), 1, reach)
    assert sk.end == "reach", sk.message
    h1 = compute_skeleton(modal_system(two_dof()), 1, 3e7, SkeletonSettings(harmonics=1))
    for E in (1e4, 1.5e5, 2.5e5, 1e6, 3e6):
        assert abs(sk.frequency_at(E) / h1.frequency_at(E) - 1) < 1e-3, E
        i = int(np.searchsorted(sk.energy, E))
        assert family_share(sk.problem, sk.orbits[i]) > 0.995, E      # no partner harmonic takes a share
    assert abs(sk.frequency_at(147310.0) / 0.223604 - 1) < 1e-4
    assert abs(sk.frequency_at(1e6) / 0.224278 - 1) < 1e-4


def _chain3(spring):
    K = 2 * np.eye(3) - np.eye(3, k=1) - np.eye(3, k=-1)
    return nnm.Model(np.eye(3), K, springs=[spring])


def test_three_dof_chain_skeleton_past_a_three_to_one_tongue_is_where_the_branch_returns():
    """A 3-DOF chain with a cubic spring between masses 1 and 2, NNM 2 (0.2251 Hz linear, hardening): its follow
    branch (HB, 15 harmonics: another truncation than the skeleton's 9) goes through a 3:1 tongue (entered at
    ~1 kJ, up to 1.4 kJ and down to 460 J) and comes back onto the backbone at ~725 J.  The skeleton moves onto the
    backbone's sheet there (0.2432 Hz at 1 kJ) and the branch's points after the tongue lie on it to 1e-4, labelled
    backbone; the skeleton before its one-harmonic guide stayed on the tongue's sheet (0.2439 Hz at 1 kJ, 2.8e-3
    off the branch that had come back)."""
    model = _chain3(nnm.CubicSpring(dof=0, other=1, k3=2.0))
    b = nnm.continue_nnm(model, 2, 1e4, method="hb", freq_tol=None, harmonics=15, floquet=False)
    assert b.status == "done", b.message
    E, f = np.asarray(b.energy), np.asarray(b.frequency_hz)
    inside = np.flatnonzero(b.labels == "tongue 3:1")
    assert len(inside) and E[inside].max() < 2e3
    above = np.arange(inside.max() + 1, len(E))                 # after the traversal: back on the backbone
    sk = skeleton(model, 2, 1e4, _skeleton_system)
    assert len(above) >= 5 and set(b.labels[above]) == {"backbone"} and E[above].min() < 1e3
    assert max(abs(f[i] / sk.frequency_at(E[i]) - 1) for i in above) < 1e-4


def test_soft_three_dof_chain_skeleton_keeps_its_family_where_the_one_harmonic_guide_fails():
    """A softening 3-DOF chain (cubic spring -0.5 at mass 1), NNM 1: past ~0.85 J the one-harmonic family lies more
    than 2 % from the skeleton (18 % near its own fold at 1.3 J) and says nothing about sheets there (GUIDE_TRUST).
    The skeleton goes on along its family, continuous in frequency (steps < 3 %), into the 3:1 internal resonance
    with mode 3 that takes it over (locked above 1.5 J; the follow branch's points up to 1.3 J lie on it).  Trusting
    the guide there, it had moved onto orbits at 0.045 Hz (half the family's frequency) at 1.05 J."""
    from nnm_solver.backbone.skeleton import compute_skeleton
    from nnm_solver.model.modal import modal_system
    model = _chain3(nnm.CubicSpring(dof=0, k3=-0.5))
    sk = compute_skeleton(modal_system(model), 1, 5.0)
    assert sk.end == "locked" and sk.partner == (3, 3) and sk.energy[-1] > 1.5, sk.message
    assert np.max(np.abs(np.diff(np.log(sk.frequency_hz)))) < 0.03
    b = nnm.continue_nnm(model, 1, 1.3, floquet=False, integrator="gauss6", steps_per_period=100)
    on = np.asarray(b.energy) > 0.5
    assert max(abs(f / sk.frequency_at(E) - 1) for E, f in zip(b.energy[on], b.frequency_hz[on])) < 1e-3


def test_a_skeleton_with_no_point_says_why_instead_of_failing():
    """A skeleton whose stepping found no orbit (amplitude_family's 'stuck' at the linear mode) is an empty Skeleton
    with its end and message (it raised IndexError building its sheet starts from an empty float array)."""
    from nnm_solver.backbone.skeleton import Skeleton
    s = Skeleton(None, [], [], [], [], "stuck", "no harmonic-balance solution at the linear mode", [], (1, 0), 1)
    assert len(s.energy) == 0 and s.sheet_starts == [] and s.end == "stuck"


def test_aircraft_mode_19_skeleton_ends_where_its_family_ends_whatever_energy_max():
    """The skeleton's first amplitude follows energy_max (a fraction of the reach), so its points, and the steps that
    meet a resonance, change with it.  The aircraft's mode 19 folds in amplitude at 6.2 J, where its energy folds and
    recovers as mode 18's motion grows (1:1).  Before, with energy_max 10 J the step past 6.11 J landed on a 9:1
    tongue's sheet with mode 238 (an orbit of 9.6e5 J at the same frequency, a partner holding the whole orbit) and
    the stepping read it as the reach: no end, and the backbone went on into that tongue; a step taken over by a
    partner is now shortened first and its share read before the reach, and the family's own fold is looked for
    past it.  Every energy_max gives the same end, energy and frequency."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    ends = []
    for energy_max in (3.0, 10.0, 200.0):
        sk = skeleton(model, 19, energy_max, _skeleton_system)
        assert sk.end == "locked" and sk.partner == (1, 18), (energy_max, sk.end, sk.partner, sk.message)
        ends.append((sk.energy[-1], sk.frequency_hz[-1]))
    E, f = np.array(ends).T
    assert np.ptp(E) / E[0] < 1e-3 and np.ptp(f) / f[0] < 1e-6 and 6.1 < E[0] < 6.3, ends
