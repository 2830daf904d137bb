r"""Banded matrices for the general kernels in physical coordinates (general_band.py): LU with partial pivoting,
solves, and the band layout of a model (its DOFs renumbered by reverse Cuthill-McKee).

Storage: a band matrix A (n, n) of half-bandwidth w is the array Ab (n, 2 w + 1), Ab[i, j - i + w] = A[i, j].
The LU works on W (N, 2 kl + ku + 1), W[i, j - i + kl] = A[i, j] for j in [i - kl, i + ku] (the last kl columns
hold the fill of the row interchanges), as LAPACK's dgbtrf: L is kept as the sequence of its steps (the multipliers
of step k in column k of rows k + 1 .. k + kl, never swapped afterwards) with the pivots piv.  Costs: factor
O(N kl (kl + ku)), solve with m right-hand sides O(N (2 kl + ku) m): linear in N where dense LU is O(N^3).
Tested against numpy.linalg.solve (tests/test_general_band.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..jit import jit as _jit

__all__ = ["band_lu", "band_solve", "to_band", "BandLayout", "band_layout"]


@_jit
def band_lu(W, kl, ku):
    """LU of W (N, 2 kl + ku + 1) in place with partial pivoting; returns (piv (N,), ok): ok False at a zero
    pivot (a singular matrix) or a NaN/inf."""
    N = W.shape[0]
    piv = np.arange(N)
    for k in range(N):
        last = min(k + kl, N - 1)
        p = k
        best = abs(W[k, kl])
        for i in range(k + 1, last + 1):
            v = abs(W[i, k - i + kl])
            if v > best:
                best = v
                p = i
        piv[k] = p
        if not (best > 0.0) or not np.isfinite(best):
            return piv, False
        jmax = min(k + kl + ku, N - 1)
        if p != k:
            for j in range(k, jmax + 1):
                a = W[k, j - k + kl]
                W[k, j - k + kl] = W[p, j - p + kl]
                W[p, j - p + kl] = a
        d = W[k, kl]
        for i in range(k + 1, last + 1):
            l = W[i, k - i + kl] / d
            W[i, k - i + kl] = l
            if l != 0.0:
                oi = kl - i
                ok_ = kl - k
                for j in range(k + 1, jmax + 1):
                    W[i, j + oi] -= l * W[k, j + ok_]
    return piv, True


@_jit
def band_solve(W, piv, kl, ku, X):
    """Solves A Y = X in place for X (N, m), with W, piv the LU of band_lu."""
    N, m = X.shape
    for k in range(N):
        p = piv[k]
        if p != k:
            for c in range(m):
                a = X[k, c]
                X[k, c] = X[p, c]
                X[p, c] = a
        for i in range(k + 1, min(k + kl, N - 1) + 1):
            l = W[i, k - i + kl]
            if l != 0.0:
                for c in range(m):
                    X[i, c] -= l * X[k, c]
    for i in range(N - 1, -1, -1):
        for j in range(i + 1, min(i + kl + ku, N - 1) + 1):
            u = W[i, j - i + kl]
            if u != 0.0:
                for c in range(m):
                    X[i, c] -= u * X[j, c]
        d = W[i, kl]
        for c in range(m):
            X[i, c] /= d


def to_band(A, w):
    """Ab (n, 2 w + 1) of a dense or sparse A (n, n) whose entries lie within w of the diagonal."""
    A = sp.coo_matrix(A)
    Ab = np.zeros((A.shape[0], 2 * w + 1))
    np.add.at(Ab, (A.row, A.col - A.row + w), A.data)
    return Ab


@dataclass(frozen=True)
class BandLayout:
    """A model in physical coordinates, renumbered to a narrow band: x_p = x[perm].

    perm (n,) the DOF order (reverse Cuthill-McKee of the pattern of M, K and B^T B, or the model's own when that is
    narrower); w the half-bandwidth of M, K_linear and every tangent B^T T B in that order; Mb, Kb (n, 2 w + 1) the
    band arrays of M and K_linear; (Bp, Bi, Bx) the rows of B (n_d, n) in CSR form (indptr, indices, values) on the
    renumbered DOFs; Phi (n, n) the modes' rows renumbered (x_p = Phi q), PhiT its transpose (modal forces
    Phi^T f), PhiT_M (n, n) its left inverse (q = PhiT_M x_p) and MPhi = M Phi = PhiT_M^T (all C-contiguous).
    """

    perm: np.ndarray
    w: int
    Mb: np.ndarray
    Kb: np.ndarray
    Bp: np.ndarray
    Bi: np.ndarray
    Bx: np.ndarray
    Phi: np.ndarray
    PhiT: np.ndarray
    PhiT_M: np.ndarray
    MPhi: np.ndarray


def _bandwidth(P):
    P = sp.coo_matrix(P)
    return int(np.max(np.abs(P.row - P.col), initial=0))


def _element_rows(n_rows, index):
    """E (n_elements, n_rows): 1 where an element's force depends on a row of d (a spring on its own row, a coupled
    element on its m rows index[e, 0] ..)."""
    owner = np.arange(n_rows)
    for e, (r0, m) in enumerate(index[:, :2]):
        owner[r0:r0 + m] = n_rows + e
    _, owner = np.unique(owner, return_inverse=True)
    return sp.csr_matrix((np.ones(n_rows), (owner, np.arange(n_rows))), shape=(int(owner.max(initial=-1)) + 1, n_rows))


def band_layout(M, K, B, index, Phi, PhiT_M, accept=None):
    """The BandLayout of a model with mass M, linear stiffness K (dense or sparse, n x n), deformations d = B x
    (B (n_d, n)) with coupled elements on the rows of ``index`` (coupled.coupled_table), and a complete
    M-orthonormal basis Phi (n, n) with its left inverse PhiT_M = Phi^T M.  The pattern of the tangents is that of
    E^T E, E the DOFs each element's force depends on (a coupled element couples the DOFs of all its rows).
    accept(n, w) -> bool: None is returned (no band arrays built) when it refuses the half-bandwidth w."""
    M, K, B = sp.csr_matrix(M), sp.csr_matrix(K), sp.csr_matrix(B)
    E = _element_rows(B.shape[0], np.asarray(index)) @ abs(B)
    pattern = (abs(M) + abs(K) + E.T @ E).tocsr()
    pattern.eliminate_zeros()
    perm = np.asarray(reverse_cuthill_mckee(pattern, symmetric_mode=True), dtype=np.int64)
    if _bandwidth(pattern[perm][:, perm]) >= _bandwidth(pattern):
        perm = np.arange(M.shape[0])
    w = _bandwidth(pattern[perm][:, perm])
    if accept is not None and not accept(M.shape[0], w):
        return None
    Bp_ = B[:, perm].tocsr()
    Bp_.sort_indices()
    return BandLayout(perm=perm, w=w, Mb=to_band(M[perm][:, perm], w), Kb=to_band(K[perm][:, perm], w),
                      Bp=Bp_.indptr.astype(np.int64), Bi=Bp_.indices.astype(np.int64), Bx=Bp_.data.astype(float),
                      Phi=np.ascontiguousarray(Phi[perm]), PhiT=np.ascontiguousarray(Phi[perm].T),
                      PhiT_M=np.ascontiguousarray(PhiT_M[:, perm]), MPhi=np.ascontiguousarray(PhiT_M[:, perm].T))
