"""The multipliers' dense eigenproblem by LAPACK dgeev from compiled code that releases the GIL (jit.eigvals_nogil,
floquet.eigenvalues): the eigenvalues of numpy's eigvals, NaN for a matrix that is not finite, and a kernel compiled
without the GIL (so the worker threads' eigenproblems run beside the continuation; numpy 1.26's eigvals holds it)."""
import numpy as np
import pytest

from nnm_solver import jit
from nnm_solver.stability.floquet import eigenvalues


def _same_set(a, b, tol):
    gaps = np.abs(np.asarray(a)[:, None] - np.asarray(b)[None, :])
    return len(a) == len(b) and gaps.min(axis=1).max() <= tol and gaps.min(axis=0).max() <= tol


@pytest.mark.parametrize("n", [1, 2, 7, 120])
def test_the_eigenvalues_of_numpy(n):
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n))
    c = eigenvalues(A)
    ref = np.linalg.eigvals(A)
    assert c.dtype == complex and _same_set(c, ref, 1e-11 * max(1.0, np.abs(ref).max()))
    if n > 2:
        assert np.any(np.abs(c.imag) > 1e-3)                   # (complex pairs among them)
    S = A + A.T                                                # real spectrum: real eigenvalues
    assert np.all(eigenvalues(S).imag == 0) and _same_set(eigenvalues(S), np.linalg.eigvalsh(S), 1e-11 * n)


def test_not_finite_gives_nan_and_empty_is_empty():
    A = np.eye(4)
    A[1, 2] = np.nan
    assert np.all(np.isnan(eigenvalues(A)))
    assert eigenvalues(np.zeros((0, 0))).shape == (0,)
    assert np.all(np.isnan(eigenvalues(np.full((3, 3), np.inf))))


@pytest.mark.skipif(jit.numba is None or jit._GEEV is None, reason="numba's LAPACK not available")
def test_the_kernel_releases_the_gil():
    wr, wi, info = jit._geev_values(np.diag([1.0, 2.0]))
    assert info == 0 and sorted(wr) == [1.0, 2.0] and not wi.any()
    assert jit._geev_values.targetoptions.get("nogil") is True
    assert jit.eigvals_nogil(np.diag([3.0, -1.0])).tolist() == [3.0 + 0j, -1.0 + 0j]
