"""Branch tools (nnm_solver.analysis): harmonic content, tongues, MAC between orbits."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver import analysis as A
from nnm_solver.errors import NNMInputError


# ---------------------------------------------------------------------- orbits with a known answer
def one_three_branch(a, b, m1=1.0, m2=1.0, spp=4000):
    """A linear model whose two modes have frequencies 1 and 3 rad/s: the orbit released from rest at
    x0 = (a, b) is x1 = a cos t, x2 = b cos 3t, periodic with T = 2 pi; harmonic 1 lives on DOF 0 and
    harmonic 3 on DOF 1, so the mass-weighted amplitudes are sqrt(m1) a and sqrt(m2) b."""
    model = nnm.Model(np.diag([m1, m2]), np.diag([m1, 9.0 * m2]), [], name="1:3 linear")
    x0 = np.array([[a, b]], dtype=float)
    return nnm.Branch(model, 1, model.energy(x0, 0 * x0), [1 / (2 * np.pi)], [2 * np.pi], x0, 0 * x0,
                      settings=dict(method="shooting", steps_per_period=spp))


def test_dominant_harmonic_known_content():
    b = one_three_branch(0.55, 0.45)
    k, frac, fr, amps, k2, f2 = A.dominant_harmonic(b, 0)
    assert k == 1 and frac == pytest.approx(0.55, abs=2e-3)
    assert k2 == 3 and f2 == pytest.approx(0.45, abs=2e-3)
    assert amps[1] == pytest.approx(0.55, rel=2e-3) and amps[3] == pytest.approx(0.45, rel=2e-3)
    assert fr.sum() == pytest.approx(1.0) and fr[0] == 0 and np.all(fr[[2, 4, 5]] < 2e-3)
    # a single DOF sees only its own harmonic
    assert A.dominant_harmonic(b, 0, dof=1)[:2] == (3, pytest.approx(1.0, abs=2e-3))
    assert A.dominant_harmonic(b, 0, dof=0)[:2] == (1, pytest.approx(1.0, abs=2e-3))
    # the 3rd harmonic dominates when it is larger
    b = one_three_branch(0.2, 0.8)
    assert A.dominant_harmonic(b, 0)[:2] == (3, pytest.approx(0.8, abs=2e-3))


def test_dominant_harmonic_is_mass_weighted():
    # m1 = 4: harmonic 1 has mass-weighted amplitude 2 * 0.3 = 0.6 against 0.4 for harmonic 3
    b = one_three_branch(0.3, 0.4, m1=4.0)
    k, frac, *_ = A.dominant_harmonic(b, 0)
    assert k == 1 and frac == pytest.approx(0.6, abs=2e-3)
    # ... and the amplitude of a pure linear mode is its mass-normalised modal amplitude
    assert A.dominant_harmonic(one_three_branch(0.3, 0.0, m1=4.0), 0).amplitudes[1] == pytest.approx(0.6, rel=1e-3)


def test_describe_orbit_known_content():
    text = A.describe_orbit(one_three_branch(0.55, 0.45), 0)
    assert text.startswith("3:1 internal resonance: the 3rd harmonic carries 45 % of the amplitude")
    assert "linear mode 2" in text  # the 3rd harmonic lives on DOF 1 = linear mode 2 (MAC 1)
    text = A.describe_orbit(one_three_branch(0.1, 0.9), 0)
    assert text.startswith("3:1 internal resonance: the 3rd harmonic dominates with 90 %")
    assert A.describe_orbit(one_three_branch(0.98, 0.02), 0, with_mode=False) == \
        "fundamental NNM motion (harmonic 1 carries 98 %)"
    assert A.describe_orbit(one_three_branch(1.0, 0.0), 0) == "fundamental NNM motion (harmonic 1 carries 100 %)"


def test_harmonic_shape_and_orbit_shapes():
    b = one_three_branch(0.55, 0.45)
    np.testing.assert_allclose(A.harmonic_shape(b, 0, 1), [0.55, 0.0], atol=2e-3)
    np.testing.assert_allclose(A.harmonic_shape(b, 0, 3), [0.0, 0.45], atol=2e-3)
    np.testing.assert_allclose(A.orbit_shape(b, 0, "x0"), [0.55, 0.45])
    np.testing.assert_allclose(A.orbit_shape(b, 0, "peak"), [0.55, 0.45], atol=1e-9)  # t = 0 is the peak
    assert A.mac_orbits(b, 0, b, 0) == pytest.approx(1.0)
    c = one_three_branch(0.45, -0.55)
    assert A.mac_orbits(b, 0, c, 0, kind="x0") == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(NNMInputError):
        A.orbit_shape(b, 0, "nonsense")


# ---------------------------------------------------------------------- tongue geometry on synthetic data
def synthetic_branch(E):
    model = nnm.Model(np.eye(2), np.diag([1.0, 9.0]), [])
    N = len(E)
    x0 = np.column_stack([np.ones(N), np.zeros(N)])
    return nnm.Branch(model, 1, E, np.linspace(1.0, 1.1, N), 1 / np.linspace(1.0, 1.1, N), x0, 0 * x0)


def synthetic_fractions(sec, k=3, n=7):
    F = np.zeros((len(sec), n + 1))
    F[:, 1] = 1 - np.asarray(sec)
    F[:, k] = sec
    return F


def test_find_tongues_geometry():
    #            0  1  2   3   4   5   6  7  8   9  10  11  12  13  14  15  16  17
    E = np.array([1, 2, 4, 8, 16, 12, 6, 3, 5, 10, 9, 8.5, 9.5, 12, 20, 40, 30, 20.0])
    sec = np.array([0, 0, .01, .02, .05, .1, .3, .9, .3, .12, .1, .08, .06, .05, .03, .02, .05, .09])
    b = synthetic_branch(E)
    t = A.find_tongues(b, fractions=synthetic_fractions(sec), with_mode=False)
    assert len(t) == 2
    t31 = t[0]
    assert (t31.label, t31.order, t31.start, t31.tip, t31.end) == ("3:1", 3, 4, 7, 14)
    assert t31.complete and t31.kind == "fold"
    assert t31.energy_range == (3.0, 16.0) and t31.tip_energy == 3.0
    assert t31.tip_fraction == pytest.approx(0.9)
    assert t31.middle(b) == 6  # the 3rd harmonic's share 0.3 is nearest to half of 0.9
    # the branch ends on the way down from the fold at 15: an open tongue (harmonic share 0.02 -> 0.09)
    op = t[1]
    assert (op.start, op.tip, op.end, op.complete) == (15, 17, 17, False)
    # the nested fold pair 10/11 is not a tongue of its own; with weak harmonic content everywhere the
    # folds are not tongues at all
    assert A.find_tongues(b, fractions=synthetic_fractions(np.full(len(E), 0.01)), with_mode=False) == []


def test_find_tongues_content_without_folds():
    E = np.geomspace(1, 100, 12)
    sec = np.zeros(12)
    sec[5:8] = [0.2, 0.4, 0.25]
    t = A.find_tongues(synthetic_branch(E), fractions=synthetic_fractions(sec, k=5), with_mode=False)
    assert len(t) == 1 and t[0].kind == "content" and t[0].label == "5:1" and t[0].tip == 6
    assert (t[0].start, t[0].end) == (5, 7) and not t[0].complete


# ---------------------------------------------------------------------- the 2-DOF benchmark
def test_two_dof_three_to_one_tongue(two_dof_nnm1):
    b = two_dof_nnm1
    tongues = A.find_tongues(b)
    assert [t.label for t in tongues] == ["3:1"]
    t = tongues[0]
    assert t.complete and t.kind == "fold"
    assert t.energy_range[1] == pytest.approx(4708, rel=0.02)   # entry fold (energy maximum)
    assert t.tip_energy == pytest.approx(286, rel=0.03)          # the tip
    assert t.tip_frequency_hz == pytest.approx(0.224, abs=1e-3)
    assert t.tip_fraction > 0.6 and t.mode == 2
    k, frac, *_ = A.dominant_harmonic(b, t.tip)
    assert k == 3 and frac > 0.6
    assert A.describe_orbit(b, t.tip).startswith("3:1 internal resonance")
    assert A.describe_orbit(b, 0).startswith("fundamental NNM motion (harmonic 1 carries 100 %")
    # along the way in, the 3rd harmonic's share grows monotonically towards the tip
    share = t.fractions[: t.tip - t.start + 1, 3]
    assert share[-1] > 5 * share[0] and np.all(np.diff(share) > -0.02)


def test_two_dof_mac(two_dof_nnm1):
    b = two_dof_nnm1
    _, Phi = b.model.linear_modes()
    assert nnm.mac(A.orbit_shape(b, 0), Phi[:, 0]) == pytest.approx(1.0, abs=1e-6)
    assert A.mac_orbits(b, 0, b, 1) == pytest.approx(1.0, abs=1e-6)
    # at the tongue's tip the shape has moved away from the low-energy NNM1
    tip = A.find_tongues(b, with_mode=False)[0].tip
    assert A.mac_orbits(b, 0, b, tip) < 0.9
    with pytest.raises(NNMInputError):
        one = nnm.Model(np.eye(1), np.eye(1), [])
        A.mac_orbits(b, 0, nnm.Branch(one, 1, [0.5], [1 / (2 * np.pi)], [2 * np.pi], [[1.0]], [[0.0]]), 0)


def test_find_tongues_towards_higher_energy():
    # softening-structure pattern: the branch climbs into the tongue, turns back at its tip (an energy
    # maximum), comes down to a fold and climbs again; then it ends on the way down a second tongue
    #            0  1  2  3  4   5   6   7   8  9  10  11  12   13   14   15   16
    E = np.array([1, 2, 4, 8, 9, 12, 20, 14, 7, 8, 16, 40, 90, 300, 280, 200, 150.0])
    sec = np.array([0, 0, .01, .05, .1, .3, .8, .3, .06, .05, .04, .1, .3, .6, .58, .57, .56])
    t = A.find_tongues(synthetic_branch(E), fractions=synthetic_fractions(sec, k=3), with_mode=False)
    assert [(x.start, x.tip, x.end, x.direction, x.complete) for x in t] == \
        [(2, 6, 8, "higher", True), (12, 13, 16, "higher", False)]
    assert t[0].energy_range == (7.0, 20.0) and t[0].middle() == 5
