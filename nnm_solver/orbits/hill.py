r"""Floquet multipliers of a harmonic-balance orbit by Hill's method (harmonic_balance.py).

A perturbation y of the orbit q(t) obeys  y'' + K(t) y = 0,  K(t) = Omega^2 + Bq^T diag(g'(d(t))) Bq
(modal coordinates, d = Bq q the spring deformations).  Floquet form y = e^{lambda t} p(t), p
T-periodic, expanded in the full basis (1, cos h theta, sin h theta, h = 1..H; theta = omega t):

    (D^2 + K_h) a + 2 lambda D a + lambda^2 a = 0,

D = omega (d/dtheta on the coefficients), K_h the Galerkin matrix of K(t) (AFT, as for the HB
Jacobian).  Linearised: lambda [a; b] = [[0, I], [-(D^2 + K_h), -2 D]] [a; b], size 2 n (2H + 1).
Each Floquet exponent appears with copies lambda + i k omega (same multiplier e^{lambda T}); of
the 2 n (2H + 1) eigenvalues the 2 n whose eigenvectors, written in exp(i k theta), k = -H..H, have
the smallest |mean k| are kept (the wave-number ordering of Lazarus & Thomas, 2010): the truncation
spoils the copies centred on high harmonics.  Multipliers mu = exp(lambda T); cost O((2 n (2H + 1))^3) per point.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .hb_basis import HBBasis


def derivative_matrix(basis):
    """Dm (N_b, N_b): coefficients of dp/dtheta from those of p, for a 'full' basis."""
    nb = len(basis)
    Dm = np.zeros((nb, nb))
    for j in range(nb):
        if basis.h[j] == 0:
            continue
        if basis.sine[j]:   # (sin h t)' = h cos h t: the cos of order h sits just before
            Dm[j - 1, j] = basis.h[j]
        else:               # (cos h t)' = -h sin h t: the sin of order h sits just after
            Dm[j + 1, j] = -basis.h[j]
    return Dm


def hill_multipliers(problem, u, harmonics=None):
    """Floquet multipliers (2n,) of the HB orbit u of ``problem`` (an HBProblem), largest modulus first."""
    A, w = problem.unpack(u)
    s, n = problem.sys, problem.n
    H = int(harmonics or problem.basis.harmonics)
    bp = HBBasis(H, "full", max(4 * H + 4, 2 * problem.basis.harmonics + 2 * H + 2))
    theta = 2 * np.pi * np.arange(bp.samples) / bp.samples
    d = problem.basis.functions(theta) @ (A @ s.Bq.T)
    nb = len(bp)
    C = np.einsum("jk,ks,kl->sjl", bp.P, s.tangent(d), bp.E)
    Kh = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
    Kh[np.diag_indices(nb * n)] += np.tile(s.omega2, nb)
    D = np.kron(derivative_matrix(bp), np.eye(n)) * w
    m = nb * n
    L = np.zeros((2 * m, 2 * m))
    L[:m, m:] = np.eye(m)
    L[m:, :m] = -(D @ D + Kh)
    L[m:, m:] = -2.0 * D
    lam, V = sla.eig(L, check_finite=False)
    a = V[:m].reshape(nb, n, -1)
    ac, as_ = a[1::2], a[2::2]                                    # cos / sin coefficients, h = 1..H
    w_pos = (np.abs(ac - 1j * as_) ** 2).sum(axis=1)               # |c_{+h}|^2 of exp(+i h theta) (x4)
    w_neg = (np.abs(ac + 1j * as_) ** 2).sum(axis=1)               # |c_{-h}|^2
    total = 4 * (np.abs(a[0]) ** 2).sum(axis=0) + (w_pos + w_neg).sum(axis=0)
    centroid = (bp.h[1::2] @ (w_pos - w_neg)) / np.maximum(total, 1e-300)
    keep = np.argsort(np.abs(centroid), kind="stable")[:2 * n]
    mu = np.exp(lam[keep] * 2 * np.pi / w)
    return mu[np.argsort(-np.abs(mu), kind="stable")]
