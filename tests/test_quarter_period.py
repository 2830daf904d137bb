"""Quarter-period shooting (orbits/shooting.py): H = q(T/4) for reversible orbits of odd systems, the square
corrector it gives, and the continuation guards that came with it (continuation.py)."""
import dataclasses

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.continuation.engine import ContinuationSettings, LeastSquares, _unseen_turns, correct
from nnm_solver.integrators.registry import get_integrator
from nnm_solver.model.modal import modal_system
from nnm_solver.orbits.shooting import ShootingProblem

from conftest import two_dof_model


def _three_dof():
    """A chain of three unequal masses with two cubic springs (one grounded, one relative) and a quintic one."""
    M = np.diag([1.0, 2.0, 0.5])
    K = np.array([[3.0, -1.0, 0.0], [-1.0, 2.5, -1.2], [0.0, -1.2, 1.7]])
    springs = [nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=1, k3=-0.05, other=2),
               nnm.PolynomialSpring(dof=2, coefficients={5: 0.3})]
    return nnm.Model(M, K, springs)


def _converge(ms, mode, integrator, quarter, amplitude=0.6, tol=1e-13):
    prob = ShootingProblem(ms, mode, 100, symmetric=True, integrator=integrator, quarter=quarter)
    q0 = np.zeros(ms.n)
    q0[mode] = amplitude
    u0 = prob.pack(q0, np.zeros(ms.n), prob.T_r * 1.02)
    p = np.zeros(len(u0))
    p[mode] = 1.0                       # fix the amplitude of the continued mode: a hyperplane of the branch
    settings = ContinuationSettings(step=0.1, step_min=1e-9, step_max=1.0, max_iter=40)
    u, J, it, err = correct(prob, u0, p, settings, tol)
    prob.accept(u, J)
    return prob, u


@pytest.mark.parametrize("integrator", ["newmark", "gauss4"])
@pytest.mark.parametrize("model, mode", [(two_dof_model(), 0), (_three_dof(), 1)])
def test_quarter_and_half_period_shooting_find_the_same_discrete_orbit(model, mode, integrator):
    """Both formulations converge, on the same hyperplane, to the same discrete orbit (u to round-off) with the
    same Floquet multipliers; the quarter Jacobian is square (n x (n + 1))."""
    ms = modal_system(model)
    pq, uq = _converge(ms, mode, integrator, quarter=None)
    ph, uh = _converge(ms, mode, integrator, quarter=False)
    assert pq.quarter and not ph.quarter and pq.rows == ms.n and ph.rows == 2 * ms.n
    assert np.allclose(uq, uh, rtol=1e-9, atol=1e-11)
    mq, mh = np.sort_complex(pq.multipliers(uq)), np.sort_complex(ph.multipliers(uh))
    assert np.allclose(mq, mh, atol=1e-7)


def test_half_period_orbits_pass_through_zero_displacement_at_a_quarter_period():
    """The theory of the formulation: a converged half-period orbit (z(T/2) = -z0, v0 = 0) of the discrete map has
    every displacement zero after N/4 steps (N divisible by 4), to the corrector's accuracy."""
    ms = modal_system(_three_dof())
    ph, uh = _converge(ms, 0, "newmark", quarter=False, amplitude=0.9)
    q0, v0, T = ph.unpack(uh)
    q, v, ok = ph.integrator.state(ms, q0, v0, T / ph.spp, ph.spp // 4)
    assert ok and np.linalg.norm(q) < 1e-10 * np.linalg.norm(q0)
    assert np.linalg.norm(v) > 0.1 * np.linalg.norm(q0) * ph.w_r       # the velocity is at its largest there


@pytest.mark.parametrize("requested, used", [(200, 200), (198, 200), (81, 84), (8, 8)])
def test_steps_per_period_are_a_multiple_of_four_for_quarter_shooting(requested, used):
    ms = modal_system(two_dof_model())
    prob = ShootingProblem(ms, 0, requested)
    assert prob.quarter and prob.spp == used and prob.nsteps == used // 4
    half = ShootingProblem(ms, 0, requested, quarter=False)
    assert half.spp == requested + requested % 2 and half.nsteps == half.spp // 2


def test_square_systems_are_solved_by_lu_and_agree_with_lstsq():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((80, 80)) + 8 * np.eye(80)
    b = rng.standard_normal(80)
    ls = LeastSquares(np.array(A, order="F"))
    assert ls._lu is not None
    assert np.allclose(ls.solve(b), np.linalg.solve(A, b), rtol=1e-12, atol=1e-12)
    B = rng.standard_normal((80, 3))
    assert np.allclose(ls.solve(B), np.linalg.solve(A, B), rtol=1e-12, atol=1e-12)
    tall = rng.standard_normal((120, 80))
    assert LeastSquares(np.array(tall, order="F"))._lu is None        # over-determined: QR


def test_a_step_against_the_period_slope_at_both_ends_is_refused():
    """A converged point whose period moved against the tangent's period derivative at both ends (a jump onto a
    branch alongside, or two turning points inside the step) is refused; one turning point inside the step is
    not (the slopes at the two ends then differ in sign)."""
    u, p = np.array([1.0, 1.0]), np.array([1.0, -0.2])       # the period falls along the branch ...
    jumped = np.array([1.5, 1.01])                          # ... but rose over the step
    assert "period" in _unseen_turns(None, u, p, jumped, np.array([1.0, -0.1]), 1e-6)
    assert _unseen_turns(None, u, p, jumped, np.array([1.0, 0.3]), 1e-6) == ""          # one turning point
    assert _unseen_turns(None, u, p, np.array([1.5, 0.95]), np.array([1.0, -0.1]), 1e-6) == ""
    assert _unseen_turns(None, u, p, np.array([1.5, 1.0 + 1e-8]), np.array([1.0, -0.1]), 1e-6) == ""  # noise


def test_the_two_dof_backbone_goes_all_round_the_5to1_tongue():
    """NNM 1 of the 2-DOF benchmark to 300 kJ goes through the 5:1 tongue and its inner loop (folds at 109 kJ,
    2.36 kJ, 75.8 kJ and 43.9 kJ) before it goes on up the backbone: without the period test it stepped from
    the tongue's far side (73 kJ) straight onto the backbone (89.6 kJ)."""
    b = nnm.continue_nnm(two_dof_model(), 1, 3e5, integrator="newmark", freq_tol=None, tongues="follow-all")   # the fold energies
                                                                                       # measured with its fixed step
    folds = [e["energy"] for e in b.events if e["kind"] == "fold"]
    for E in (4708.27, 285.607, 109148.2, 2356.36, 75849.1, 43884.9):
        assert min(abs(f / E - 1) for f in folds) < 1e-4, E
    assert b.status == "done" and b.energy[-1] == pytest.approx(3e5)


def test_a_jump_onto_a_branch_alongside_is_caught_at_mid_step(monkeypatch):
    """Without the period test, NNM 1 of the 2-DOF stepped from the 5:1 tongue's far side (73 kJ) onto the backbone
    (89.6 kJ); the mid-step check (Locator.jumped: the branch's point half-way lies 0.39 step lengths off the
    cubic interpolant of the ends) refuses that step too, and the branch goes round the tongue's inner loop."""
    import nnm_solver.continuation.engine as continuation
    import nnm_solver.stability.locator as locator
    energy_only = continuation._unseen_turns

    def no_period_test(energy, u, p, u_new, p_new, floor):
        reason = energy_only(energy, u, p, u_new, p_new, floor)
        return reason if reason.startswith("the energy") else ""

    monkeypatch.setattr(continuation, "_unseen_turns", no_period_test)
    calls = []
    jumped = locator.Locator.jumped
    monkeypatch.setattr(locator.Locator, "jumped", lambda self, *a: calls.append(jumped(self, *a)) or calls[-1])
    b = nnm.continue_nnm(two_dof_model(), 1, 3e5, integrator="newmark", freq_tol=None, tongues="follow-all")   # the fold energies
                                                                                       # measured with its fixed step
    folds = [e["energy"] for e in b.events if e["kind"] == "fold"]
    for E in (109148.2, 2356.36, 75849.1, 43884.9):
        assert min(abs(f / E - 1) for f in folds) < 1e-4, E
    assert any("step lengths off" in c for c in calls)                    # the check refused a step
    assert sum(bool(c) for c in calls) <= 3


def test_an_exactly_singular_least_squares_system_gives_a_non_finite_solution_not_an_exception():
    """A zero pivot in the triangular solve (mode 20 of the aircraft with 13 condensed harmonics met one) must reach
    the corrector as a non-finite step, which it reports as its own failure, as the LU route does."""
    tall = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])             # a zero column: an exactly zero pivot
    for A in (tall, np.hstack([np.vstack([tall] * 40), np.zeros((120, 70))])):
        x = LeastSquares(np.array(A, order="F")).solve(np.ones(A.shape[0]))
        assert not np.all(np.isfinite(x))


def _half_sweeps(monkeypatch, prob):
    """Count the sensitivity sweeps the problem's integrator makes (their numbers of steps)."""
    calls = []
    cls = type(prob.integrator)
    sensitivity = cls.sensitivity

    def counted(self, system, q0, v0, h, nsteps, *args):
        calls.append(nsteps)
        return sensitivity(self, system, q0, v0, h, nsteps, *args)
    monkeypatch.setattr(cls, "sensitivity", counted)
    return calls


@pytest.mark.parametrize("integrator", ["gauss4", "gauss6"])
def test_the_half_period_map_from_the_quarter_period_sweep(monkeypatch, integrator):
    """Quarter-period shooting with a Gauss scheme makes the multipliers' A11 = dq(T/2)/dq0 from the accepted point's
    quarter-period Jacobian (its discrete map's reversibility and symplecticity: no sweep over T/2); the same A11
    and multipliers as the sweep route (ORBITS.half_map = "sweep") to the corrector's accuracy.  A residual above
    ORBITS.reversible_residual, or Newmark (not symplectic), takes the sweep."""
    from nnm_solver.orbits import shooting_stability
    ms = modal_system(_three_dof())
    prob, u = _converge(ms, 1, integrator, quarter=None, amplitude=0.9)
    assert prob.quarter and np.array_equal(prob.last_evaluated(), u)
    calls = _half_sweeps(monkeypatch, prob)
    A_rev = prob.stability_maps()[0].copy()
    mu_rev = np.sort_complex(prob.multipliers(u))
    assert calls == []                                       # no sweep over T/2
    monkeypatch.setattr(shooting_stability, "ORBITS", dataclasses.replace(shooting_stability.ORBITS, half_map="sweep"))
    prob._accepted_maps = None
    A_sweep = prob.stability_maps()[0].copy()
    assert calls == [prob.spp // 2]
    assert np.max(np.abs(A_rev - A_sweep)) < 1e-10 * np.max(np.abs(A_sweep))
    assert np.max(np.abs(A_sweep - np.diag(np.diag(A_sweep)))) > 1e-2    # (the springs couple the modes)
    assert np.allclose(np.sort_complex(prob.multipliers(u)), mu_rev, atol=1e-9)
    # a residual above the bound: the sweep
    monkeypatch.setattr(shooting_stability, "ORBITS", dataclasses.replace(
        shooting_stability.ORBITS, half_map="reversible", reversible_residual=0.0))
    prob._accepted_maps = None
    prob.stability_maps()
    assert calls == [prob.spp // 2] * 2


def test_the_reversible_half_map_needs_the_orbit():
    """Away from a reversible orbit (q(T/4) far from 0) the formula is not the half-period map: the premise the
    residual bound guards."""
    ms = modal_system(_three_dof())
    prob = ShootingProblem(ms, 1, 100, integrator="gauss6")
    q0 = np.array([0.3, 0.9, -0.4])
    u = prob.pack(q0, np.zeros(3), prob.T_r * 0.9)
    prob.jacobian(u)
    A_rev = prob.integrator.reversible_half_block(ms, prob._stages, prob._maps[0])
    A_sweep = prob.integrator.sensitivity(ms, q0, np.zeros(3), prob._h(prob.T_r * 0.9), prob.spp // 2, False, False)[2]
    assert np.max(np.abs(A_rev - A_sweep)) > 1e-3 * np.max(np.abs(A_sweep))
    assert get_integrator("newmark").reversible_half_block(ms, prob._stages, prob._maps[0]) is None
