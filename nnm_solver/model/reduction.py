"""Craig-Bampton reduction and the modal assurance criterion (MAC)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import NNMInputError
from .sparse import SparseSolver


def _sym_sparse(name, A, n=None):
    if not sp.issparse(A):
        try:
            A = np.asarray(A, float)
        except (TypeError, ValueError):
            raise NNMInputError(f"{name} must be a numeric matrix") from None
        if A.ndim != 2:
            raise NNMInputError(f"{name} must be a 2-D matrix, got {A.ndim} dimensions")
        A = sp.csc_matrix(A)
    if A.shape[0] != A.shape[1] or (n is not None and A.shape[0] != n):
        raise NNMInputError(f"{name} must be square and match the other matrix, got shape {A.shape}")
    if not np.all(np.isfinite(A.data)):
        raise NNMInputError(f"{name} contains NaN or infinite entries")
    return A.tocsc().astype(float)


def craig_bampton(M, K, retained_dofs, n_modes, tol=0.0, xyz=None):
    """Craig-Bampton reduction  x = R [x_b; q].

    M, K : (n, n) dense or sparse mass (kg) and stiffness (N/m).
    retained_dofs : boundary DOF indices, kept first in the given order.
    n_modes : number of fixed-interface modes kept (lowest frequencies).
    Returns (Mr, Kr, R, fixed_hz): reduced dense matrices (n_b + n_modes square),
    R (n, n_b + n_modes) dense, and the fixed-interface frequencies in Hz.  The modal
    block of Mr is the identity (mass-orthonormal fixed-interface modes) and the modal
    block of Kr is diag((2 pi fixed_hz)^2).
    xyz : optional (n/6, 3) node coordinates of an FE model with 6 DOF per node, used
    for a nested-dissection ordering of the factorisation (much faster on big models).
    """
    K = _sym_sparse("K", K)
    n = K.shape[0]
    M = _sym_sparse("M", M, n)
    b = np.asarray(retained_dofs)
    if b.ndim != 1 or b.dtype.kind not in "iu" or len(b) == 0:
        raise NNMInputError("retained_dofs must be a non-empty 1-D list of integer DOF indices")
    if b.min() < 0 or b.max() >= n or len(np.unique(b)) != len(b):
        raise NNMInputError(f"retained_dofs must be distinct indices in 0..{n - 1}")
    internal = np.setdiff1d(np.arange(n), b)
    if not isinstance(n_modes, (int, np.integer)) or not 0 <= n_modes < len(internal) - 1:
        raise NNMInputError(f"n_modes must be an integer in 0..{len(internal) - 2}, got {n_modes!r}")
    Kii = K[internal][:, internal].tocsc()
    Mii = M[internal][:, internal].tocsc()
    Kib = K[internal][:, b].toarray()
    try:
        if xyz is not None:
            xyz = np.asarray(xyz, float)
            if xyz.shape != (n // 6, 3) or n % 6:
                raise NNMInputError(f"xyz must have shape (n/6, 3) = ({n // 6}, 3), got {xyz.shape}")
            lu = _InternalSolver(K, internal, xyz)
        else:
            lu = SparseSolver(Kii)
    except RuntimeError:
        raise NNMInputError("K restricted to the internal DOFs is singular: the structure with the retained "
                            "DOFs clamped still has rigid-body motion; retain more DOFs") from None
    Psi = -lu.solve(Kib)
    if n_modes > 0:
        op = spla.LinearOperator(Kii.shape, matvec=lu.solve, dtype=float)
        ncv = min(len(internal) - 1, n_modes + max(100, (2 * n_modes) // 5))  # ~20 % faster than 2k+1
        v0 = np.ones(len(internal)) / np.sqrt(len(internal))        # a fixed start: the same basis at every run
        lam, Phi = spla.eigsh(Kii, k=n_modes, M=Mii, sigma=0.0, OPinv=op, which="LM", tol=tol, ncv=ncv, v0=v0)
        order = np.argsort(lam)
        lam, Phi = lam[order], Phi[:, order]
        Phi /= np.sqrt(np.einsum("ik,ik->k", Phi, Mii @ Phi))
        # a fixed sign: each mode's largest entry positive, so that the reduced coordinates (and branches saved in
        # them) are the same at every build of the same model
        Phi *= np.sign(Phi[np.argmax(np.abs(Phi), axis=0), np.arange(Phi.shape[1])])
    else:
        lam, Phi = np.zeros(0), np.zeros((len(internal), 0))
    nb = len(b)
    R = np.zeros((n, nb + n_modes))
    R[b, np.arange(nb)] = 1.0
    R[internal, :nb] = Psi
    R[internal, nb:] = Phi
    Mr = R.T @ (M @ R)
    Kr = R.T @ (K @ R)
    # exact structure of the modal blocks (removes round-off)
    Mr[nb:, nb:] = np.eye(n_modes)
    Kr[nb:, nb:] = np.diag(lam)
    Kr[:nb, nb:] = 0.0
    Kr[nb:, :nb] = 0.0
    Mr = 0.5 * (Mr + Mr.T)
    Kr = 0.5 * (Kr + Kr.T)
    return Mr, Kr, R, np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)


class _InternalSolver:
    """Solve K_ii y = r with K_ii = K[internal][:, internal], ordered by node nested dissection.

    The retained DOFs are kept in the factorised matrix with a unit diagonal (decoupled),
    so that the node-based ordering of the whole model can be used.
    """

    def __init__(self, K, internal, xyz):
        n = K.shape[0]
        mask = np.zeros(n, bool)
        mask[internal] = True
        D = sp.diags(mask.astype(float))
        scale = float(abs(K.diagonal()).max())
        A = D @ K @ D + sp.diags((~mask).astype(float) * scale)
        self.solver = SparseSolver(A, xyz)
        self.internal = internal
        self.n = n

    def solve(self, b):
        b = np.asarray(b, float)
        full = np.zeros((self.n,) + b.shape[1:])
        full[self.internal] = b
        return self.solver.solve(full)[self.internal]


def mac(a, b, M=None):
    """Modal assurance criterion |a_i . b_j|^2 / ((a_i . a_i)(b_j . b_j)), in [0, 1] (seed eq. 19).

    a (n, na), b (n, nb): the MAC matrix (na, nb) between their columns; two vectors (n,): a float.
    M : optional mass matrix (n, n), dense or sparse: the mass-weighted MAC
    |a_i^T M b_j|^2 / ((a_i^T M a_i)(b_j^T M b_j)), for which distinct linear modes give exactly 0.
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    if a.ndim == 1 and b.ndim == 1:
        return float(mac(a[:, None], b[:, None], M)[0, 0])
    if a.ndim == 1:
        a = a[:, None]
    if b.ndim == 1:
        b = b[:, None]
    if a.ndim != 2 or b.ndim != 2 or a.shape[0] != b.shape[0]:
        raise NNMInputError(f"mac needs two sets of shapes with the same number of rows, got {a.shape} and {b.shape}")
    Ma = a if M is None else np.asarray(M @ a)
    Mb = b if M is None else np.asarray(M @ b)
    na = np.einsum("ij,ij->j", a, Ma)
    nb = np.einsum("ij,ij->j", b, Mb)
    if np.any(na == 0) or np.any(nb == 0):
        raise NNMInputError("mac: a shape column is identically zero")
    return (Ma.T @ b) ** 2 / np.outer(na, nb)


def mass_mac(model, a, b):
    """Mass-weighted modal assurance criterion between shapes of ``model`` (seed eq. 19 with M):

        MAC(a, b) = (a^T M b)^2 / ((a^T M a) (b^T M b)),   in [0, 1].

    model : an nnm Model (its mass matrix ``model.M`` is used) or a mass matrix (n, n), dense or
        scipy.sparse (e.g. a full FE mass matrix, to compare recovered physical displacements).
    a, b : two shapes (n,) -> a float; or sets of shapes (n, na), (n, nb) (columns) -> the MAC matrix
        (na, nb); a 1-D and a 2-D argument -> (1, nb) or (na, 1).
    Distinct linear modes of the model give 0, a shape and any multiple of it give 1.
    """
    M = getattr(model, "M", model)
    if M is None or not (sp.issparse(M) or np.ndim(M) == 2):
        raise NNMInputError("mass_mac needs a Model or a mass matrix (n, n) as its first argument")
    n = M.shape[0]
    for name, v in (("a", a), ("b", b)):
        if np.shape(v)[:1] != (n,):
            raise NNMInputError(f"mass_mac: {name} has shape {np.shape(v)}, expected ({n},) or ({n}, k) rows "
                                f"matching the mass matrix")
    return mac(a, b, M)
