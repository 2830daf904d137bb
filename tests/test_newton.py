"""continuation/newton.py, the solver's fixed-parameter Newton (its settings, stopping rules and failures as values),
against closed-form solutions; and the forced responses' fold locator (driver/forced_points.py, the engine's corrector
and stability/roots.py's root finder) against an independent property of a fold: the fixed-frequency Jacobian is
singular there."""
import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.continuation import ContinuationSettings
from nnm_solver.continuation.newton import (CONVERGED, MAX_ITER, NON_POSITIVE, NOT_FINITE, SINGULAR, NewtonSettings,
                                            newton, newton_solve)
from nnm_solver.driver.forced_points import land_on_frequency, locate_fold
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.forced_hb import ForcedBasis, ForcedHBProblem


class Circle:
    """F(x, y) = [x^2 + y^2 - 4; x - y]: the roots (sqrt 2, sqrt 2) and (-sqrt 2, -sqrt 2)."""

    def __init__(self):
        self.evaluations = 0

    def residual(self, u):
        return np.array([u[0] ** 2 + u[1] ** 2 - 4.0, u[0] - u[1]])

    def jacobian(self, u):
        self.evaluations += 1
        return self.residual(u), np.array([[2 * u[0], 2 * u[1]], [1.0, -1.0]])

    def error(self, u, r):
        return float(np.linalg.norm(r))


def test_newton_converges_to_the_closed_form_root_and_says_why_it_stopped():
    res = newton_solve(Circle(), [1.0, 2.0], NewtonSettings(tol=1e-13))
    assert res.converged and res.reason == CONVERGED and 3 <= res.iterations <= 8
    np.testing.assert_allclose(res.u, [np.sqrt(2), np.sqrt(2)], rtol=1e-13)
    assert newton(Circle(), [1.0, 2.0], tol=1e-13) == pytest.approx([np.sqrt(2), np.sqrt(2)], rel=1e-13)


def test_newton_on_a_subset_of_the_unknowns_keeps_the_others():
    """x fixed at 1: the root y = sqrt 3 of x^2 + y^2 = 4 alone (one equation, one free unknown)."""

    class Fixed(Circle):
        def jacobian(self, u):
            r, J = super().jacobian(u)
            return r[:1], J[:1]

    res = newton_solve(Fixed(), [1.0, 1.0], NewtonSettings(tol=1e-14), free=[1])
    assert res.converged and res.u[0] == 1.0 and res.u[1] == pytest.approx(np.sqrt(3), rel=1e-14)
    res = newton_solve(Fixed(), [1.0, 1.0], NewtonSettings(tol=1e-14), free=slice(1, 2))
    assert res.converged and res.u[1] == pytest.approx(np.sqrt(3), rel=1e-14)


def test_an_over_determined_consistent_system_is_solved_in_the_least_squares_sense():
    class Three(Circle):
        def residual(self, u):
            return np.r_[super().residual(u), 2 * (u[0] - u[1])]

        def jacobian(self, u):
            r, J = super().jacobian(u)
            return self.residual(u), np.vstack([J, [2.0, -2.0]])

    res = newton_solve(Three(), [-1.0, -3.0], NewtonSettings(tol=1e-13, positive_last=False))
    assert res.converged
    np.testing.assert_allclose(res.u, [-np.sqrt(2), -np.sqrt(2)], rtol=1e-13)


def test_a_stopping_rule_ends_the_iteration_with_its_reason():
    """The rule sees each step; with tol = 0 it alone decides (here: the step fell below 1e-6)."""
    seen = []

    def small_step(k, u, du, u_new):
        seen.append(k)
        return "small step" if np.linalg.norm(du) < 1e-6 else ""

    res = newton_solve(Circle(), [1.0, 2.0], NewtonSettings(tol=0.0), stop=small_step)
    assert res.converged and res.reason == "small step" and res.iterations == len(seen) == seen[-1] + 1
    np.testing.assert_allclose(res.u, np.sqrt(2), rtol=1e-11)      # quadratic: the next step is below 1e-12


def test_failures_are_values():
    class Flat(Circle):                      # a singular Jacobian at the start
        def jacobian(self, u):
            return self.residual(u), np.zeros((2, 2))

    res = newton_solve(Flat(), [1.0, 2.0])
    assert not res.converged and res.reason == SINGULAR and res.iterations == 0

    class Blows(Circle):                     # the residual leaves the finite numbers
        def jacobian(self, u):
            r, J = super().jacobian(u)
            return (r if u[0] < 10 else np.full(2, np.nan)), J

    res = newton_solve(Blows(), [20.0, 1.0])
    assert res.reason == NOT_FINITE and not res.converged

    # the last unknown must stay positive: from (1, -2) the first step lands on x = y = -4.5
    res = newton_solve(Circle(), [1.0, -2.0], NewtonSettings(positive_last=True))
    assert res.reason == NON_POSITIVE and list(res.u) == [1.0, -2.0]
    res = newton_solve(Circle(), [1.0, -2.0], NewtonSettings(positive_last=False))
    assert res.converged and res.u == pytest.approx([-np.sqrt(2), -np.sqrt(2)], rel=1e-10)

    prob = Circle()
    res = newton_solve(prob, [1.0, 2.0], NewtonSettings(tol=1e-300, max_iter=4))
    assert res.reason == MAX_ITER and res.iterations == 4 and prob.evaluations == 4
    assert newton(Circle(), [1.0, 2.0], tol=1e-300, max_iter=4) is None


def test_the_last_step_is_checked():
    """A linear problem: one step solves it, so max_iter = 1 converges (the final residual check)."""

    class Linear(Circle):
        def residual(self, u):
            return np.array([u[0] + 2 * u[1] - 3.0, u[0] - u[1]])

        def jacobian(self, u):
            return self.residual(u), np.array([[1.0, 2.0], [1.0, -1.0]])

    res = newton_solve(Linear(), [5.0, -7.0], NewtonSettings(tol=1e-14, max_iter=1))
    assert res.converged and res.iterations == 1
    np.testing.assert_allclose(res.u, [1.0, 1.0], rtol=1e-14)


def _duffing_problem():
    """x'' + 0.1 x' + x + 0.1 x^3 = 0.3 cos(w t) (the forced tests' Duffing), odd basis H = 7."""
    model = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=0.1)])
    s = modal_system(model)
    return ForcedHBProblem(s, ForcedBasis(7, "odd"), s.Phi.T @ [0.3], [0.1], 1.0)


def test_the_fold_locator_finds_where_the_fixed_frequency_jacobian_is_singular():
    """Continue the Duffing curve to the two points around its upper fold (near 1.21 rad/s) and locate the fold:
    there the coefficients' block of the Jacobian (the Newton matrix at a fixed frequency) is singular, which the
    locator never looks at (it finds the zero of the tangent's frequency component)."""
    from nnm_solver.continuation import pseudo_arclength
    from nnm_solver.driver.forced_points import first_orbit, frequency_tangent

    prob = _duffing_problem()
    u0, _ = first_orbit(prob, 1.0, 1e-12)
    cs = ContinuationSettings(step=0.05, step_min=1e-9, step_max=np.inf)
    engine = pseudo_arclength(prob, u0, frequency_tangent(prob.jacobian(u0)[1]), cs, 1e-12)
    prev = first = next(engine)
    second = next(engine)
    for cp in engine:
        if cp.tangent[-1] * prev.tangent[-1] < 0:
            break
        prev = cp
    engine.close()
    uf = locate_fold(prob, prev.u, cp.u, 1e-12, cs)
    assert uf is not None and 1.15 < prob.frequency(uf) < 1.3
    sv = np.linalg.svd(prob.jacobian(uf)[1][:, :-1], compute_uv=False)
    sv_ends = [np.linalg.svd(prob.jacobian(u)[1][:, :-1], compute_uv=False) for u in (prev.u, cp.u)]
    assert sv[-1] / sv[0] < 1e-8 < min(s[-1] / s[0] for s in sv_ends)
    # the end landing: exactly at the asked frequency, on the curve, between the points it started from
    w_mid = 0.5 * (prob.frequency(first.u) + prob.frequency(second.u))
    end = land_on_frequency(prob, first.u, second.u, w_mid, 1e-12, second.tangent)
    assert end is not None and prob.frequency(end[0]) == pytest.approx(w_mid, rel=1e-15)
    assert prob.error(end[0], prob.residual(end[0])) < 1e-12
    lo, hi = sorted([first.u[0], second.u[0]])
    assert lo < end[0][0] < hi and end[2] @ second.tangent > 0


def test_natural_parameter_steps_through_the_values_and_stops_at_the_first_failure():
    """x^3 + x = lam, solved for lam = 1..10 by Newton from the last solution: each against numpy's cubic roots; a
    corrector that fails at lam = 4 stops the stepping with the solution at lam = 3."""
    from nnm_solver.continuation import natural_parameter

    class Cubic:
        lam = 0.0

        def residual(self, u):
            return np.array([u[0] ** 3 + u[0] - self.lam])

        def jacobian(self, u):
            return self.residual(u), np.array([[3 * u[0] ** 2 + 1.0]])

        def error(self, u, r):
            return abs(r[0])

    prob, seen = Cubic(), []

    def solve(u, lam):
        prob.lam = lam
        seen.append(lam)
        res = newton_solve(prob, u, NewtonSettings(tol=1e-13, positive_last=False))
        return res.u, res.converged

    values = np.arange(1.0, 11.0)
    res = natural_parameter(solve, [0.0], values, predict=lambda u, a, b: u * (b / a) ** (1 / 3))
    assert res.completed and res.reached == 10 and seen == list(values)
    exact = [r.real for r in np.roots([1.0, 0.0, 1.0, -10.0]) if abs(r.imag) < 1e-12][0]
    assert res.u[0] == pytest.approx(exact, rel=1e-12)

    def fails_at_4(u, lam):
        return solve(u, lam) if lam < 4 else (u, False)

    res = natural_parameter(fails_at_4, [0.0], values)
    exact3 = [r.real for r in np.roots([1.0, 0.0, 1.0, -3.0]) if abs(r.imag) < 1e-12][0]
    assert not res.completed and res.reached == 3 and res.u[0] == pytest.approx(exact3, rel=1e-12)
    res = natural_parameter(lambda u, lam: (u, False), [0.0], values)
    assert res.u is None and res.reached == 0 and not res.completed


def test_the_first_orbit_by_a_force_ramp_is_a_periodic_orbit_of_the_ode():
    """Duffing forced 10x harder (F = 3) at 0.5 rad/s: Newton from the linear response fails there, the ramp of the
    force converges; one period of DOP853 from the orbit's initial state comes back to it and passes through the
    orbit's state at a quarter period (to the truncation at H = 21: 7e-8; 1.6e-3 at H = 9, 1e-11 at H = 31)."""
    from scipy.integrate import solve_ivp

    from nnm_solver.driver.forced_points import first_orbit

    model = nnm.Model(np.eye(1), np.eye(1), [nnm.CubicSpring(dof=0, k3=0.1)])
    s = modal_system(model)
    w = 0.5
    prob = ForcedHBProblem(s, ForcedBasis(21, "odd"), s.Phi.T @ [3.0], [0.1], 1.0)
    assert not prob.solve_at_frequency(prob.linear_start(w), 1e-11)[1]
    u, why = first_orbit(prob, w, 1e-11)
    assert u is not None and why == "" and prob.load == 1.0 and prob.frequency(u) == w
    A, _ = prob.modal_coefficients(u)
    basis = prob.basis

    def state(t):
        theta = np.array([w * t])
        return (basis.functions(theta) @ A)[0, 0] * s.Phi[0, 0], w * (basis.derivatives(theta) @ A)[0, 0] * s.Phi[0, 0]

    def rhs(t, y):
        return [y[1], 3.0 * np.cos(w * t) - 0.1 * y[1] - y[0] - 0.1 * y[0] ** 3]

    T = 2 * np.pi / w
    sol = solve_ivp(rhs, (0.0, T), state(0.0), method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    amp = np.abs(A).max() * abs(s.Phi[0, 0])
    for t in (0.25 * T, T):
        np.testing.assert_allclose(sol.sol(t), state(t), atol=1e-7 * amp)
