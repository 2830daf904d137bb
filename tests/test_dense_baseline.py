"""Checks of the dense textbook baseline (benchmarks/dense_baseline.py).

The baseline is the reference the optimised solver is benchmarked against, so it has to
be right: exact Duffing periods, exact (discrete) sensitivities, energy conservation.
"""
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipk

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import dense_baseline as db  # noqa: E402

M2 = np.eye(2)
K2 = np.array([[2.0, -1.0], [-1.0, 2.0]])
SPRINGS2 = [(0, None, 0.5)]


def duffing_period(k, A):
    """Exact period of x'' + x + k x^3 = 0 with amplitude A."""
    w2 = 1.0 + k * A ** 2
    m = k * A ** 2 / (2.0 * w2)
    return 4.0 * ellipk(m) / np.sqrt(w2)


@pytest.mark.parametrize("k", [1.0])
def test_duffing_frequency_matches_exact_period(k):
    r = db.dense_continue([[1.0]], [[1.0]], [(0, None, k)], mode=1, energy_max=2.0,
                          steps_per_period=200, tol=1e-9)
    assert r["stop_reason"] == "energy_max"
    assert len(r["energy"]) >= 4
    assert r["energy"][-1] >= 2.0
    # phase condition: starts at zero velocity, so x0 is the amplitude
    assert np.allclose(r["v0"], 0.0, atol=1e-12)
    A = r["x0"][:, 0]
    T_exact = duffing_period(k, A)
    rel = np.abs(r["period"] / T_exact - 1.0)
    # Newmark average acceleration elongates the period by ~(w h)^2 / 12 = 8e-5 at 200 steps
    assert np.all(rel < 2.5e-4), rel
    assert rel[0] == pytest.approx((2 * np.pi / 200) ** 2 / 12, rel=0.05)
    # energy reported = energy of the initial state
    assert np.allclose(r["energy"], 0.5 * A ** 2 + 0.25 * k * A ** 4)
    # hardening: frequency increases with energy
    assert np.all(np.diff(r["frequency_hz"]) > 0)
    # Floquet multipliers of a 1-DOF conservative periodic orbit: the trivial pair at +1
    assert np.allclose(r["floquet"], 1.0, atol=1e-4)


def test_duffing_period_converges_with_steps():
    """The discretisation error is O(h^2): halving h divides it by ~4."""
    k = 1.0
    errs = []
    for steps in (100, 200):
        r = db.dense_continue([[1.0]], [[1.0]], [(0, None, k)], mode=1, energy_max=0.0,
                              steps_per_period=steps, tol=1e-10, energy_start=None)
        # first point only (energy_max=0 stops at once); compare at its own amplitude
        errs.append(abs(r["period"][0] / duffing_period(k, r["x0"][0, 0]) - 1.0))
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.05)


def _fd_jacobian(z0, T, steps, eps=1e-6):
    B, k3 = db.spring_arrays(SPRINGS2, 2)
    D = np.zeros((4, 5))
    for i in range(5):
        dz = np.zeros(4)
        dT = 0.0
        if i < 4:
            dz[i] = eps
        else:
            dT = eps
        zp = db.newmark_shoot(M2, K2, B, k3, z0 + dz, T + dT, steps, sensitivity=False)["zT"]
        zm = db.newmark_shoot(M2, K2, B, k3, z0 - dz, T - dT, steps, sensitivity=False)["zT"]
        D[:, i] = (zp - zm) / (2 * eps)
    return D


def test_monodromy_matches_finite_differences_2dof():
    B, k3 = db.spring_arrays(SPRINGS2, 2)
    z0 = np.array([1.3, -0.4, 0.2, 0.7])          # strongly nonlinear, not periodic
    T, steps = 5.7, 120
    r = db.newmark_shoot(M2, K2, B, k3, z0, T, steps, sensitivity=True)
    D = _fd_jacobian(z0, T, steps)
    scale = np.max(np.abs(D))
    assert np.max(np.abs(r["monodromy"] - D[:, :4])) < 1e-7 * scale
    assert np.max(np.abs(r["dzdT"] - D[:, 4])) < 1e-7 * scale


@pytest.fixture(scope="module")
def nnm1_2dof():
    return db.dense_continue(M2, K2, SPRINGS2, mode=1, energy_max=3.0, tol=1e-9, steps_per_period=100)


def test_monodromy_of_converged_point_is_symplectic_and_has_trivial_multipliers(nnm1_2dof):
    r = nnm1_2dof
    assert r["stop_reason"] == "energy_max"
    assert r["energy"][-1] >= 3.0
    for mu in r["floquet"]:
        # conservative system: multipliers come in pairs (mu, 1/mu); two near +1
        assert np.sum(np.abs(mu - 1.0) < 1e-3) >= 2
        assert np.prod(mu).real == pytest.approx(1.0, abs=1e-8)
    # frequency starts at the linear NNM1 frequency 1/(2 pi) (+ Newmark elongation)
    assert r["frequency_hz"][0] == pytest.approx(1 / (2 * np.pi), rel=5e-4)
    # hardening spring on DOF 0
    assert np.all(np.diff(r["frequency_hz"]) > 0)
    assert np.all(np.diff(r["energy"]) > 0)


def test_discrete_orbit_conserves_energy_and_is_periodic(nnm1_2dof):
    r = nnm1_2dof
    B, k3 = db.spring_arrays(SPRINGS2, 2)
    z0 = np.concatenate([r["x0"][-1], r["v0"][-1]])
    T = r["period"][-1]
    orb = db.newmark_shoot(M2, K2, B, k3, z0, T, 100, sensitivity=False, orbit=True)
    E = np.array([db.energy(M2, K2, B, k3, x, v) for x, v in zip(orb["x"], orb["v"])])
    assert E[0] == pytest.approx(r["energy"][-1])
    # average acceleration is not exactly energy-conserving with a cubic force, but
    # its energy error stays small and bounded (no drift)
    assert np.max(np.abs(E / E[0] - 1.0)) < 1e-3
    assert abs(E[-1] / E[0] - 1.0) < 1e-8           # periodic orbit closes
    assert np.linalg.norm(orb["x"][-1] - orb["x"][0]) < 1e-8 * np.linalg.norm(z0)


def test_linear_system_energy_is_conserved_exactly():
    """For a linear system the trapezoidal rule conserves energy to round-off."""
    B, k3 = db.spring_arrays([], 2)
    z0 = np.array([0.3, -0.1, 0.05, 0.2])
    orb = db.newmark_shoot(M2, K2, B, k3, z0, 10.0, 157, sensitivity=False, orbit=True)
    E = np.array([db.energy(M2, K2, B, k3, x, v) for x, v in zip(orb["x"], orb["v"])])
    assert np.max(np.abs(E / E[0] - 1.0)) < 1e-12


def test_relative_spring_and_higher_mode():
    """Relative spring between DOFs and continuation of mode 2 of a 3-DOF chain."""
    M = np.diag([1.0, 2.0, 1.5])
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    springs = [(2, 1, 2.0)]
    r = db.dense_continue(M, K, springs, mode=2, energy_max=0.2, max_points=12, steps_per_period=100)
    lam = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
    assert r["frequency_hz"][0] == pytest.approx(np.sqrt(lam[1]) / (2 * np.pi), rel=5e-4)
    B, k3 = db.spring_arrays(springs, 3)
    for x, v, E in zip(r["x0"], r["v0"], r["energy"]):
        assert db.energy(M, K, B, k3, x, v) == pytest.approx(E)
        assert abs(v[r["phase_dof"]]) < 1e-7 * np.linalg.norm(np.concatenate([x, v]))
    # force check of the relative spring: f = k3 d^3 on DOF 2, -k3 d^3 on DOF 1
    x = np.array([0.1, 0.2, 0.5])
    assert np.allclose(db.nonlinear_force(B, k3, x), [0.0, -2.0 * 0.3 ** 3, 2.0 * 0.3 ** 3])
