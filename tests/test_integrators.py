"""Time integrators of the shooting (issue 12): Gauss-Legendre collocation against exact periods, its
order, its exact sensitivities against finite differences, HB agreement, and the per-point frequency
error estimate against true errors."""
import numpy as np
import pytest
import scipy.linalg as sla

import nnm_solver as nnm
from nnm_solver.integrators.registry import get_integrator
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.shooting import ShootingProblem

from conftest import duffing_model, two_dof_model
from test_duffing import _rel_errors


def test_the_names_are_a_contract():
    assert nnm.INTEGRATORS[0] == "newmark"
    assert {"gauss4", "gauss6"} <= set(nnm.INTEGRATORS)
    with pytest.raises(nnm.NNMInputError, match="integrator must be one of newmark"):
        nnm.continue_nnm(duffing_model(), 1, 1.0, integrator="rk4")
    with pytest.raises(nnm.NNMInputError, match="belongs to method='shooting'"):
        nnm.continue_nnm(duffing_model(), 1, 1.0, method="hb", integrator="gauss4")


@pytest.mark.parametrize("k", [1.0, -0.2])
@pytest.mark.parametrize("name, bound", [("gauss4", 1e-8), ("gauss6", 1e-10)])
def test_duffing_period_at_200_steps(k, name, bound):
    """Exact period from the complete elliptic integral; the error estimate bounds the true error within 10x."""
    b = nnm.continue_nnm(duffing_model(k), mode=1, energy_max=2.0 if k > 0 else 0.6, steps_per_period=200,
                         integrator=name, tol=1e-11)
    assert b.status == "done" and b.settings.integrator == name
    err = np.abs(_rel_errors(b, k))
    assert np.max(err) < bound
    big = err > 1e-11                      # above the corrector's tolerance and round-off
    if big.any():
        ratio = b.freq_error[big] / err[big]
        assert np.all((ratio > 0.1) & (ratio < 10)), ratio


@pytest.mark.parametrize("name, order", [("newmark", 2), ("gauss4", 4), ("gauss6", 6)])
def test_convergence_order_on_the_duffing_period(name, order):
    m = duffing_model(1.0)
    errs = []
    for spp in (24, 48):
        b = nnm.continue_nnm(m, mode=1, energy_max=1.0, steps_per_period=spp, integrator=name, tol=1e-12,
                             max_points=12, freq_tol=None)      # the fixed step whose order is measured
        errs.append(np.max(np.abs(_rel_errors(b, 1.0))))
    assert np.log2(errs[0] / errs[1]) == pytest.approx(order, abs=0.3)


def _fd_map(integ, system, z0, h, N, eps=1e-6):
    n = system.n
    out = np.zeros((2 * n, 2 * n))
    for j in range(2 * n):
        zp, zm = z0.copy(), z0.copy()
        zp[j] += eps
        zm[j] -= eps
        a = integ.state(system, zp[:n], zp[n:], h, N)
        b = integ.state(system, zm[:n], zm[n:], h, N)
        out[:, j] = (np.r_[a[0], a[1]] - np.r_[b[0], b[1]]) / (2 * eps)
    return out


def _three_dof():
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    return nnm.Model(np.diag([1.0, 2.0, 1.5]), K, [nnm.CubicSpring(dof=0, k3=0.8),
                                                   nnm.CubicSpring(dof=2, other=1, k3=-0.1)])


@pytest.mark.parametrize("name", ["gauss4", "gauss6"])
@pytest.mark.parametrize("make", [two_dof_model, _three_dof])
def test_sensitivities_against_finite_differences(name, make):
    system = modal_system(make())
    integ = get_integrator(name)
    n = system.n
    rng = np.random.default_rng(3)
    z0 = rng.normal(size=2 * n) * 0.8
    h, N = 0.09, 40
    q, v, Sq, Sv, sq_h, sv_h, ok = integ.sensitivity(system, z0[:n], z0[n:], h, N, True)
    assert ok
    S = np.vstack([Sq, Sv])
    assert np.max(np.abs(S - _fd_map(integ, system, z0, h, N))) < 1e-7 * np.max(np.abs(S))
    eh = 1e-7 * h
    a = integ.state(system, z0[:n], z0[n:], h + eh, N)
    b = integ.state(system, z0[:n], z0[n:], h - eh, N)
    fd_h = (np.r_[a[0], a[1]] - np.r_[b[0], b[1]]) / (2 * eh)
    assert np.max(np.abs(np.r_[sq_h, sv_h] - fd_h)) < 1e-6 * np.max(np.abs(fd_h))
    # the columns of dq0 only (reversible orbits) are the same numbers
    _, _, Sq1, Sv1, _, _, _ = integ.sensitivity(system, z0[:n], z0[n:], h, N, False)
    assert np.allclose(Sq1, Sq[:, :n], rtol=1e-12, atol=1e-14) and np.allclose(Sv1, Sv[:, :n], rtol=1e-12, atol=1e-14)


def test_linear_period_closes_the_discrete_orbit():
    m = nnm.Model(np.eye(1), np.eye(1) * 4.0, [])
    system = modal_system(m)
    for name in nnm.INTEGRATORS:
        integ = get_integrator(name)
        T = integ.linear_period(2.0, 16)
        q, v, ok = integ.state(system, np.ones(1), np.zeros(1), T / 16, 16)
        assert abs(q[0] - 1) < 1e-13 and abs(v[0]) < 1e-12


def _period_at_energy(model, x0, v0, T, E, spp=400, integrator="gauss6"):
    """Reference period at energy E: Newton on the shooting function plus E(u) = E (fine Gauss shooting)."""
    system = modal_system(model)
    pr = ShootingProblem(system, 0, spp, symmetric=True, integrator=integrator)
    u = pr.pack(system.to_modal(x0), system.to_modal(v0), T)
    for _ in range(20):
        r, J = pr.jacobian(u)
        A = np.vstack([J, pr.energy_gradient(u)[None]])
        du = sla.lstsq(A, -np.r_[r, pr.energy(u) - E])[0]
        u = u + du
        if np.linalg.norm(du) < 1e-14 * np.linalg.norm(u):
            break
    return pr.unpack(u)[2]


def test_two_dof_backbone_agrees_with_harmonic_balance():
    """Below the 3:1 tongue; HB with 15 odd harmonics is converged to round-off there."""
    m = two_dof_model()
    hb = nnm.continue_nnm(m, 1, 20.0, method="hb", harmonics=15, tol=1e-12, floquet=False)
    sh = nnm.continue_nnm(m, 1, 20.0, steps_per_period=200, integrator="gauss6", tol=1e-11)
    for i in range(0, len(hb), max(len(hb) // 6, 1)):
        T = _period_at_energy(m, hb.x0[i], hb.v0[i], hb.period[i], hb.energy[i], spp=200)
        assert abs(T / hb.period[i] - 1) < 1e-8
    assert np.all(sh.freq_error < 1e-8)


def test_multipliers_stay_on_the_unit_circle_at_low_energy():
    b = nnm.continue_nnm(two_dof_model(), 1, 1e-2, steps_per_period=100, integrator="gauss4", max_points=8)
    assert np.max(np.abs(np.abs(b.floquet) - 1)) < 1e-6
    assert b.stable.all()


@pytest.mark.parametrize("name, spp", [("newmark", 200), ("gauss4", 100)])
def test_error_estimate_bounds_the_true_error_on_the_two_dof(name, spp):
    """Through the 3:1 tongue (its 3rd harmonic doubles Newmark's error); reference: gauss6 at 400 steps."""
    m = two_dof_model()
    b = nnm.continue_nnm(m, 1, 1e4, steps_per_period=spp, integrator=name)
    folds = [e["energy"] for e in b.events if e["kind"] == "fold"]
    checked = 0
    for i in range(0, len(b), 9):
        if any(abs(b.energy[i] / E - 1) < 0.02 for E in folds):
            continue          # at an energy fold the frequency at a fixed energy is not defined
        checked += 1
        true = abs(_period_at_energy(m, b.x0[i], b.v0[i], b.period[i], b.energy[i]) / b.period[i] - 1)
        if true > 1e-10:
            assert 0.1 < b.freq_error[i] / true < 10, (i, b.energy[i], true, b.freq_error[i])
    assert checked > 10


def test_freq_tol_raises_the_steps_where_needed(tmp_path):
    m = two_dof_model()
    # Newmark at 100 steps: 3.3e-4 on the linear mode, several times more in the 3:1 tongue (3rd harmonic)
    b = nnm.continue_nnm(m, 1, 1e4, steps_per_period=100, freq_tol=1e-4, integrator="newmark")
    assert b.status == "done" and "exceed" not in b.message
    assert np.nanmax(b.freq_error) <= 1e-4
    assert b.steps.min() > 100 and len(np.unique(b.steps)) >= 2     # refined at the start, and again later
    assert np.all(np.diff(b.steps) >= 0)
    # a point computed with the finest step, the farthest in energy from where that step was chosen (an energy
    # fold at 4681 J, where the period at a fixed energy is not defined)
    finest = np.flatnonzero(b.steps == b.steps.max())
    i = int(finest[np.argmax(np.abs(np.log(b.energy[finest] / b.energy[finest[0]])))])
    true = abs(_period_at_energy(m, b.x0[i], b.v0[i], b.period[i], b.energy[i]) / b.period[i] - 1)
    assert true < 2e-4
    # the steps of each point survive the file and rebuild its periodic orbit
    path = tmp_path / "b.h5"
    nnm.save_branch(path, b)
    c = nnm.load_branches(path)[0]
    assert np.array_equal(c.steps, b.steps) and np.allclose(c.freq_error, b.freq_error, equal_nan=True)
    assert c.settings.freq_tol == 1e-4
    x, v = c.settings.orbit(c, i, 64)
    assert np.allclose(x[0], c.x0[i], atol=1e-9 * np.abs(c.x0[i]).max())


def test_integrator_survives_the_file_and_rebuilds_the_orbit(tmp_path):
    m = two_dof_model()
    b = nnm.continue_nnm(m, 1, 50.0, steps_per_period=40, integrator="gauss6", max_points=10)
    path = tmp_path / "g.h5"
    nnm.save_branch(path, b)
    c = nnm.load_branches(path)[0]
    assert c.settings.integrator == "gauss6"
    t, x, v = c.orbit(len(c) - 1, 40)
    # periodic with the integrator it was computed with (Newmark would leave a defect of ~1e-3 at 40 steps)
    system = modal_system(m)
    q0, v0 = system.to_modal(c.x0[-1]), system.to_modal(c.v0[-1])
    q, vv, ok = get_integrator("gauss6").state(system, q0, v0, c.period[-1] / 40, 40)
    assert np.allclose(system.to_physical(q), c.x0[-1], atol=1e-8 * np.abs(c.x0[-1]).max())
    assert np.allclose(x[0], c.x0[-1], atol=1e-9 * np.abs(c.x0[-1]).max())
