"""The backbone past internal resonances (issue 29): the single-harmonic skeleton, jumps from it, honest ends."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.driver.api import _skeleton_branch
from nnm_solver.driver.skeleton import skeleton


def two_dof():
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])


def test_skeleton_is_the_single_harmonic_backbone_and_knows_where_the_band_is_left():
    model = two_dof()
    sk = skeleton(model, 1, 3e5, _skeleton_branch)
    assert np.all(np.diff(sk.energy) > 0) and sk.energy[-1] >= 3e5
    assert sk.branch.settings.harmonics == 1 and sk.branch.settings.condensed
    # single-harmonic Duffing-like backbone: the frequency rises monotonically, no tongue
    assert np.all(np.diff(sk.frequency_hz) > 0) and set(sk.branch.labels) == {"backbone"}
    # a partner at 3 f(E_mid): the band is crossed at E_mid; targets where 3 f has left it by 0.3, 1, 3, 10 %
    E_mid = 1e3
    f_p = 3 * sk.frequency_at(E_mid)
    targets = sk.targets(E_mid / 2, 3, f_p)
    assert targets == sorted(targets) and 2 <= len(targets) <= 4 and targets[0] > E_mid   # (skeleton points: margins may share one)
    for E_t in targets:
        assert 3 * sk.frequency_at(E_t) / f_p - 1 >= 0.003                # past the band on the far side
    x0, T = sk.orbit_at(targets[0])
    assert np.isclose(model.energy(x0, np.zeros(2)), targets[0], rtol=0.05) and np.isclose(1 / T, sk.frequency_at(targets[0]))
    assert sk.targets(E_mid / 2, 3, 3 * sk.frequency_hz[-1] * 2) == []     # a band the skeleton never crosses
    assert sk.targets(2 * sk.energy[-1], 3, f_p) == []                          # above the skeleton's reach


def test_two_dof_skip_backbone_traverses_its_three_to_one_tongue():
    """NNM 1 of the 2-DOF benchmark to 3e5 J with tongues="skip" (its partner hardens with the amplitude: the
    linear partner frequency does not locate the band, the skeleton gives no target).  gauss6: done, every
    point labelled backbone, the 3:1 tongue recorded and the 5:1 passed by rescaled orbits.  Harmonic balance
    (H = 9) cannot jump the 5:1 that way: the branch says so (status 'tongue', not 'done' or 'failed')."""
    b = nnm.continue_nnm(two_dof(), 1, 3e5, tongues="skip", floquet=False, integrator="gauss6", steps_per_period=100)
    assert b.status == "done", b.message
    assert set(b.labels) == {"backbone"}
    labels = [t["label"] for t in b.tongues]
    assert labels[0] == "tongue 3:1" and "tongue 5:1" in labels
    for kw in (dict(condensed=True), dict()):
        h = nnm.continue_nnm(two_dof(), 1, 3e5, tongues="skip", floquet=False, method="hb", harmonics=9, **kw)
        assert h.status in ("done", "tongue"), h.message
        if h.status == "tongue":
            assert "5:1" in h.message and "mode 2" in h.message and h.energy.max() < 3e5
        assert h.tongues[0]["label"] == "tongue 3:1" and set(h.labels) == {"backbone"}


@pytest.mark.slow
def test_aircraft_mode_20_skip_backbone_jumps_its_five_to_one_from_the_skeleton():
    """The Paris-like aircraft's mode 20 (gauss6): the 5:1 tongue (tank mode 72) at 3.3 J is jumped from the
    skeleton's orbit (the family beyond both the 5:1 and the 3:1 band), not by a rescaled orbit; the backbone
    softens beyond -1 % on points labelled backbone."""
    from pathlib import Path
    model = nnm.load_model(Path(__file__).resolve().parents[1] / "assets" / "paris.h5")
    f20 = model.linear_modes()[0][19]
    b = nnm.continue_nnm(model, 20, 12.0, integrator="gauss6", steps_per_period=200, tongues="skip", floquet=False)
    assert b.status == "done", b.message
    first = b.tongues[0]
    assert first["label"] == "tongue 5:1" and first["skipped"] and "skeleton" in first["jump"]
    assert set(b.labels) == {"backbone"} and b.frequency_hz.min() / f20 - 1 < -0.01


def test_a_backbone_that_ends_inside_a_tongue_is_not_done():
    """energy_max inside the 3:1 tongue that skip mode traverses: status 'tongue', the message names the
    resonance and the partner, the points returned lie below the tongue's entry."""
    b = nnm.continue_nnm(two_dof(), 1, 2e4, method="hb", harmonics=9, condensed=True, tongues="skip", floquet=False)
    assert b.status == "tongue", b.message
    assert "3:1" in b.message and "mode 2" in b.message
    entry = b.tongues[0]["entry_energy"]
    assert b.energy.max() <= entry * (1 + 1e-9) < 2e4
    default = nnm.continue_nnm(two_dof(), 1, 2e4, method="hb", harmonics=9, condensed=True, floquet=False)
    assert default.status == "done" and "tongue 3:1" in set(default.labels)    # following the family is done
