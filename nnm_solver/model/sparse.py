"""Sparse symmetric factorisation and solve with a fill-reducing ordering.

Used by Craig-Bampton (reduction.py), the Ritz basis (ritz.py) and the FE kit (nnm_fem) for shift-invert
eigensolves.  Two back ends:

- CHOLMOD (scikit-sparse, the optional extra ``nnm[sparse]``): supernodal Cholesky with its own fill-reducing
  ordering (AMD, METIS tried), for symmetric positive definite matrices.  Used whenever it is installed and the
  matrix is positive definite: on the full aircraft's K (64,446 DOFs, benchmarks/bench_sparse.py) it factorises
  in 0.9 s against SuperLU's 8.9 s with the nested dissection below (12.9 s with COLAMD), holds 166 MB against
  1,058 MB, solves 8 right-hand sides 4x faster, at the same backward error (1e-13).
- SuperLU (scipy, always there): LU with scipy's COLAMD ordering, or, given the node coordinates ``xyz``, with
  the nodes' geometric nested dissection in symmetric mode.  The fallback when CHOLMOD is not installed, and for
  matrices that are not positive definite (a shift inside the spectrum, a singular K: SuperLU's RuntimeError
  "Factor is exactly singular" is what callers catch).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


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


#: the back ends of SparseSolver: "auto" (CHOLMOD if installed and the matrix is positive definite, else SuperLU)
BACKENDS = ("auto", "cholmod", "superlu")


def _cholmod():
    """scikit-sparse's CHOLMOD module, or None when it is not installed."""
    try:
        from sksparse import cholmod
    except ImportError:
        return None
    return cholmod


def cholmod_available():
    return _cholmod() is not None


class SparseSolver:
    """Factorisation of a symmetric FE matrix A; ``solve(b)`` for b (n,) or (n, k).

    backend "auto" (default): CHOLMOD's Cholesky when scikit-sparse is installed and A is positive definite, else
    SuperLU (LU, nested-dissection ordering of the nodes when their coordinates ``xyz`` (n / ndof, 3) are given,
    scipy's COLAMD otherwise); "cholmod" or "superlu" to choose (CHOLMOD refuses a matrix that is not positive
    definite with its CholmodNotPositiveDefiniteError).  ``backend`` tells which one factorised A.
    """

    def __init__(self, A, xyz=None, ndof=6, backend="auto"):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        A = sp.csc_matrix(A)
        self.shape = A.shape
        self.p = None
        self.factor = None
        cholmod = _cholmod() if backend != "superlu" else None
        if backend == "cholmod" and cholmod is None:
            raise ImportError("the CHOLMOD back end needs scikit-sparse (pip install scikit-sparse)")
        if cholmod is not None:
            try:
                # supernodal: always L L^T, so that a matrix that is not positive definite is refused (the simplicial
                # mode CHOLMOD picks for small matrices is L D L^T without pivoting, which takes indefinite ones)
                self.factor = cholmod.cholesky(A.astype(float), mode="supernodal")
                self.backend = "cholmod"
                return
            except cholmod.CholmodNotPositiveDefiniteError:
                if backend == "cholmod":
                    raise
        self.backend = "superlu"
        if xyz is None:
            self.lu = spla.splu(A)
        else:
            self.p = dof_ordering(A, xyz, ndof)
            Ap = A[self.p][:, self.p].tocsc()
            self.lu = spla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                options=dict(SymmetricMode=True))

    def solve(self, b):
        if self.factor is not None:
            return self.factor.solve_A(np.asarray(b, dtype=float))
        if self.p is None:
            return self.lu.solve(b)
        b = np.asarray(b)
        y = np.empty_like(b, dtype=float)
        y[self.p] = self.lu.solve(np.ascontiguousarray(b[self.p]))
        return y
