r"""Square maps that are a diagonal plus a low-rank term, A = diag(d) + U Vt (n x n, rank r << n).

The half-period map of the Newmark sweep has this form (newmark_monodromy.py): the linear modes give the
diagonal, the n_s element deformations over the N steps give the rank r = N n_s term.  For models of many modes
with few elements (r well below n) a shifted solve (A - sigma I) x = b then needs no n x n factorisation: by the
Woodbury identity

    (E + U Vt)^-1 = E^-1 - E^-1 U (I_r + Vt E^-1 U)^-1 Vt E^-1,   E = diag(d - sigma),

it costs an r x r LU once (O(n r^2)) and O(n r) per solve, instead of an n x n LU (O(n^3)).  The shift-invert
Arnoldi of the Krein-collision follower (ShootingStability.local_collision) uses it; its Ritz pairs are checked
against A itself (residuals) before they are trusted.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.sparse.linalg import LinearOperator

from .settings import KERNELS

__all__ = ["DiagonalPlusLowRank"]



class DiagonalPlusLowRank:
    """A = diag(d) + U @ Vt: d (n,), U (n, r), Vt (r, n)."""

    def __init__(self, d, U, Vt):
        self.d, self.U, self.Vt = np.asarray(d), np.asarray(U), np.asarray(Vt)
        n, r = self.U.shape
        if self.d.shape != (n,) or self.Vt.shape != (r, n):
            raise ValueError(f"diagonal plus low rank: d {self.d.shape}, U {self.U.shape}, Vt {self.Vt.shape} "
                             "do not fit one n x n map")

    @property
    def n(self):
        return self.d.shape[0]

    @property
    def rank(self):
        return self.U.shape[1]

    def dense(self):
        """The n x n matrix."""
        A = self.U @ self.Vt
        A[np.diag_indices(self.n)] += self.d
        return A

    def matvec(self, x):
        return self.d * x + self.U @ (self.Vt @ x)

    def deflated(self, v):
        """The map on the quotient by span(v) in the basis of floquet.deflate (one Householder reflector
        H = I - tau w w^T of v's QR, C = (H A H)[1:, 1:]): again a diagonal plus a term of rank r + 2, as
        H D H = D - tau w (D w)^T - tau (D w) w^T + tau^2 (w^T D w) w w^T."""
        v = np.asarray(v, dtype=float).reshape(-1, 1)
        (h, tau), _ = sla.qr(v, mode="raw", check_finite=False)
        tau = float(tau[0])
        w = np.concatenate([[1.0], h[1:, 0]])
        Dw = self.d * w
        HU = self.U - tau * np.outer(w, w @ self.U)
        VtH = self.Vt - tau * np.outer(self.Vt @ w, w)
        U = np.column_stack([HU, w, Dw])
        Vt = np.vstack([VtH, tau * tau * (w @ Dw) * w - tau * Dw, -tau * w])
        return DiagonalPlusLowRank(self.d[1:], U[1:], Vt[:, 1:])

    def shift_invert(self, sigma):
        """LinearOperator x -> (A - sigma I)^-1 x by the Woodbury identity (module docstring), or None when a
        diagonal entry is within KERNELS.near_diagonal of sigma (the identity would cancel; the caller takes another route)."""
        dtype = np.result_type(self.U.dtype, type(sigma))
        E = (self.d - sigma).astype(dtype)
        if np.min(np.abs(E)) <= KERNELS.near_diagonal * max(1.0, float(np.max(np.abs(self.d)))):
            return None
        Z = self.U / E[:, None]
        Vt = self.Vt.astype(dtype)               # once: a real Vt would be cast for every complex solve
        lu = sla.lu_factor(np.eye(self.rank, dtype=dtype) + Vt @ Z, check_finite=False)

        def solve(x):
            y = np.asarray(x).reshape(-1) / E
            return y - Z @ sla.lu_solve(lu, Vt @ y, check_finite=False)
        return LinearOperator((self.n, self.n), matvec=solve, dtype=dtype)

    def operator(self, dtype=float):
        """A as a LinearOperator."""
        return LinearOperator((self.n, self.n), matvec=self.matvec, dtype=dtype)
