"""Harmonic balance (nnm_solver.hb): exact Duffing period, analytic Jacobian, energy along the
orbit, and the cross-check of the shooting solver (NNM1/NNM2 backbones and the 3:1 tongue)."""
import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.special import ellipk

import nnm_solver as nnm
from nnm_solver.hb import continue_nnm_hb, hb_coefficients, hb_motion
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from nnm_solver.model.modal import modal_system
from nnm_solver.stability.events import stability_changes


def duffing_period(k, A):
    """Exact period (s) of x'' + x + k x^3 = 0 released from rest at x = A."""
    w2 = 1.0 + k * A ** 2
    m = k * A ** 2 / (2.0 * w2)
    return 4.0 * ellipk(m) / np.sqrt(w2)


def duffing(k=1.0):
    return nnm.Model([[1.0]], [[1.0]], [nnm.CubicSpring(dof=0, k3=k)])


def two_dof():
    return nnm.Model(np.eye(2), [[2.0, -1.0], [-1.0, 2.0]], [nnm.CubicSpring(dof=0, k3=0.5)])


@pytest.fixture(scope="module")
def nnm1_hb():
    """NNM1 of the 2-DOF benchmark by HB (with Hill's multipliers) up to 1e4 J, through the 3:1 tongue, at 11 harmonics
    throughout (freq_tol=None: the numbers below are this truncation's)."""
    return nnm.continue_nnm(two_dof(), 1, 1e4, nnm.HarmonicBalance(harmonics=11, tol=1e-10, freq_tol=None),
                            max_points=1000, floquet=True)


@pytest.fixture(scope="module")
def nnm1_shooting():
    return nnm.continue_nnm(two_dof(), 1, 1e4, steps_per_period=400, tol=1e-8)


def test_duffing_exponential_convergence_in_harmonics():
    """Odd-harmonic HB vs the exact elliptic period up to E = 2 J (k A^2 up to ~1.6)."""
    errors = {}
    for H in (3, 7, 11, 17):
        b = continue_nnm_hb(duffing(), 1, 2.0, harmonics=H, tol=1e-12, floquet=False)
        assert b.status == "done" and b.energy[-1] >= 2.0
        assert b.settings["method"] == "harmonic_balance"
        assert np.all(b.v0 == 0.0)  # cosine basis: t = 0 at zero velocity, x0 = amplitude
        errors[H] = np.max(np.abs(b.period / duffing_period(1.0, b.x0[:, 0]) - 1.0))
    # measured: 4.6e-4, 3.3e-7, 2.3e-10, 4e-14
    assert errors[3] < 1e-3 and errors[7] < 1e-6 and errors[11] < 1e-9 and errors[17] < 1e-12
    assert errors[3] > 1e3 * errors[11]  # exponential: ~x30 per added odd harmonic


@pytest.mark.parametrize("k", [-0.5, 0.3])
def test_duffing_full_basis_and_softening(k):
    E_max = 0.3 if k < 0 else 2.0  # softening: stay well below the separatrix (E = 1/(4|k|))
    b = continue_nnm_hb(duffing(k), 1, E_max, harmonics=17, basis="full", tol=1e-12)
    assert np.all(b.stable) and np.allclose(np.abs(b.floquet), 1.0, atol=1e-6)  # 1 DOF: mu = 1, 1
    assert b.status == "done"
    A = np.hypot(b.x0[:, 0], b.v0[:, 0] / (2 * np.pi * b.frequency_hz))  # v0 ~ 0 by the phase condition
    assert np.max(np.abs(b.v0)) < 1e-10
    assert np.max(np.abs(b.period / duffing_period(k, A) - 1.0)) < 1e-10
    h, sine, X = hb_coefficients(b, -1)
    assert np.max(np.abs(X[sine])) < 1e-10 and np.max(np.abs(X[h % 2 == 0])) < 1e-10


@pytest.mark.parametrize("basis", ["odd", "full"])
def test_jacobian_matches_finite_differences(basis):
    model = nnm.Model(np.diag([1.0, 2.0, 1.5]), [[3.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]],
                      [nnm.CubicSpring(dof=0, k3=0.7), nnm.CubicSpring(dof=2, other=1, k3=-0.3)])
    problem = HBProblem(modal_system(model), 1, HBBasis(5, basis))
    problem.q_ref = np.array([0.3, -0.8, 0.5])
    rng = np.random.default_rng(1)
    u = rng.normal(size=len(problem.basis) * 3 + 1)
    u[-1] = 1.3
    r, J = problem.jacobian(u)
    assert np.allclose(r, problem.residual(u))
    eps = 1e-6
    Jfd = np.column_stack([(problem.residual(u + eps * e) - problem.residual(u - eps * e)) / (2 * eps)
                           for e in np.eye(len(u))])
    assert np.max(np.abs(J - Jfd)) < 1e-7 * np.max(np.abs(J))


def test_energy_constant_along_the_hb_orbit():
    model = two_dof()
    b = continue_nnm_hb(model, 1, 10.0, harmonics=21, tol=1e-11, floquet=False)
    for i in (len(b) // 2, len(b) - 1):
        t, x, v = hb_motion(b, i, samples=97)
        E = model.energy(x, v)
        assert np.max(np.abs(E / b.energy[i] - 1.0)) < 1e-9
        assert np.allclose(x[0], b.x0[i]) and np.allclose(v[0], b.v0[i], atol=1e-12)


@pytest.mark.parametrize("mode", [1, 2])
def test_backbones_agree_with_shooting(mode):
    """Shooting (Newmark) vs HB at equal energy up to 10 J (before the 3:1 tongue of NNM1).

    Average-acceleration Newmark lengthens the period by (w h)^2 / 12 = (2 pi / spp)^2 / 12, so
    f_shooting / f_HB - 1 must be -(2 pi / spp)^2 / 12 to leading order (HB error < 1e-11 here).
    Measured: ratio 1.0000 at low energy; at 10 J 1.043 (NNM1) and 0.941 (NNM2), the Newmark error
    of a nonlinear orbit with its higher harmonics.
    """
    model = two_dof()
    spp = 200
    hb = continue_nnm_hb(model, mode, 20.0, harmonics=21, tol=1e-11, max_rel_step=0.1, floquet=False)
    sh = nnm.continue_nnm(model, mode, 10.0, steps_per_period=spp, tol=1e-10, integrator="newmark")
    assert hb.status == "done" and sh.status == "done"
    assert np.all(np.diff(hb.energy) > 0)
    f_hb = CubicSpline(np.log(hb.energy), hb.frequency_hz)(np.log(sh.energy))
    ratio = (sh.frequency_hz / f_hb - 1.0) / -((2 * np.pi / spp) ** 2 / 12)
    assert np.all(np.abs(ratio[:10] - 1.0) < 1e-3), ratio  # nearly linear: exactly the Newmark error
    assert np.all((ratio > 0.92) & (ratio < 1.08)), ratio
    assert abs(sh.frequency_hz[-1] / f_hb[-1] - 1) > 1e-5  # the comparison resolves the Newmark error


def test_nnm1_follows_the_3_to_1_tongue(nnm1_hb):
    """NNM1 continued to 1e4 J: energy up to a fold ~4.7e3 J, down the tongue to ~286 J (tip, 0.224 Hz),
    then up again (shooting at 400 steps per period: folds at 4687 J and 285.8 J; HB with 11 harmonics:
    4686 J and 284.8 J at 0.22400 Hz)."""
    b = nnm1_hb
    assert b.status == "done", b.message
    folds = [e for e in b.events if e["kind"] == "fold"]
    assert len(folds) >= 2
    top, tip = folds[0], folds[1]
    assert top["detail"] == "energy maximum" and 4.5e3 < top["energy"] < 4.9e3
    assert tip["detail"] == "energy minimum" and 270 < tip["energy"] < 300
    assert abs(tip["frequency_hz"] - 0.224) < 5e-4
    # at the tip the motion is dominated by NNM2 at three times the frequency
    h, sine, X = hb_coefficients(b, tip["index"])
    _, shapes = b.model.linear_modes()
    modal = X @ shapes  # (harmonics, modes) with M = I
    assert abs(modal[h == 3, 1][0]) > 5 * abs(modal[h == 1, 1][0])
    assert abs(modal[h == 3, 1][0]) > abs(modal[h == 1, 0][0])


def test_hill_stability_matches_shooting_floquet(nnm1_hb, nnm1_shooting):
    """Hill's method (HB) vs the monodromy of shooting: the same sequence of stability changes, at
    overlapping energy intervals, and the same largest multiplier on the unstable backbone."""
    hb, sh = nnm1_hb, nnm1_shooting
    assert sh.status == "done"
    low = hb.energy < 1.0
    assert np.all(hb.stable[low]) and np.allclose(np.abs(hb.floquet[low]), 1.0, atol=1e-6)
    bif_hb = stability_changes(hb.events)
    bif_sh = stability_changes(sh.events)
    assert [e["stability_change"] for e in bif_hb] == [e["stability_change"] for e in bif_sh]
    assert len(bif_hb) >= 6  # loss/gain on the backbone, on the tongue, after it
    for a, b in zip(bif_hb, bif_sh):  # the crossing lies between points index-1 and index on each branch
        ia, ib = a["index"], b["index"]
        lo_a, hi_a = sorted(hb.energy[ia - 1:ia + 1])
        lo_b, hi_b = sorted(sh.energy[ib - 1:ib + 1])
        assert lo_a <= hi_b * 1.02 and lo_b <= hi_a * 1.02, (a, b)
    # largest multiplier on the unstable part of the backbone (before the first fold)
    first_fold_hb = next(e["index"] for e in hb.events if e["kind"] == "fold")
    first_fold_sh = next(e["index"] for e in sh.events if e["kind"] == "fold")
    # (interpolated along shooting's branch, the denser one: HB's period cap is 10x shooting's, MAX_PERIOD_STEP)
    E_sh, mu_sh = sh.energy[:first_fold_sh], np.abs(sh.floquet[:first_fold_sh, 0])
    sel = (hb.energy[:first_fold_hb] > 80) & (hb.energy[:first_fold_hb] < 2000)
    assert sel.sum() >= 5
    mu_interp = CubicSpline(np.log(E_sh), np.log(mu_sh))(np.log(hb.energy[:first_fold_hb][sel]))
    mu_hb = np.abs(hb.floquet[:first_fold_hb, 0][sel])
    assert np.all(mu_hb > 1.5)
    assert np.max(np.abs(np.exp(mu_interp) / mu_hb - 1)) < 1e-2


def test_coefficients_recomputed_for_a_loaded_branch(nnm1_hb):
    b = nnm1_hb.subset(slice(0, 30))  # subset drops the stored coefficients, like save/load
    i = 25
    h, sine, X = hb_coefficients(b, i)
    assert np.allclose(X, nnm1_hb.hb_coefficients[i], atol=1e-9 * np.abs(X).max())
    assert np.allclose(X.sum(axis=0), b.x0[i])


@pytest.mark.parametrize("kwargs, match", [
    (dict(harmonics=0), "harmonics"),
    (dict(harmonics=2.5), "harmonics"),
    (dict(harmonics=7, samples=10), "samples"),
    (dict(basis="sine"), "basis"),
    (dict(tol=-1.0), "tol"),
    (dict(energy_min=5.0), "energy_min"),
])
def test_bad_input(kwargs, match):
    with pytest.raises(nnm.NNMInputError, match=match):
        continue_nnm_hb(duffing(), 1, 1.0, **kwargs)


def test_bad_mode_and_not_hb_branch():
    with pytest.raises(nnm.NNMInputError, match="mode"):
        continue_nnm_hb(two_dof(), 3, 1.0)
    sh = nnm.continue_nnm(duffing(), 1, 0.5, steps_per_period=50)
    with pytest.raises(nnm.NNMInputError, match="harmonic balance"):
        hb_coefficients(sh, 0)
