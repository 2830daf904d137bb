r"""The linear part of the condensed harmonic-balance equations (condensed_hb.py): the structure as seen from its
nonlinear elements (``LinearPart``: the modes' w_k^2 and element deformations b_k, and the residual flexibility of a
truncated basis), and the Galerkin blocks of coupled elements (model/coupled.py) with their product by the
flexibility."""
from __future__ import annotations

import numpy as np

__all__ = ["LinearPart", "coupled_galerkin", "flexibility_times_tangent"]


class LinearPart:
    """The linear structure as seen from its nonlinear elements.

    omega2 (m,) rad^2/s^2, Bq (n_s, m) element deformations of the modes (b_k = Bq[:, k]), Phi (n, m)
    mode shapes (None: no physical reconstruction here), R0 / R1 (n_s, n_s) the residual flexibility of
    the modes left out (m/N and m s^2/N; None: the basis is complete), Psi0 / Psi1 (n, n_s) the same as
    displacement fields (x of a unit element force), for the reconstruction.
    """

    def __init__(self, omega2, Bq, Phi=None, R0=None, R1=None, Psi0=None, Psi1=None):
        self.omega2 = np.asarray(omega2, dtype=float)
        self.Bq = np.asarray(Bq, dtype=float)
        self.Phi = Phi
        ns = self.Bq.shape[0]
        self.R0 = np.zeros((ns, ns)) if R0 is None else np.asarray(R0, dtype=float)
        self.R1 = np.zeros((ns, ns)) if R1 is None else np.asarray(R1, dtype=float)
        self.Psi0, self.Psi1 = Psi0, Psi1
        self.complete = R0 is None

    @property
    def m(self):
        return len(self.omega2)

    def weights(self, Omega2, r, fundamental):
        """W[j, k] = 1 / (w_k^2 - Omega2_j) (N_b, m), zero for the followed mode r at the fundamental."""
        den = self.omega2[None, :] - Omega2[:, None]
        den[fundamental, r] = 1.0
        if den.all():
            W = 1.0 / den
        else:                                      # an exact internal resonance: inf, as the equations' pole
            with np.errstate(divide="ignore"):
                W = 1.0 / den
        W[fundamental, r] = 0.0
        return W

    def _weighted(self, V):
        """Bq diag(V[j]) Bq^T (N_b, n_s, n_s) for the rows of V (N_b, m)."""
        return (self.Bq[None] * V[:, None, :]) @ self.Bq.T               # batched: no einsum path search per call

    def flexibility(self, W, Omega2):
        """G_j = Bq diag(W[j]) Bq^T + R0 + Omega2_j R1: (N_b, n_s, n_s) m/N."""
        G = self._weighted(W)
        return G if self.complete else G + self.R0[None] + Omega2[:, None, None] * self.R1[None]

    def flexibility_slope(self, W, Omega2):
        """dG_j / d(Omega2_j) = Bq diag(W[j]^2) Bq^T + R1."""
        G = self._weighted(W * W)
        return G if self.complete else G + self.R1[None]


def coupled_galerkin(basis, elements, d):
    """The non-zero Galerkin blocks of the whole element tangent at the sampled deformations d (N, n_d), as a list of
    (u, t, C): index arrays u, t (k,) and C (k, N_b, N_b), C[i, j, l] = d F[j, u_i] / d D[l, t_i]; the springs' on
    the diagonal, the coupled elements' (model/coupled.py) in their m x m blocks, one entry per block position (a, b)
    (t unique within an entry).  The condensed equations of a model with coupled elements use them."""
    nd = d.shape[1]
    idx = np.arange(nd)
    out = [(idx, idx, basis.galerkin(elements.tangent(d)))]
    for rows, T in elements.coupled_tangents(d):
        for a in range(rows.shape[1]):
            for b in range(rows.shape[1]):
                out.append((rows[:, a], rows[:, b], basis.galerkin(T[:, :, a, b])))
    return out


def flexibility_times_tangent(G, blocks, nb, nd):
    """JD (N_b, n_d, N_b, n_d): JD[j, s, l, t] = sum_u G[j, s, u] dF[j, u] / dD[l, t] (G (N_b, n_d, n_d), blocks of
    ``coupled_galerkin``); O(N_b^2 n_d (n_d + sum m^2)), the tangent's sparsity kept."""
    JD = np.zeros((nb, nd, nb, nd))
    for u, t, C in blocks:
        JD[:, :, :, t] += np.einsum("jsk,kjl->jslk", G[:, :, u], C)
    return JD
