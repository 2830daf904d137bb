"""The half-period map as a diagonal plus a low-rank term (lowrank.py, newmark.sweep_factors) and the Krein
follower's shift-invert Arnoldi on it (Woodbury solves), against the dense matrix: the same map, the same
quotient, the same solves and the same eigenvalues; the Arnoldi's restarts are bounded."""
import types

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.sparse.linalg import LinearOperator

import nnm_solver.orbits.shooting_stability as shooting_stability
from nnm_solver.stability.floquet import deflate
from nnm_solver.integrators.lowrank import DiagonalPlusLowRank
from nnm_solver.integrators.newmark import sweep_factors, sweep_sensitivity
from nnm_solver.orbits.shooting_stability import ShootingStability, nearest_eigenvalues


def _random(n=240, r=30, scale=0.05, seed=0):
    rng = np.random.default_rng(seed)
    d = np.cos(np.linspace(0.0, 3.0, n))
    return DiagonalPlusLowRank(d, scale * rng.standard_normal((n, r)), scale * rng.standard_normal((r, n))), rng


def _nearest(A, sigma, k):
    ev = sla.eigvals(A)
    return ev[np.argsort(np.abs(ev - sigma))[:k]]


def _same_set(a, b, tol):
    """Do a and b hold the same values (each within tol of one in the other)?"""
    a, b = np.asarray(a), np.asarray(b)
    gaps = np.abs(a[:, None] - b[None, :])
    return a.shape == b.shape and gaps.min(axis=1).max() <= tol and gaps.min(axis=0).max() <= tol


def test_quotient_and_shifted_solves_match_the_dense_matrix():
    A, rng = _random()
    v = rng.standard_normal(A.n)
    Q = A.deflated(v)
    assert Q.rank == A.rank + 2
    C = deflate(A.dense(), v[:, None])
    assert np.abs(Q.dense() - C).max() <= 1e-14
    for sigma in (0.3, 0.3 + 0.05j):
        b = rng.standard_normal(Q.n)
        x = Q.shift_invert(sigma).matvec(b)
        assert np.abs((C - sigma * np.eye(Q.n)) @ x - b).max() <= 1e-11
    assert A.shift_invert(float(A.d[7])) is None          # the shift on the diagonal: left to a dense LU
    with pytest.raises(ValueError, match="do not fit"):
        DiagonalPlusLowRank(np.ones(4), np.ones((4, 2)), np.ones((3, 4)))


@pytest.mark.parametrize("sigma", [0.31, 0.31 + 0.04j])
def test_nearest_eigenvalues_low_rank_and_dense(sigma):
    A, _ = _random(seed=1)
    ref = _nearest(A.dense(), sigma, 6)
    assert _same_set(nearest_eigenvalues(A, sigma, 6), ref, 1e-10)
    assert _same_set(nearest_eigenvalues(A.dense(), sigma, 6), ref, 1e-10)


def test_a_stalling_complex_shift_is_given_up_after_bounded_restarts():
    """A complex shift 0.08 off a dense real spectrum: its nearest eigenvalues all lie at nearly the same distance
    (the case met on the 2,200-mode plate), so Arnoldi hardly converges; ARPACK's default (10 n restarts) ran for
    hours there.  The call gives up within ARPACK_RESTARTS restarts, and the follower's real-part retry
    (local_collision) then finds the k nearest eigenvalues."""
    n = 800
    rng = np.random.default_rng(2)
    A = DiagonalPlusLowRank(np.linspace(-0.9, 0.9, n), 1e-4 * rng.standard_normal((n, 4)),
                            1e-4 * rng.standard_normal((4, n)))
    solves = []
    op = A.shift_invert(0.1 + 0.08j)
    counting = LinearOperator(op.shape, matvec=lambda x: solves.append(1) or op.matvec(x), dtype=op.dtype)
    A.shift_invert = lambda sigma: counting if isinstance(sigma, complex) else DiagonalPlusLowRank.shift_invert(
        A, sigma)
    c = nearest_eigenvalues(A, 0.1 + 0.08j, 6)
    if c is not None:
        assert _same_set(c, _nearest(A.dense(), 0.1 + 0.08j, 6), 1e-9)
    assert len(solves) <= (shooting_stability.ARPACK_RESTARTS + 1) * 15      # ncv = 13 per restart, and a few
    assert _same_set(nearest_eigenvalues(A, 0.1, 6), _nearest(A.dense(), 0.1, 6), 1e-9)


class _Point(ShootingStability):
    """The stability part of a shooting problem at one accepted point whose A11 is kept in both forms."""

    def __init__(self, A, factored):
        self.n, self.symmetric, self.reversible, self.all_columns, self.quarter = A.n, True, True, False, True
        self._accepted_maps = (A.dense(), None)
        self._accepted_factors = (A, self._accepted_maps[0]) if factored else None
        self.sys = types.SimpleNamespace(Bq=np.ones((1, A.n)))      # every mode sees the element

    def unpack(self, u):
        return u[:self.n], u[self.n:2 * self.n], u[-1]


@pytest.mark.parametrize("shift", [0.42, 0.42 + 0.03j])
def test_local_collision_low_rank_equals_dense(shift):
    A, rng = _random(n=300, r=40, seed=3)
    tangent = np.concatenate([rng.standard_normal(A.n), np.zeros(A.n), [0.1]])
    low, dense = _Point(A, True).local_collision(tangent, shift), _Point(A, False).local_collision(tangent, shift)
    assert _same_set(low, dense, 1e-10)
    C = deflate(A.dense(), tangent[:A.n, None])
    assert _same_set(low, _nearest(C, shift, 6), 1e-10)


def test_newmark_factors_are_the_sensitivity_map():
    """sweep_factors' diagonal + low rank is sweep_sensitivity's dq_N/dq0, to round-off."""
    rng = np.random.default_rng(4)
    n, ns, N, h = 40, 2, 30, 0.01
    omega2 = np.sort(rng.uniform(1.0, 4e3, n))
    Bq = rng.standard_normal((ns, n))
    kern = (omega2, Bq, np.array([3], dtype=np.int64), np.array([[80.0], [5.0]]), np.zeros((ns, 0, 3)))
    q0, v0 = 0.2 * rng.standard_normal(n), np.zeros(n)
    q, v, Sq, Sv, _, _, ok = sweep_sensitivity(q0, v0, h, N, *kern, False, False)
    q1, v1, F, ok1 = sweep_factors(q0, v0, h, N, *kern)
    assert ok and ok1 and F.rank == ns * N
    assert np.array_equal(q, q1) and np.array_equal(v, v1)
    assert np.abs(F.dense() - Sq).max() <= 1e-13 * np.abs(Sq).max()


def test_a_stalled_complex_shift_is_not_tried_again(monkeypatch):
    """The follower asks with the same complex shift at every step of one collision: once it stalled, the next
    calls go straight to its real part.  (The stall is imposed: ARPACK's random start vector, which depends on
    the calls before in the process, occasionally converges there.)"""
    n = 800
    rng = np.random.default_rng(2)
    A = DiagonalPlusLowRank(np.linspace(-0.9, 0.9, n), 1e-4 * rng.standard_normal((n, 4)),
                            1e-4 * rng.standard_normal((4, n)))
    asked = []
    nearest = shooting_stability.nearest_eigenvalues

    def counted(M, sigma, k):
        asked.append(sigma)
        return None if isinstance(sigma, complex) else nearest(M, sigma, k)

    monkeypatch.setattr(shooting_stability, "nearest_eigenvalues", counted)
    point = _Point(A, True)
    tangent = np.concatenate([np.eye(n)[0], np.zeros(n), [0.1]])
    for _ in range(3):
        c = point.local_collision(tangent, 0.1 + 0.08j)
        assert _same_set(c, _nearest(A.deflated(tangent[:n]).dense(), 0.1, 6), 1e-9)
    assert [isinstance(s, complex) for s in asked] == [True, False, False, False]


@pytest.mark.parametrize("stages", [2, 3])
def test_gauss_factors_are_the_sensitivity_map(stages):
    """gauss.sweep_factors' diagonal + low rank (rank N s n_s) is gauss.sweep_sensitivity's dq_N/dq0, to round-off;
    the shooting problem keeps this form for its multipliers where the rank is at most ORBITS.low_rank_share n."""
    from nnm_solver.integrators import gauss
    rng = np.random.default_rng(6)
    n, ns, N, h = 60, 2, 8, 0.01
    omega2 = np.sort(rng.uniform(1.0, 4e3, n))
    Bq = rng.standard_normal((ns, n))
    kern = (omega2, Bq, np.array([3], dtype=np.int64), np.array([[80.0], [5.0]]), np.zeros((ns, 0, 3)))
    q0, v0 = 0.2 * rng.standard_normal(n), np.zeros(n)
    q, v, Sq, _, _, _, ok = gauss.sweep_sensitivity(q0, v0, h, N, kern, stages, False, False)
    q1, v1, F, ok1 = gauss.sweep_factors(q0, v0, h, N, kern, stages)
    assert ok and ok1 and F.rank == ns * stages * N
    assert np.array_equal(q, q1) and np.array_equal(v, v1)
    assert np.abs(F.dense() - Sq).max() <= 1e-13 * np.abs(Sq).max()
    assert np.abs(Sq - np.diag(np.diag(Sq))).max() > 1e-3 * np.abs(Sq).max()      # (the springs matter)


def test_gauss_shooting_keeps_the_factored_map_and_its_multipliers():
    """A chain of 150 modes with one cubic spring, quarter-period shooting with gauss6 at 24 steps a period: the
    half-period map's rank 1 x 3 x 12 = 36 is below n / 3, so stability_maps keeps it as diagonal + low rank; the
    multipliers and the Krein follower's local coordinates are those of the dense map (the route above the share)."""
    import dataclasses
    import nnm_solver as nnm
    import nnm_solver.orbits.shooting_stability as ss_module
    from nnm_solver.model.modal import ModalSystem
    from nnm_solver.orbits.shooting import ShootingProblem
    n = 150
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    s = ModalSystem(nnm.Model(np.eye(n), K * 1e4, [nnm.CubicSpring(dof=3, k3=5e9)]))

    def point(share):
        ss_module.ORBITS = dataclasses.replace(ss_module.ORBITS, low_rank_share=share)
        prob = ShootingProblem(s, 0, 24, integrator="gauss6")
        q0 = np.zeros(n)
        q0[0] = 0.02
        u = prob.pack(q0, np.zeros(n), prob.T_r)
        _, J = prob.jacobian(u)
        prob.accept(u, J)
        tangent = np.zeros(len(u))
        tangent[0] = 1.0
        mu = prob.multipliers(u, tangent)
        return prob, tangent, mu

    kept = ss_module.ORBITS
    try:
        low, tangent, mu_low = point(1.0 / 3.0)
        dense, _, mu_dense = point(0.0)
    finally:
        ss_module.ORBITS = kept
    assert low._low_rank_a11(low.stability_maps()) is not None and dense._low_rank_a11(dense.stability_maps()) is None
    assert low._low_rank_a11(low.stability_maps()).rank == 36
    assert np.abs(low.stability_maps()[0] - dense.stability_maps()[0]).max() <= 1e-12
    assert _same_set(mu_low, mu_dense, 1e-10)
    F = low._low_rank_a11(low.stability_maps())
    assert np.abs(F.U @ F.Vt).max() > 1e-3 * np.abs(F.d).max()          # (the spring matters)
    for shift in (-0.5, 0.3):
        assert _same_set(low.local_collision(tangent, shift), dense.local_collision(tangent, shift), 1e-9)
