"""Nonlinear elements beyond the cubic spring (issue 18, polynomial part): force laws, the automatic
full-period shooting for even powers, an independent DOP853 period, harmonic balance, files."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import nnm_solver as nnm


def test_polynomial_force_tangent_potential_by_finite_differences():
    m = nnm.Model(np.eye(3), np.diag([1.0, 2.0, 3.0]),
                  [nnm.PolynomialSpring(dof=0, coefficients={2: 0.7, 3: -0.2, 5: 0.05}),
                   nnm.PolynomialSpring(dof=2, other=1, coefficients={4: 1.5})])
    el, h = m.elements, 1e-6
    d = np.random.default_rng(3).normal(size=(6, 2))
    np.testing.assert_allclose(el.tangent(d), (el.force(d + h) - el.force(d - h)) / (2 * h), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(el.force(d), (el.potential(d + h) - el.potential(d - h)) / (2 * h), rtol=1e-6,
                               atol=1e-9)
    assert not el.odd
    x = np.array([0.3, -0.2, 0.5])
    np.testing.assert_allclose(m.nonlinear_force(x), [0.7 * 0.09 - 0.2 * 0.027 + 0.05 * 0.3 ** 5,
                                                      -1.5 * 0.7 ** 4, 1.5 * 0.7 ** 4], rtol=1e-12)


@pytest.mark.parametrize("bad, match", [({1: 2.0}, "power 1 < 2"), ({2.5: 1.0}, "not an integer"),
                                        ({3: float("nan")}, "not finite"), ({}, "at least one")])
def test_polynomial_bad_input(bad, match):
    with pytest.raises(nnm.NNMInputError, match=match):
        nnm.PolynomialSpring(dof=0, coefficients=bad)


def test_quadratic_cubic_oscillator_period_against_dop853():
    """x'' + x + k2 x^2 + k3 x^3 = 0: not odd, so the solver shoots over the full period (orbits from
    rest); its period converges to the DOP853 one as N^-2."""
    k2, k3 = 0.3, 0.5
    m = nnm.Model(np.eye(1), np.eye(1), [nnm.PolynomialSpring(dof=0, coefficients={2: k2, 3: k3})])
    b = nnm.continue_nnm(m, 1, 2.0, steps_per_period=1000)
    assert b.status == "done" and not b.settings.symmetric and b.settings.reversible
    i = len(b) // 2

    def rhs(t, y):
        return [y[1], -y[0] - k2 * y[0] ** 2 - k3 * y[0] ** 3]

    down = lambda t, y: y[1]
    down.direction = -1                                   # back at the starting turning point
    sol = solve_ivp(rhs, [0, 3 * b.period[i]], [b.x0[i, 0], 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    events=down)
    T_ref = sol.t_events[0][sol.t_events[0] > 1e-3][0]
    assert b.period[i] == pytest.approx(T_ref, rel=1e-5)   # Newmark at 1000 steps: ~3e-6
    hb = nnm.continue_nnm(m, 1, 2.0, method="hb", harmonics=15)
    assert hb.settings.basis == "full"
    assert np.interp(b.energy[i], hb.energy, hb.frequency_hz) == pytest.approx(b.frequency_hz[i], rel=1e-5)
    t, x, v = b.orbit(i, 128)
    E = m.energy(x, v)
    assert np.ptp(E) < 1e-4 * E.mean()                     # energy conserved along the orbit (O(h^2))


def test_polynomial_springs_survive_the_file(tmp_path):
    springs = [nnm.PolynomialSpring(dof=0, coefficients={2: 0.3, 3: 0.5}), nnm.CubicSpring(dof=1, other=0, k3=2.0)]
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs)
    nnm.save_model(tmp_path / "m.h5", m)
    assert nnm.load_model(tmp_path / "m.h5").springs == springs
    b = nnm.continue_nnm(m, 1, 1.0, max_points=8)
    with pytest.raises(nnm.NNMInputError, match="cubic springs only"):
        b.scaled(2.0)
