"""Sparse symmetric factorisation and solve with a fill-reducing ordering.

Used by Craig-Bampton (reduction.py), the Ritz basis (ritz.py, lanczos.py) and the FE kit (nnm_fem) for
shift-invert eigensolves.  Three back ends, tried in this order by ``backend="auto"``:

- CHOLMOD through scikit-sparse (the optional extra ``nnm[sparse]``, which needs SuiteSparse's headers to build):
  supernodal Cholesky, for symmetric positive definite matrices.
- CHOLMOD through cholespy (a main dependency: a self-contained wheel, CHOLMOD and METIS inside): simplicial
  Cholesky L L^T with nested-dissection ordering, for symmetric positive definite matrices.  On the unreduced
  aircraft's K (64,446 DOFs, 3.4 M nonzeros, benchmarks/bench_sparse.py) it factorises in 2-3 s against SuperLU's
  6-8 s, solves 16 right-hand sides in 0.15-0.2 s against 0.7 s, with a componentwise backward error of 1e-13
  against SuperLU's 1e-7.
- SuperLU (scipy, always there): LU with scipy's COLAMD ordering, or, given the node coordinates ``xyz``, with
  the nodes' geometric nested dissection in symmetric mode.  The fallback when neither CHOLMOD is installed, and
  for matrices that are not positive definite or not symmetric (a shift inside the spectrum, a singular K:
  SuperLU's RuntimeError "Factor is exactly singular" is what callers catch).

Accuracy.  A stiffness matrix whose diagonal spans many decades (the aircraft's: 2e2 to 8e11 N/m) has a large
condition number, so the relative residual ||A x - b|| / ||b|| of any double-precision solve is dominated by the
round-off of evaluating A x itself (1e-6 on the aircraft for every back end) and says little.  The measure of a
solve is its componentwise backward error  max_i |A x - b|_i / (|A| |x| + |b|)_i  (Oettli-Prager: x solves a
system whose every entry is perturbed by that relative amount).  After each factorisation the solver measures it
on a probe right-hand side (``backward_error``); when it is above ``MODEL.solve_backward_error`` every solve is
followed by up to ``MODEL.solve_refinement_steps`` steps of iterative refinement (x += solve(b - A x)), which bring
it down to ~1e-15 (``refined`` says whether they are on).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .settings import MODEL


def nested_dissection(adj, xyz, leaf=48):
    """Node permutation (n,) by recursive coordinate bisection; separators ordered last.

    adj : (n, n) sparse node adjacency; xyz : (n, 3) node coordinates (m).
    """
    adj = sp.csr_matrix(adj)
    perm = []
    def rec(idx, depth):
        if len(idx) <= leaf or depth > 60:
            perm.extend(idx.tolist())
            return
        X = xyz[idx]
        ax = int(np.argmax(np.ptp(X, axis=0)))
        order = np.argsort(X[:, ax], kind="stable")
        half = len(idx) // 2
        A, B = idx[order[:half]], idx[order[half:]]
        sub = adj[A][:, B]
        sep = np.diff(sub.indptr) > 0
        S = A[sep]
        A = A[~sep]
        rec(A, depth + 1)
        rec(B, depth + 1)
        perm.extend(S.tolist())
    rec(np.arange(adj.shape[0]), 0)
    return np.asarray(perm, np.int64)


def dof_ordering(A, xyz, ndof=6):
    """DOF permutation of an FE matrix A (6 DOF per node) from nested dissection of its nodes."""
    n_nodes = A.shape[0] // ndof
    C = sp.coo_matrix(A)
    adj = sp.csr_matrix((np.ones(C.nnz), (C.row // ndof, C.col // ndof)), shape=(n_nodes, n_nodes))
    p = nested_dissection(adj, xyz)
    return (ndof * p[:, None] + np.arange(ndof)).ravel()


#: the back ends of SparseSolver: "auto" (the first of CHOLMOD by scikit-sparse, CHOLMOD by cholespy, SuperLU that
#: is installed and takes the matrix), or one of them by name
BACKENDS = ("auto", "cholmod", "cholespy", "superlu")


def _cholmod():
    """scikit-sparse's CHOLMOD module, or None when it is not installed."""
    try:
        from sksparse import cholmod
    except ImportError:
        return None
    return cholmod


def _cholespy():
    """The cholespy module, or None when it is not installed."""
    try:
        import cholespy
    except ImportError:
        return None
    return cholespy


def cholmod_available():
    """True when scikit-sparse's CHOLMOD is installed."""
    return _cholmod() is not None


def cholespy_available():
    """True when cholespy (CHOLMOD in a wheel) is installed."""
    return _cholespy() is not None


def is_symmetric(A, rtol=1e-12):
    """True when the sparse A equals its transpose to rtol of its largest entry (the Cholesky back ends read one
    triangle only)."""
    D = A - A.T
    return D.nnz == 0 or float(abs(D).max()) <= rtol * float(abs(A).max())


def backward_error(A, x, b):
    """Componentwise backward error max_i |A x - b|_i / (|A| |x| + |b|)_i of a solution x (n,) or (n, k)."""
    r = np.abs(A @ x - b)
    scale = abs(A) @ np.abs(x) + np.abs(b)
    return float(np.max(r / np.maximum(scale, np.finfo(float).tiny)))


def _cholespy_factor(A):
    """cholespy's factor of the symmetric positive definite A (csc), or None when CHOLMOD finds it is not."""
    cholespy = _cholespy()
    A = A.copy()
    A.sort_indices()
    try:
        f = cholespy.CholeskySolverD(A.shape[0], A.indptr.astype(np.int32), A.indices.astype(np.int32),
                                     np.ascontiguousarray(A.data, dtype=np.float64), cholespy.MatrixType.CSC)
    except ValueError:                                 # "Matrix is not positive definite!"
        return None

    def solve(b):
        b = np.ascontiguousarray(b, dtype=np.float64)
        x = np.empty_like(b)
        f.solve(b, x)
        return x
    return solve


class SparseSolver:
    """Factorisation of a symmetric FE matrix A; ``solve(b)`` for b (n,) or (n, k).

    backend "auto" (default): CHOLMOD's Cholesky (scikit-sparse, else cholespy) when A is symmetric and positive
    definite, else SuperLU (LU, nested-dissection ordering of the nodes when their coordinates ``xyz`` (n / ndof, 3)
    are given, scipy's COLAMD otherwise); "cholmod", "cholespy" or "superlu" to choose (a Cholesky back end refuses
    a matrix that is not positive definite: scikit-sparse with its CholmodNotPositiveDefiniteError, cholespy with
    ValueError).  ``backend`` tells which one factorised A; ``backward_error`` the componentwise backward error of
    a probe solve, ``refined`` whether solves are refined (module docstring).
    """

    def __init__(self, A, xyz=None, ndof=6, backend="auto"):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        A = sp.csc_matrix(A).astype(float)
        self.shape = A.shape
        self.A = A
        self.p = None
        self.lu = None
        self._solve = None
        self.refined = False
        self.backend = self._factorise(A, xyz, ndof, backend)
        self.backward_error = self._probe()
        self.refined = self.backward_error > MODEL.solve_backward_error

    def _factorise(self, A, xyz, ndof, backend):
        """Factorise A with the back end asked for (or the first that takes it); its name."""
        symmetric = backend in ("cholmod", "cholespy") or (backend == "auto" and is_symmetric(A))
        if backend in ("auto", "cholmod") and symmetric:
            cholmod = _cholmod()
            if backend == "cholmod" and cholmod is None:
                raise ImportError("the CHOLMOD back end needs scikit-sparse (pip install scikit-sparse)")
            if cholmod is not None:
                try:
                    # supernodal: always L L^T, so that a matrix that is not positive definite is refused (the
                    # simplicial mode CHOLMOD picks for small matrices is L D L^T without pivoting)
                    self._solve = cholmod.cholesky(A, mode="supernodal").solve_A
                    return "cholmod"
                except cholmod.CholmodNotPositiveDefiniteError:
                    if backend == "cholmod":
                        raise
        if backend in ("auto", "cholespy") and symmetric:
            if backend == "cholespy" and _cholespy() is None:
                raise ImportError("the cholespy back end needs cholespy (pip install cholespy)")
            if _cholespy() is not None:
                self._solve = _cholespy_factor(A)
                if self._solve is not None:
                    return "cholespy"
                if backend == "cholespy":
                    raise ValueError("cholespy: the matrix is not positive definite")
        if xyz is None:
            self.lu = spla.splu(A)
            self._solve = self.lu.solve
        else:
            self.p = dof_ordering(A, xyz, ndof)
            Ap = A[self.p][:, self.p].tocsc()
            self.lu = spla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                options=dict(SymmetricMode=True))
            self._solve = self._solve_permuted
        return "superlu"

    def _solve_permuted(self, b):
        y = np.empty(b.shape, dtype=float)
        y[self.p] = self.lu.solve(np.ascontiguousarray(b[self.p]))
        return y

    def _probe(self):
        """The componentwise backward error of solving A x = A 1 + r (r: a fixed random vector, so that both
        smooth and rough right-hand sides are in it)."""
        n = self.shape[0]
        b = self.A @ np.ones(n) + np.random.default_rng(0).standard_normal(n) * abs(self.A).sum(axis=1).A1
        return backward_error(self.A, self._solve(b), b)

    def solve(self, b):
        """x with A x = b, for b (n,) or (n, k) (refined when ``refined``)."""
        b = np.asarray(b, dtype=float)
        x = self._solve(b)
        if self.refined:
            for _ in range(MODEL.solve_refinement_steps):
                x += self._solve(b - self.A @ x)
        return x
