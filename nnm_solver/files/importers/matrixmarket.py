"""MatrixMarket (.mtx) matrices, read by ``scipy.io.mmread`` (coordinate or array, general or symmetric).

A model is a pair of files, M and K, of the same size; MatrixMarket carries no DOF map (give one in
the model description, ``dof_map = "dofs.txt"``, to name springs and mesh nodes by node).
"""
from __future__ import annotations

import numpy as np
import scipy.io
import scipy.sparse as sp

from ...errors import NNMFileError
from .common import existing


def read_mtx(path, what="matrix", square=True):
    """A MatrixMarket file as a CSR matrix (float); one-line NNMFileError if it is missing or not MatrixMarket
    (or not square, unless ``square=False``)."""
    path = existing(path, f"{what} matrix")
    try:
        A = scipy.io.mmread(path)
    except Exception as exc:  # scipy raises ValueError, IndexError, ... for malformed files
        raise NNMFileError(f"{path}: not a readable MatrixMarket file ({exc.__class__.__name__}: "
                           f"{str(exc).splitlines()[0] if str(exc) else 'malformed'})") from None
    if np.iscomplexobj(A.data if sp.issparse(A) else A):
        raise NNMFileError(f"{path}: the {what} matrix is complex; nnm needs real matrices")
    A = A.tocsr().astype(float) if sp.issparse(A) else np.asarray(A, dtype=float)
    if A.ndim != 2 or (square and A.shape[0] != A.shape[1]):
        raise NNMFileError(f"{path}: the {what} matrix must be square, got shape {A.shape}")
    return sp.csr_matrix(A)


def read_mtx_pair(mass, stiffness):
    """(M, K) from two MatrixMarket files, checked for equal sizes."""
    M = read_mtx(mass, "mass")
    K = read_mtx(stiffness, "stiffness")
    if M.shape != K.shape:
        raise NNMFileError(f"{mass} is {M.shape[0]}x{M.shape[1]} but {stiffness} is {K.shape[0]}x{K.shape[1]}; "
                           f"M and K must have the same size")
    return M, K
