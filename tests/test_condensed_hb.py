"""Harmonic balance condensed onto the nonlinear elements (orbits/condensed_hb.py) against the
uncondensed harmonic balance (a second implementation of the same equations), finite differences,
Hill's multipliers and independent reference models."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.condensed_hb import CondensedHBProblem
from nnm_solver.orbits.harmonic_balance import HBProblem
from nnm_solver.orbits.hb_basis import HBBasis
from reference_models import beam_matrices, tip_dof


def two_dof(k3=0.5):
    return nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=k3)])


def ecl_beam(n_el=20):
    """The ECL benchmark (../shared/reference): steel cantilever 0.7 m, 14 mm square, tip cubic spring 8e9 N/m^3."""
    a = 0.014
    M, K = beam_matrices(n_el, 0.7, 205e9 * a ** 4 / 12, 7800.0 * a * a)
    return nnm.Model(M, K, [nnm.CubicSpring(dof=tip_dof(n_el), k3=8e9)])


def two_springs_chain(n=6):
    """A chain of n unit masses with a cubic spring to ground at DOF 0 and one between DOFs 2 and 4."""
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    return nnm.Model(np.diag(1.0 + 0.1 * np.arange(n)), K,
                     [nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=4, k3=-0.3)])


def _at_energy_max(model, mode, energy_max, **kw):
    a = nnm.continue_nnm(model, mode, energy_max, method="hb", floquet=False, **kw)
    b = nnm.continue_nnm(model, mode, energy_max, method="hb", condensed=True, floquet=False, **kw)
    assert a.status == b.status == "done", (a.message, b.message)
    return a, b


@pytest.mark.parametrize("basis", ["odd", "full"])
def test_jacobian_matches_finite_differences(basis):
    model = two_springs_chain()
    system = modal_system(model)
    hb = HBBasis(5, basis)
    p = CondensedHBProblem(system, 1, hb)
    rng = np.random.default_rng(3)
    u, _ = p.start(0.7)
    u = u + 0.05 * rng.standard_normal(len(u)) * np.abs(u).max()
    u[-1] = 1.03
    r, J = p.jacobian(u)
    assert np.allclose(r, p.residual(u))
    Jfd = np.zeros_like(J)
    for i in range(len(u)):
        e = np.zeros(len(u))
        e[i] = 1e-6 * max(1.0, abs(u[i]))
        Jfd[:, i] = (p.residual(u + e) - p.residual(u - e)) / (2 * e[i])
    assert np.max(np.abs(J - Jfd)) < 1e-7 * max(1.0, np.max(np.abs(J)))


def test_two_dof_condensed_equals_uncondensed():
    """NNM 1 of the 2-DOF benchmark to 57 J (H = 7): the same frequency at energy_max to 1e-10, every point's
    reconstructed orbit solves the uncondensed HB equations, and the same energies as the model's."""
    model = two_dof()
    a, b = _at_energy_max(model, 1, 57.0, harmonics=7, tol=1e-12)
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-10
    system = modal_system(model)
    full = HBProblem(system, 0, HBBasis(7, "odd"))
    for i in range(0, len(b), 7):
        A = system.to_modal(b.coefficients_at(i))
        u = full.pack(A, 2 * np.pi * b.frequency_hz[i])
        assert full.error(u, full.residual(u)) < 1e-11
        assert np.isclose(full.energy(u), b.energy[i], rtol=1e-10)
    assert b.settings.condensed and not a.settings.condensed


@pytest.mark.parametrize("make, mode, energy_max, H", [(ecl_beam, 1, 0.5, 5), (two_springs_chain, 2, 0.3, 7)])
def test_condensed_equals_uncondensed_on_other_structures(make, mode, energy_max, H):
    model = make()
    a, b = _at_energy_max(model, mode, energy_max, harmonics=H)
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-10
    assert abs(b.frequency_hz[-1] / b.frequency_hz[0] - 1) > 1e-4            # a nonlinear stretch of the branch
    assert np.allclose(b.x0[-1], a.x0[-1], rtol=0, atol=1e-8 * np.abs(a.x0[-1]).max())


def test_full_basis_condensed_equals_uncondensed():
    model = two_springs_chain()
    a, b = _at_energy_max(model, 1, 0.4, harmonics=5, basis="full")
    assert abs(b.frequency_hz[-1] / a.frequency_hz[-1] - 1) < 1e-9


def test_multipliers_and_events_are_those_of_the_uncondensed_orbits():
    """Hill's multipliers of the reconstructed orbit equal the uncondensed ones, so the located events do."""
    model = two_dof()
    a = nnm.continue_nnm(model, 1, 45.0, method="hb", harmonics=5, floquet=True)
    b = nnm.continue_nnm(model, 1, 45.0, method="hb", harmonics=5, condensed=True, floquet=True)
    assert a.status == b.status == "done"
    ka = [(e["kind"], e["energy"]) for e in a.events]
    kb = [(e["kind"], e["energy"]) for e in b.events]
    assert [k for k, _ in ka] == [k for k, _ in kb] and len(kb) >= 1
    for (_, ea), (_, eb) in zip(ka, kb):
        assert abs(eb / ea - 1) < 1e-6
    assert np.array_equal(a.stable[[0, -1]], b.stable[[0, -1]])
    system = modal_system(model)
    p = CondensedHBProblem(system, 0, HBBasis(5, "odd"))
    full = HBProblem(system, 0, HBBasis(5, "odd"))
    A = system.to_modal(b.coefficients_at(len(b) - 1))
    u_full = full.pack(A, 2 * np.pi * b.frequency_hz[-1])
    D = HBBasis(5, "odd")
    u = p.pack(A @ system.Bq.T, A[0, 0], 2 * np.pi * b.frequency_hz[-1])
    assert D.harmonics == 5
    mu_c = np.sort_complex(p.multipliers(u))
    mu_f = np.sort_complex(full.multipliers(u_full))
    assert np.allclose(mu_c, mu_f, atol=1e-8)


def test_bad_condensed_option_is_one_clear_error():
    with pytest.raises(nnm.NNMInputError, match="condensed"):
        nnm.continue_nnm(two_dof(), 1, 1.0, method="hb", condensed="yes")
    with pytest.raises(nnm.NNMInputError, match="condensed"):
        nnm.continue_nnm(two_dof(), 1, 1.0, condensed=True)          # shooting has no condensed form
