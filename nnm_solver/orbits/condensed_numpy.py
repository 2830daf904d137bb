r"""The numpy forms of the condensed harmonic-balance equations (condensed_hb.py): the residual's parts and its
Jacobian assembled from them, for coupled elements (model/coupled.py) and an installation without numba; models of
springs take the compiled kernels (condensed_kernels.py: the same equations to round-off,
tests/test_per_point_kernels.py).
The units are condensed_hb.py's: D (N_b, n_s) m, a sqrt(kg) m, omega rad/s, residuals in m."""
from __future__ import annotations

import numpy as np

from .condensed_linear import coupled_galerkin, flexibility_times_tangent

__all__ = ["forces", "residual_parts", "jacobian_of"]


def forces(prob, D):
    """(d (N, n_s) deformations at the samples (m), F (N_b, n_s) element force coefficients (N)) of the
    CondensedHBProblem prob at the deformation coefficients D."""
    d = prob.basis.E @ D
    return d, prob.basis.P @ prob.sys.force(d)


def residual_parts(prob, u):
    """(D, a, w, Omega2, W, G, d, F, r): the residual r at u with its intermediate results (``jacobian_of``'s input)."""
    D, a, w = prob.unpack(u)
    Omega2 = prob.h2 * w * w
    W = prob.lin.weights(Omega2, prob.r, prob.fund)
    G = prob.lin.flexibility(W, Omega2)
    d, F = forces(prob, D)
    RD = D + np.einsum("jst,jt->js", G, F)
    RD[prob.cos1] -= a * prob.b_r
    alpha = np.zeros(len(prob.fund))
    alpha[prob.fund == prob.cos1] = a
    Ra = (prob.w_r ** 2 - w * w) * alpha + F[prob.fund] @ prob.b_r
    r = np.concatenate([RD.ravel(), Ra * prob.beta / prob.w_r ** 2])
    return D, a, w, Omega2, W, G, d, F, r


def jacobian_of(prob, parts):
    """(r, J) of the CondensedHBProblem prob from ``residual_parts`` at u."""
    D, a, w, Omega2, W, G, d, F, r = parts
    bs, nb, ns = prob.basis, prob.nb, prob.ns
    nD = nb * ns
    J = np.zeros((len(r), nD + 2))                                       # unknowns: D, a, omega
    if prob.sys.elements.coupled:
        blocks = coupled_galerkin(bs, prob.sys.elements, d)
        JD = flexibility_times_tangent(G, blocks, nb, ns).reshape(nD, nD)
    else:
        C = bs.galerkin(prob.sys.tangent(d))       # dF[j, s] / dD[l, s]
        # dR_D[j, s] / dD[l, t] = delta + G[j, s, t] C[t, j, l]
        JD = np.einsum("jst,tjl->jslt", G, C).reshape(nD, nD)
    JD[np.diag_indices(nD)] += 1.0
    J[:nD, :nD] = JD
    J[prob.cos1 * ns:(prob.cos1 + 1) * ns, nD] = -prob.b_r / prob.beta
    dG = prob.lin.flexibility_slope(W, Omega2)                             # dG / dOmega2
    J[:nD, nD + 1] = (np.einsum("jst,jt->js", dG, F) * (2 * prob.h2 * w)[:, None]).ravel() * prob.w_r
    c = prob.beta / prob.w_r ** 2
    for i, j in enumerate(prob.fund):
        row = nD + i
        if prob.sys.elements.coupled:
            R = np.zeros((nb, ns))                                      # [l, t] = sum_u b_r[u] dF[j, u] / dD[l, t]
            for u_, t_, C_ in blocks:
                R[:, t_] += (prob.b_r[u_][:, None] * C_[:, j, :]).T
            J[row, :nD] = c * R.ravel()
        else:
            J[row, :nD] = c * (prob.b_r[:, None] * C[:, j, :]).T.ravel()
        if j == prob.cos1:
            J[row, nD] = (prob.w_r ** 2 - w * w) / prob.w_r ** 2
            J[row, nD + 1] = -2.0 * w * a * c * prob.w_r
    return r, J
