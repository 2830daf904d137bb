"""The compiled kernels of condensed harmonic balance (orbits/condensed_kernels.py; issue 52): residual, Jacobian,
energy, its gradient and the modal amplitudes equal the numpy forms to round-off, on complete and truncated linear
parts, polynomial and piecewise-linear springs, odd and full bases; the Jacobian and the gradient are also checked
against central differences (independent of both forms)."""
import copy

import numpy as np
import pytest

from nnm_solver.model.modal import modal_system
from nnm_solver.orbits import condensed_kernels
from nnm_solver.orbits.condensed_hb import CondensedHBProblem, LinearPart
from nnm_solver.orbits.hb_basis import HBBasis
from test_per_point import MODELS, _perturbed

pytestmark = pytest.mark.skipif(not condensed_kernels.AVAILABLE, reason="numba is not installed")


def numpy_form(p):
    """The same problem evaluated by the numpy forms."""
    q = copy.copy(p)
    q._kernel = None
    q._last_parts = None
    return q


def problems():
    for name in ("cubic", "polynomial", "piecewise"):
        system = modal_system(MODELS[name]())
        for kind in ("odd", "full"):
            if kind == "odd" and not system.elements.odd:
                continue
            yield f"{name}-{kind}", CondensedHBProblem(system, 1, HBBasis(5, kind))
    system = modal_system(MODELS["cubic"]())
    rng = np.random.default_rng(5)
    R0, R1 = 0.05 * rng.standard_normal((2, 2, 2))
    for kind in ("odd", "full"):
        lin = LinearPart(system.omega2[:3], system.Bq[:, :3], R0=R0, R1=R1)
        yield f"truncated-{kind}", CondensedHBProblem(system, 1, HBBasis(5, kind), lin)


CASES = dict(problems())


@pytest.mark.parametrize("name", sorted(CASES))
def test_kernels_equal_the_numpy_forms(name):
    p = CASES[name]
    assert p._kernel is not None
    q = numpy_form(p)
    for seed in (0, 1):
        u = _perturbed(p, 0.6, seed)
        r, J = p.jacobian(u)
        r0, J0 = q.jacobian(u)
        assert np.max(np.abs(r - r0)) <= 1e-14 * np.max(np.abs(r0)) + 1e-15 * np.max(np.abs(u))
        assert np.max(np.abs(J - J0)) <= 1e-14 * np.max(np.abs(J0))
        assert np.array_equal(p.residual(u), r)                         # the residual alone is the same numbers
        parts = p.residual_parts(u)
        assert np.array_equal(parts[-1], r) and np.array_equal(p.jacobian_of(parts)[1], J)
        assert abs(p.energy(u) - q.energy(u)) <= 1e-14 * abs(q.energy(u))
        g, g0 = p.energy_gradient(u), q.energy_gradient(u)
        assert np.max(np.abs(g - g0)) <= 1e-13 * np.max(np.abs(g0))
        A, A0 = p.amplitudes(u)[0], q.amplitudes(u)[0]
        assert np.max(np.abs(A - A0)) <= 1e-14 * np.max(np.abs(A0))


@pytest.mark.parametrize("name", ["cubic-odd", "piecewise-full", "truncated-full"])
def test_kernel_jacobian_and_gradient_are_the_derivatives(name):
    """Central differences of the kernels' residual and energy (step 1e-6 of u's size: their error ~1e-9)."""
    p = CASES[name]
    u = _perturbed(p, 0.6, 3)
    r, J = p.jacobian(u)
    h = 1e-6 * np.max(np.abs(u))
    Jfd = np.column_stack([(p.residual(u + h * e) - p.residual(u - h * e)) / (2 * h) for e in np.eye(len(u))])
    assert np.max(np.abs(J - Jfd)) < 1e-6 * np.max(np.abs(J))
    g, gfd = p.energy_gradient(u), p.energy_gradient_fd(u, h=1e-6)
    assert np.max(np.abs(g - gfd)) < 1e-6 * np.max(np.abs(g))


def test_the_correctors_qr_through_numba_is_scipys(monkeypatch):
    """continuation/linalg.py: the small QR by LAPACK through numba has scipy.linalg.qr's factors bit for bit, and its
    compiled solve scipy's triangular solve's result to round-off; an exactly singular system gives a non-finite
    solution as before."""
    from nnm_solver.continuation import linalg
    rng = np.random.default_rng(11)
    A = rng.standard_normal((23, 22))
    b = rng.standard_normal(23)
    fast = linalg.LeastSquares(np.array(A, order="F"))
    monkeypatch.setattr(linalg, "_GEQRF", None)
    plain = linalg.LeastSquares(np.array(A, order="F"))
    assert np.array_equal(fast.R, plain.R) and np.array_equal(fast._Q, plain._Q)
    x, x0 = fast.solve(b), plain.solve(b)
    assert np.max(np.abs(x - x0)) <= 1e-13 * np.max(np.abs(x0))
    assert np.allclose(A.T @ (A @ x - b), 0.0, atol=1e-12)        # the least-squares normal equations
    monkeypatch.undo()
    singular = np.array(A, order="F")
    singular[:, 3] = 0.0
    assert not np.all(np.isfinite(linalg.LeastSquares(singular).solve(b)))
