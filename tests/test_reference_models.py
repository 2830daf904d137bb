"""Checks of the independent references in tests/reference_models.py (not of the solver)."""
import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
from scipy.special import ellipk

import nnm_solver as nnm
from reference_models import (EI_STRIP, RHOA_STRIP, beam_matrices, cantilever_beam, cantilever_frequencies_analytic,
                              force_jacobian, monodromy_ivp, multipliers_ivp, periodic_orbit_ivp,
                              softening_saddle_energy, tip_dof)


def test_default_strip_parameters():
    # 1 m x 20 mm x 5 mm steel strip: EI = 210e9 * 0.02 * 0.005^3 / 12, rhoA = 7800 * 0.02 * 0.005
    assert EI_STRIP == pytest.approx(43.75)
    assert RHOA_STRIP == pytest.approx(0.78)


def test_beam_linear_frequencies_match_analytic_cantilever():
    beam = cantilever_beam(n_el=12)
    assert beam.n == 24
    f, _ = beam.linear_modes()
    fa = cantilever_frequencies_analytic(3)
    assert fa[0] == pytest.approx(4.191, abs=1e-3)            # a few Hz
    np.testing.assert_allclose(f[:3], fa, rtol=1e-3)           # < 0.1 % with 12 elements
    # the finite elements are stiff: frequencies converge from above
    assert np.all(f[:3] >= fa * (1 - 1e-9))


def test_beam_other_parameters_and_tip_spring():
    EI, rhoA, L = 2.0, 0.5, 2.0
    f, _ = cantilever_beam(n_el=12, length=L, EI=EI, rhoA=rhoA).linear_modes()
    np.testing.assert_allclose(f[:3], cantilever_frequencies_analytic(3, L, EI, rhoA), rtol=1e-3)
    # a linear tip spring stiffens mode 1; a very stiff one pins the tip: clamped-pinned beam, beta L = 3.9266
    f_pinned, _ = cantilever_beam(n_el=24, tip_spring_k=1e9).linear_modes()
    fa = 3.9266023120 ** 2 / (2 * np.pi) * np.sqrt(EI_STRIP / RHOA_STRIP)
    assert f_pinned[0] == pytest.approx(fa, rel=1e-3)


def test_beam_matrices_and_spring():
    M, K = beam_matrices(4)
    assert M.shape == K.shape == (8, 8)
    np.testing.assert_allclose(M, M.T)
    np.testing.assert_allclose(K, K.T)
    assert np.all(np.linalg.eigvalsh(M) > 0) and np.all(np.linalg.eigvalsh(K) > 0)
    beam = cantilever_beam(n_el=4, k3=-3.0)
    assert beam.k3.tolist() == [-3.0]
    assert beam.springs[0].dof == tip_dof(4) == 6
    x = np.zeros(8)
    x[6] = 0.1
    np.testing.assert_allclose(beam.nonlinear_force(x)[6], -3.0 * 0.1 ** 3)


def test_force_jacobian_by_differences():
    beam = cantilever_beam(n_el=3, k3=1e7)
    x = np.linspace(1e-3, 3e-3, beam.n)
    J = force_jacobian(beam, x)
    h = 1e-8
    Jfd = np.column_stack([(beam.nonlinear_force(x + h * e) - beam.nonlinear_force(x - h * e)) / (2 * h)
                           for e in np.eye(beam.n)])
    np.testing.assert_allclose(J, Jfd, rtol=1e-6, atol=1e-6 * np.abs(J).max())


def test_monodromy_of_linear_two_dof_is_expm():
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    model = nnm.Model(np.eye(2), K)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K, np.zeros((2, 2))]])
    x0, v0, T = np.array([0.3, -0.1]), np.array([0.05, 0.2]), 7.3
    Phi = monodromy_ivp(model, x0, v0, T)
    np.testing.assert_allclose(Phi, scipy.linalg.expm(A * T), rtol=0, atol=1e-9)
    # sparse M and K are accepted
    sp = nnm.Model(scipy.sparse.identity(2, format="csr"), scipy.sparse.csr_matrix(K))
    np.testing.assert_allclose(monodromy_ivp(sp, x0, v0, T), Phi, rtol=0, atol=1e-10)


def test_monodromy_of_linear_model_with_mass_matrix():
    # M != I: Phi = expm([[0, I], [-M^-1 K, 0]] T)
    M = np.array([[2.0, 0.5], [0.5, 1.0]])
    K = np.array([[3.0, -1.0], [-1.0, 2.0]])
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), np.zeros((2, 2))]])
    Phi = monodromy_ivp(nnm.Model(M, K), np.array([1.0, 0.0]), np.zeros(2), 4.0)
    np.testing.assert_allclose(Phi, scipy.linalg.expm(A * 4.0), rtol=0, atol=1e-9)


def duffing_period(A, k3=1.0):
    """Exact period of x'' + x + k3 x^3 = 0 (k3 > 0) released at rest from x = A."""
    w2 = 1.0 + k3 * A * A
    m = k3 * A * A / (2.0 * w2)
    return 4.0 * ellipk(m) / np.sqrt(w2)


def test_duffing_orbit_refinement_and_monodromy():
    duffing = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=1.0)])
    A = 1.0
    T_exact = duffing_period(A)
    # Newton from a perturbed period at fixed energy (x0 = A): the exact period
    x0, T, info = periodic_orbit_ivp(duffing, np.array([A]), np.zeros(1), T_exact * 1.02, return_info=True)
    assert x0[0] == pytest.approx(A, rel=1e-12)
    assert T == pytest.approx(T_exact, rel=1e-10)
    # fixed period: the amplitude is found
    x0p, Tp = periodic_orbit_ivp(duffing, np.array([0.9]), np.zeros(1), T_exact, fix="period")
    assert Tp == T_exact and x0p[0] == pytest.approx(A, rel=1e-9)

    Phi = monodromy_ivp(duffing, x0, np.zeros(1), T)
    assert np.linalg.det(Phi) == pytest.approx(1.0, abs=1e-8)
    # both multipliers are 1: the characteristic polynomial is (mu - 1)^2, i.e. trace 2 and det 1.
    # Phi is a Jordan block (the period changes with the energy), so the eigenvalues themselves
    # are only as accurate as the square root of the rounding: |mu - 1| ~ sqrt(1e-12).
    assert np.trace(Phi) == pytest.approx(2.0, abs=1e-8)
    mu = multipliers_ivp(duffing, x0, np.zeros(1), T)
    np.testing.assert_allclose(mu, [1.0, 1.0], atol=1e-5)
    np.testing.assert_allclose(np.abs(mu), 1.0, atol=1e-8)
    # ... and not the identity: the shear along the family is there
    assert np.abs(Phi - np.eye(2)).max() > 1e-2


def test_half_period_monodromy_of_reversible_orbit():
    two_dof = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])
    x0, T = periodic_orbit_ivp(two_dof, np.array([1.0, 1.0]), None, 2 * np.pi * 0.95)
    full = monodromy_ivp(two_dof, x0, np.zeros(2), T)
    np.testing.assert_allclose(monodromy_ivp(two_dof, x0, np.zeros(2), T, half=True), full, rtol=0,
                               atol=1e-8 * np.abs(full).max())
    mu = multipliers_ivp(two_dof, x0, np.zeros(2), T)
    assert np.prod(mu).real == pytest.approx(1.0, abs=1e-9)   # symplectic: det = 1


@pytest.mark.slow
def test_beam_orbit_multipliers_have_the_trivial_pair():
    # 4 elements: the explicit integrator's cost grows with the highest frequency (1.1 kHz here)
    beam = cantilever_beam(n_el=4, k3=1e7)
    tip = tip_dof(4)
    f_lin, shapes = beam.linear_modes()
    x0 = shapes[:, 0] * (2e-3 / shapes[tip, 0])             # tip 2 mm: ~10 % above the linear frequency
    x0, T, info = periodic_orbit_ivp(beam, x0, None, 1.0 / (1.1 * f_lin[0]), rtol=1e-10, return_info=True)
    assert info["iterations"] <= 8
    assert 1.05 < 1.0 / (T * f_lin[0]) < 1.15
    mu = multipliers_ivp(beam, x0, np.zeros(beam.n), T, rtol=1e-10, half=True)
    assert mu.shape == (2 * beam.n,)
    assert np.all(np.diff(np.abs(mu)) <= 1e-12)              # sorted by decreasing modulus
    assert np.abs(mu).max() < 1 + 1e-4                        # stable (on the unit circle)
    assert np.sort(np.abs(mu - 1.0))[1] < 1e-3                # the trivial pair at +1


def test_softening_saddle_energy():
    beam = cantilever_beam(k3=-1e7)
    E, w = softening_saddle_energy(beam, tip_dof(), -1e7)
    k_tip = 3 * EI_STRIP / 1.0 ** 3                           # static tip stiffness of a cantilever
    assert E == pytest.approx(k_tip ** 2 / (4e7), rel=1e-9)
    assert w == pytest.approx(np.sqrt(k_tip / 1e7), rel=1e-9)
