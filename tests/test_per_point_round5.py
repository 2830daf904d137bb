"""Round 5 of the lean per-point path of condensed harmonic balance (issue 52): the corrector's compiled chord iterations
are generic (continuation/chord.py, the residual kernel passed to them; orbits/ holds only the kernel), with the
iterates of the corrector's own Python loop bit for bit.

* any problem offering ``residual_kernel`` (chord.residual_kernel of a compiled ``kernel(u, args)``) has its chord
  iterations compiled: checked here on a problem of this test's own (a kernel the solver does not know), iterate for
  iterate against the Python loop;
* one compiled loop serves every kernel of the same argument types (the kernel is an address, not part of the
  loop's type: numba caches it on disk once);
* the condensed problem's branches with the compiled loop equal those of the Python loop (tests/test_per_point_round4.py
  checks the iterates on the condensed problem; benchmarks/bench_per_point.py --compare the five branches).
"""
import numpy as np
import pytest

import nnm_solver as nnm
from corrector_runs import corrected, same_run
from nnm_solver.continuation import chord
from nnm_solver.continuation.engine import ContinuationSettings, correct_factored, tangent

numba = pytest.importorskip("numba")
needs_chord = pytest.mark.skipif(not chord.AVAILABLE, reason="numba (with its LAPACK) is not installed")


@numba.njit
def _linear_part(u, A, b):
    """A x - lam b (x = u[:-1], lam = u[-1])."""
    n = b.shape[0]
    r = np.empty(n)
    for i in range(n):
        acc = -u[n] * b[i]
        for j in range(n):
            acc += A[i, j] * u[j]
        r[i] = acc
    return r


@numba.njit
def _toy_residual(u, args):
    """F(u) = A x + c x^3 - lam b (x = u[:-1], lam = u[-1]): n equations in n + 1 unknowns, a curve of solutions."""
    A, c, b = args
    return _linear_part(u, A, b) + c * u[:-1] ** 3


@numba.njit
def _other_residual(u, args):
    """Another kernel of the same argument types: F(u) = A x + c sin(x) - lam b."""
    A, c, b = args
    return _linear_part(u, A, b) + c * np.sin(u[:-1])


class ToyProblem:
    """A problem of the engine's protocol whose residual is a compiled kernel of this test (the solver knows nothing
    of it): residual, jacobian (the kernel's by hand), error |r| / |u[:-1]| and, when ``compiled``, residual_kernel."""

    def __init__(self, n=6, seed=1, kernel=_toy_residual):
        rng = np.random.default_rng(seed)
        M = rng.standard_normal((n, n))
        self.A = M @ M.T / n + np.eye(n)
        self.c = rng.uniform(0.5, 2.0, n)
        self.b = rng.standard_normal(n)
        self.args = (self.A, self.c, self.b)
        self.kernel = kernel
        self.residual_kernel = chord.residual_kernel(kernel, self.args)

    def residual(self, u):
        return self.kernel(np.ascontiguousarray(u, dtype=float), self.args)

    def jacobian(self, u):
        n = len(self.b)
        x = u[:n]
        J = np.empty((n, n + 1))
        J[:, :n] = self.A
        d = 3 * self.c * x ** 2 if self.kernel is _toy_residual else self.c * np.cos(x)
        J[np.arange(n), np.arange(n)] += d
        J[:, n] = -self.b
        return self.residual(u), J

    def error(self, u, r):
        x = u[:-1]
        return float(np.sqrt(r.dot(r)) / max(np.sqrt(x.dot(x)), 1e-300))


@needs_chord
@pytest.mark.parametrize("kernel", [_toy_residual, _other_residual])
def test_a_kernel_of_another_problem_gets_the_correctors_iterates(monkeypatch, kernel):
    """correct_factored on the toy problem with the compiled chord loop (its kernel passed to it) and with the
    corrector's Python loop: the same point, Jacobian, iterations and error bit for bit, or the same failure, from
    predictions near and far along its solution curve, with few iterations allowed, without the final refresh and from
    a given iterate and factorisation; the compiled loop was called, and the Python loop evaluated residuals."""
    prob = ToyProblem(kernel=kernel)
    n = len(prob.b)
    u0 = np.zeros(n + 1)
    u0[n] = 0.5
    x = np.linalg.solve(prob.A, 0.5 * prob.b)
    u0[:n] = x                                       # near the curve (the cubic term not yet balanced)
    settings = ContinuationSettings(0.1, 1e-6, 1.0, max_iter=25)
    u, J, *_ = correct_factored(prob, u0, np.eye(n + 1)[n], settings, 1e-13)
    p = tangent(J, np.eye(n + 1)[n])
    w = np.ones(n + 1)
    cases = [(u + s * p, ContinuationSettings(0.1, 1e-6, 1.0, max_iter=m), refresh, None)
             for s in (0.02, 0.3, 1.0, 3.0) for m in (12, 3) for refresh in (True, False)]
    row = w * w * p
    factor = correct_factored(prob, u, p, settings, 1e-13, w)[4]
    cases += [(u + s * p, settings, False, (u + s * p, factor)) for s in (0.05, 0.4)]
    calls = []
    real = chord.chord_iterations

    def counted(*a):
        calls.append(1)
        return real(*a)

    monkeypatch.setattr(chord, "chord_iterations", counted)
    new = [corrected(prob, up, p, cs, 1e-12, w, start, refresh) for up, cs, refresh, start in cases]
    assert len(calls) >= len(cases) and row.dot(row) > 0
    evaluated = []
    with monkeypatch.context() as m:
        m.setattr(chord, "AVAILABLE", False)
        real_residual = prob.residual
        m.setattr(prob, "residual", lambda v: evaluated.append(1) or real_residual(v))
        old = [corrected(prob, up, p, cs, 1e-12, w, start, refresh) for up, cs, refresh, start in cases]
    assert len(evaluated) > len(cases)               # the Python loop iterated on residuals
    assert sum(not isinstance(x, str) for x in old) >= 8 and max(x[2] for x in old if not isinstance(x, str)) >= 3
    for a, b in zip(new, old):
        assert same_run(a, b), (a, b)


@needs_chord
def test_one_compiled_loop_serves_every_kernel_of_the_same_argument_types():
    """Two kernels with the same argument types run in the one compiled chord loop (the kernel is its address, an
    integer: not part of the loop's type, so the loop is compiled and cached once, not around each kernel)."""
    before = set(chord.chord_iterations.signatures)
    for kernel in (_toy_residual, _other_residual):
        prob = ToyProblem(kernel=kernel)
        n = len(prob.b)
        u0 = np.append(np.linalg.solve(prob.A, 0.3 * prob.b), 0.3)
        correct_factored(prob, u0, np.eye(n + 1)[n], ContinuationSettings(0.1, 1e-6, 1.0), 1e-12)
    added = set(chord.chord_iterations.signatures) - before
    assert len(added) <= 1
    assert all("int64" in str(sig[11]) for sig in chord.chord_iterations.signatures)     # the kernel's address
    k1, k2 = (chord.residual_kernel(k, ToyProblem().args)[0] for k in (_toy_residual, _other_residual))
    assert k1.address != k2.address and chord.residual_kernel(_toy_residual, ToyProblem().args)[0] is k1
    # the kept kernels are told apart by what numba's types depend on (a read-only or Fortran-ordered constant: another
    # signature of the kernel, another entry point)
    A, c, b = ToyProblem().args
    frozen = A.copy()
    frozen.setflags(write=False)
    for other in ((frozen, c, b), (np.asfortranarray(A + 0.0), c, b)):
        k3 = chord.residual_kernel(_toy_residual, other)[0]
        assert k3 is not k1 and k3.address != k1.address
        u = np.append(np.linalg.solve(A, 0.3 * b), 0.3)
        assert np.array_equal(_toy_residual(u, other), _toy_residual(u, (A, c, b)))


@numba.njit
def _raising_residual(u, args):
    """_toy_residual, raising beyond lam = 5 (a kernel's own error)."""
    if u[u.shape[0] - 1] > 5.0:
        raise ValueError("the kernel's own error: lam beyond 5")
    return _toy_residual(u, args)


@needs_chord
def test_a_kernels_exception_reaches_the_caller():
    """An exception raised by the kernel inside the compiled chord loop reaches its caller with its message (the kernel
    is called by numba's calling convention, as a compiled call raises it), and below lam = 5 the same kernel runs."""
    from nnm_solver.continuation.linalg import LeastSquares, stacked
    good, bad = ToyProblem(), ToyProblem(kernel=_raising_residual)
    n = len(good.b)
    row = np.eye(n + 1)[n]
    u = np.append(np.linalg.solve(good.A, 0.3 * good.b), 0.3)
    factor = LeastSquares(stacked(good.jacobian(u)[1], row))
    settings = ContinuationSettings(0.1, 1e-6, 1.0)
    out = chord.iterate(bad.residual_kernel, u, u, row, factor, None, 0, 1e-12, settings)
    assert np.array_equal(out[1], good.residual(out[0]))
    far = u.copy()
    far[n] = 6.0
    with pytest.raises(ValueError, match="lam beyond 5"):
        chord.iterate(bad.residual_kernel, far, far, row, factor, None, 0, 1e-12, settings)


@needs_chord
def test_a_pickled_problem_takes_its_kernels_address_again():
    """A ResidualKernel pickles as its kernel and signature, not its address (a process's own): unpickled, the
    condensed problem's kernel has this process's entry point and its corrector the same iterates."""
    import pickle
    from nnm_solver.model.modal import modal_system
    from nnm_solver.orbits.condensed_hb import CondensedHBProblem
    from nnm_solver.orbits.hb_basis import HBBasis
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    prob = CondensedHBProblem(modal_system(model), 0, HBBasis(5, "odd"))
    kernel = prob.residual_kernel[0]
    again = pickle.loads(pickle.dumps(kernel))
    assert again is not kernel and again.address == kernel.address and again.signature == kernel.signature
    copy = pickle.loads(pickle.dumps(prob))
    u0, p0 = prob.start(0.3)
    cs = ContinuationSettings(0.1, 1e-6, 1.0)
    a = correct_factored(prob, u0, p0, cs, 1e-12)
    b = correct_factored(copy, u0, p0, cs, 1e-12)
    assert np.array_equal(a[0], b[0]) and a[2] == b[2]


@needs_chord
def test_the_condensed_problem_offers_its_kernel_and_branches_are_the_python_loops(monkeypatch):
    """The condensed problem's residual_kernel is orbits' kernel (condensed_kernels.chord_residual) on its constants,
    returning its residual bit for bit; its branch (2-DOF, NNM 1 to 20 J) with the compiled loop equals the branch
    with the corrector's Python loop in every column."""
    from nnm_solver.orbits import condensed_kernels
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    it = nnm.iter_nnm(model, 1, 2.0, method="hb", condensed=True, floquet=False)
    for _ in it:
        pass
    prob, u = it._problem, it._prev[0].u
    kernel, args = prob.residual_kernel
    assert kernel.kernel is condensed_kernels.chord_residual and args is prob._kernel[0]
    assert np.array_equal(kernel.kernel(u, args), prob.residual(u))
    new = nnm.continue_nnm(model, 1, 20.0, method="hb", condensed=True)
    with monkeypatch.context() as m:
        m.setattr(chord, "AVAILABLE", False)
        old = nnm.continue_nnm(model, 1, 20.0, method="hb", condensed=True)
    assert len(new) == len(old) > 10
    for name in ("energy", "frequency_hz", "x0", "v0", "freq_error"):
        assert np.array_equal(getattr(new, name), getattr(old, name), equal_nan=True), name
    assert list(new.labels) == list(old.labels) and new.status == old.status
