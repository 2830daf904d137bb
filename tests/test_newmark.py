"""Modal Newmark integrator: accuracy vs solve_ivp, energy, and exact sensitivities vs finite differences."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nnm_solver.integrators.newmark import sweep_record, sweep_sensitivity, sweep_state
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.shooting import ShootingProblem

from conftest import two_dof_model


def _system():
    return modal_system(two_dof_model())


def test_matches_solve_ivp_and_converges_second_order():
    ms = _system()
    m = ms.model
    x0 = np.array([1.2, 0.4])
    q0 = ms.to_modal(x0)
    T = 5.0

    def rhs(t, z):
        x, v = z[:2], z[2:]
        return np.concatenate([v, -(m.K @ x) - m.nonlinear_force(x)])

    ref = solve_ivp(rhs, (0, T), np.concatenate([x0, [0, 0]]), rtol=1e-12, atol=1e-12).y[:2, -1]
    errs = []
    for N in (400, 800):
        q, v, ok = sweep_state(q0, np.zeros(2), T / N, N, *ms.kernel)
        assert ok
        errs.append(np.linalg.norm(ms.to_physical(q) - ref))
    assert errs[0] < 5e-3
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.1)   # second order


def test_energy_bounded_along_orbit():
    ms = _system()
    x0 = np.array([2.0, 1.0])
    Q, V, ok = sweep_record(ms.to_modal(x0), np.zeros(2), 0.05, 400, *ms.kernel)
    assert ok
    E = ms.model.energy(ms.to_physical(Q), ms.to_physical(V))
    assert np.ptp(E) / E[0] < 2e-3


@pytest.mark.parametrize("k3", [0.0, 0.5, -0.05])
def test_sensitivity_matches_finite_differences(k3):
    ms = modal_system(two_dof_model(k3))
    q0 = np.array([0.9, -0.3])
    v0 = np.array([0.2, 0.5])
    h, N = 0.04, 150
    q, v, Sq, Sv, sq_h, sv_h, ok = sweep_sensitivity(q0, v0, h, N, *ms.kernel)
    assert ok
    eps = 1e-6
    z0 = np.concatenate([q0, v0])
    for j in range(4):
        dz = np.zeros(4)
        dz[j] = eps
        qp, vp, _ = sweep_state(*np.split(z0 + dz, 2), h, N, *ms.kernel)
        qm, vm, _ = sweep_state(*np.split(z0 - dz, 2), h, N, *ms.kernel)
        fd = np.concatenate([qp - qm, vp - vm]) / (2 * eps)
        assert np.allclose(np.concatenate([Sq[:, j], Sv[:, j]]), fd, rtol=1e-6, atol=1e-7)
    qp, vp, _ = sweep_state(q0, v0, h + 1e-7, N, *ms.kernel)
    qm, vm, _ = sweep_state(q0, v0, h - 1e-7, N, *ms.kernel)
    fd = np.concatenate([qp - qm, vp - vm]) / 2e-7
    assert np.allclose(np.concatenate([sq_h, sv_h]), fd, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("symmetric", [True, False])
def test_shooting_jacobian_matches_finite_differences(symmetric):
    ms = _system()
    prob = ShootingProblem(ms, 0, steps_per_period=100, symmetric=symmetric)
    u = prob.pack(np.array([1.1, 0.6]), np.array([0.1, -0.2]), 5.9)
    r, J = prob.jacobian(u)
    assert np.allclose(r, prob.residual(u))
    eps = 1e-7
    fd = np.column_stack([(prob.residual(u + e) - prob.residual(u - e)) / (2 * eps) for e in eps * np.eye(len(u))])
    assert np.allclose(J, fd, rtol=1e-5, atol=1e-6)


def test_monodromy_of_converged_orbit_matches_finite_differences(two_dof_nnm1):
    """Full-period monodromy (square of the half-period map) vs FD of the full-period flow."""
    b = two_dof_nnm1
    i = 15
    ms = modal_system(b.model)
    N = b.settings["steps_per_period"]
    T = b.period[i]
    q0, v0 = ms.to_modal(b.x0[i]), ms.to_modal(b.v0[i])
    from nnm_solver.integrators.registry import get_integrator
    integ = get_integrator(b.settings["integrator"])             # the branch's own scheme (default gauss6)
    prob = ShootingProblem(ms, 0, N, symmetric=True, integrator=integ)
    prob.all_columns = True
    prob.jacobian(prob.pack(q0, v0, T))
    prob.accept(prob.pack(q0, v0, T), None)
    Mono = prob.monodromy()
    eps = 1e-6
    z0 = np.concatenate([q0, v0])
    cols = []
    for j in range(4):
        dz = eps * np.eye(4)[j]
        qp, vp, _ = integ.state(ms, *np.split(z0 + dz, 2), T / N, N)
        qm, vm, _ = integ.state(ms, *np.split(z0 - dz, 2), T / N, N)
        cols.append(np.concatenate([qp - qm, vp - vm]) / (2 * eps))
    assert np.allclose(Mono, np.column_stack(cols), rtol=1e-5, atol=1e-6)
    # and its eigenvalues are the stored multipliers
    # its eigenvalues are the stored multipliers (computed from the reduced n x n problem); the
    # trivial pair at +1 is a Jordan block, whose computed eigenvalues scatter by ~sqrt(eps ||M||)
    mu = np.linalg.eigvals(Mono)
    stored = b.floquet[i]
    trivial = np.abs(mu - 1) < 1e-2
    assert trivial.sum() == 2 and (np.abs(stored - 1) < 1e-2).sum() == 2
    assert np.allclose(np.sort_complex(mu[~trivial]), np.sort_complex(stored[np.abs(stored - 1) >= 1e-2]), atol=1e-6)
