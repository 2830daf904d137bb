"""Sparse symmetric factorisation and solve with a fill-reducing ordering (geometric nested dissection).

Used by Craig-Bampton (reduction.py) and by the FE kit (nnm_fem) for shift-invert eigensolves.
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


class SparseSolver:
    """LU factorisation of a symmetric FE matrix with nested-dissection ordering; solve(b)."""

    def __init__(self, A, xyz=None, ndof=6):
        A = sp.csc_matrix(A)
        if xyz is None:
            self.p = None
            self.lu = spla.splu(A)
        else:
            self.p = dof_ordering(A, xyz, ndof)
            Ap = A[self.p][:, self.p].tocsc()
            self.lu = spla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                options=dict(SymmetricMode=True))
        self.shape = A.shape

    def solve(self, b):
        if self.p is None:
            return self.lu.solve(b)
        b = np.asarray(b)
        y = np.empty_like(b, dtype=float)
        y[self.p] = self.lu.solve(np.ascontiguousarray(b[self.p]))
        return y
