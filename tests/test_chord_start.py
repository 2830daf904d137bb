"""The chord start of a continuation step (engine.ContinuationSettings.chord_start): the last point's
factorisation with its last row replaced (linalg.LeastSquares.with_last_row, Sherman-Morrison) solves the new
system exactly, and a branch continued with it is the branch continued without it (the corrector converges to the
same tolerance; only the first Jacobian of each step differs)."""
import numpy as np
import pytest

from nnm_solver.continuation.engine import ContinuationSettings, pseudo_arclength
from nnm_solver.continuation.linalg import LeastSquares, stacked


@pytest.mark.parametrize("n", [80, 200])
def test_row_replaced_solve_is_exact(n):
    rng = np.random.default_rng(n)
    J = rng.standard_normal((n - 1, n))
    old, new = rng.standard_normal(n), rng.standard_normal(n)
    base = LeastSquares(stacked(J, old))
    solver = base.with_last_row(new)
    b = rng.standard_normal(n)
    x = np.linalg.solve(np.vstack([J, new]), b)
    assert np.allclose(solver.solve(b), x, rtol=1e-10, atol=1e-12)
    B = rng.standard_normal((n, 3))
    assert np.allclose(solver.solve(B), np.linalg.solve(np.vstack([J, new]), B), rtol=1e-10, atol=1e-12)


def test_row_replaced_refuses_what_it_cannot_do_exactly():
    rng = np.random.default_rng(1)
    J = rng.standard_normal((99, 100))
    # a least-squares (over-determined) factorisation: no exact row update
    assert LeastSquares(stacked(np.vstack([J, J[:1]]), rng.standard_normal(100))).with_last_row(np.ones(100)) is None
    # the new row makes the system singular (it lies in J's row space): no update
    base = LeastSquares(stacked(J, rng.standard_normal(100)))
    assert base.with_last_row(J[0] + 2 * J[5]) is None


class _Circle:
    """F(x, y, z) = [x^2 + y^2 - 1, z - x y] on a 100-dimensional embedding (square corrector systems: LU), with a
    counter of Jacobian evaluations."""

    def __init__(self, n=70):
        self.n = n
        self.jacobians = 0

    def residual(self, u):
        x, y = u[0], u[1]
        return np.concatenate([[x * x + y * y - 1.0, u[2] - x * y], u[3:] - 0.1 * np.sin(x) * np.arange(self.n - 3)
                               / self.n])

    def jacobian(self, u):
        self.jacobians += 1
        x, y = u[0], u[1]
        J = np.zeros((self.n - 1, self.n))
        J[0, 0], J[0, 1] = 2 * x, 2 * y
        J[1, 0], J[1, 1], J[1, 2] = -y, -x, 1.0
        J[2:, 3:] = np.eye(self.n - 3)
        J[2:, 0] = -0.1 * np.cos(x) * np.arange(self.n - 3) / self.n
        return self.residual(u), J

    def error(self, u, r):
        return float(np.linalg.norm(r))

    def accept(self, u, J):
        pass


def _branch(chord_start, points=40):
    problem = _Circle()
    u0 = np.zeros(problem.n)
    u0[0] = 1.0
    u0[3:] = 0.1 * np.sin(1.0) * np.arange(problem.n - 3) / problem.n
    p0 = np.zeros(problem.n)
    p0[1] = 1.0
    cs = ContinuationSettings(step=0.05, step_min=1e-6, step_max=0.2, chord_start=chord_start)
    out = []
    for k, pt in enumerate(pseudo_arclength(problem, u0, p0, cs, 1e-11)):
        out.append(pt.u)
        if k == points:
            break
    return np.array(out), problem.jacobians


def test_branch_with_chord_start_is_on_the_same_curve_with_one_jacobian_a_point():
    U0, j0 = _branch(False)
    U1, j1 = _branch(True)
    for U in (U0, U1):
        assert np.allclose(U[:, 0] ** 2 + U[:, 1] ** 2, 1.0, atol=1e-10)
        assert np.allclose(U[:, 2], U[:, 0] * U[:, 1], atol=1e-10)
    a0, a1 = np.unwrap(np.arctan2(U0[:, 1], U0[:, 0])), np.unwrap(np.arctan2(U1[:, 1], U1[:, 0]))
    assert np.all(np.diff(a1) > 0) and a1[-1] > 1.0        # along the curve, the same way
    # one Jacobian a point (the converged point's) against two (the prediction's and the converged point's)
    assert j1 <= len(U1) + 2 and j0 >= 1.8 * len(U0)
