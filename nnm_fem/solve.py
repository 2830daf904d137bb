"""Sparse generalized eigenproblems K phi = w^2 M phi by shift-invert Lanczos."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from nnm_solver.errors import NNMInputError
from nnm_solver.model.sparse import SparseSolver


def modes(K, M, n_modes, sigma=None, fixed=None, tol=0.0, xyz=None):
    """Lowest ``n_modes`` modes above the shift: (freqs_hz (n_modes,), shapes (n, n_modes)).

    K, M : sparse (n, n).  sigma : shift in (rad/s)^2 (default: a small negative value
    so that rigid-body modes are found).  fixed : DOF indices clamped to zero.
    Shapes are mass-normalised; frequencies of rigid-body modes are 0.  xyz : optional
    node coordinates (n/6, 3) for a nested-dissection ordering (much less fill).
    """
    K = sp.csc_matrix(K)
    M = sp.csc_matrix(M)
    n = K.shape[0]
    free = np.ones(n, bool)
    if fixed is not None:
        free[np.asarray(fixed, np.int64)] = False
    fi = np.flatnonzero(free)
    Kf, Mf = K[fi][:, fi].tocsc(), M[fi][:, fi].tocsc()
    if not 0 < n_modes < len(fi):
        raise NNMInputError(f"n_modes must be between 1 and {len(fi) - 1}, got {n_modes}")
    if sigma is None:
        scale = abs(Kf.diagonal()).max() / max(abs(Mf.diagonal()).max(), 1e-300)
        sigma = -1e-9 * scale
    if xyz is not None and fixed is None:
        lu = SparseSolver(Kf - sigma * Mf, xyz)
    else:
        lu = SparseSolver(Kf - sigma * Mf)
    op = spla.LinearOperator(Kf.shape, matvec=lu.solve, dtype=float)
    lam, V = spla.eigsh(Kf, k=n_modes, M=Mf, sigma=sigma, OPinv=op, which="LM", tol=tol)
    order = np.argsort(lam)
    lam, V = lam[order], V[:, order]
    V /= np.sqrt(np.einsum("ik,ik->k", V, Mf @ V))
    Phi = np.zeros((n, n_modes))
    Phi[fi] = V
    return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), Phi
