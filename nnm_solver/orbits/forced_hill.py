r"""Stability of forced, damped periodic responses (``forced_hb.py``, ``forced_hb_condensed.py``).

**Stability** (``damped_hill_multipliers``): Hill's method as in ``hill.py`` with the damping terms,
(D^2 + C D + K_h) a + lambda (2 D + C) a + lambda^2 a = 0, D = omega D_theta (x) I, C = I (x) C_q;
the 2n exponents of smallest wave-number centroid kept, mu = exp(lambda T).  A forced orbit has no
trivial pair (no free time shift).  Cheaper, and for any model size: the **fold test**
(``fold_sign`` of both problems, forced_hb.py), the sign of det dR/d(unknowns) at fixed omega.  dR/dA at fixed omega is Hill's matrix
L(lambda) at lambda = 0, whose determinant is positive for lambda -> +inf; it is negative exactly when an
odd number of real multipliers exceeds 1, which happens through the folds of the curve (saddle-node),
the usual loss of stability of forced responses.  The condensed Jacobian has the same sign (det dR/dA =
det(dynamic stiffness) det(I + G C), the first positive with damping).  It does not see instabilities
through a complex pair (Neimark-Sacker) or -1 (period doubling).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .hb_basis import HBBasis
from .hill import central_exponents, derivative_matrix

__all__ = ["damped_hill_multipliers"]


def damped_hill_multipliers(system, basis, A, omega, damping_q, harmonics=None):
    """Floquet multipliers (2n,) of the forced orbit with modal coefficients A (N_b, n) on ``basis`` at
    omega (rad/s), damping_q (n,) modal damping coefficients or (n, n) modal damping matrix: Hill's
    method with damping (module docstring), largest modulus first.  O((2 n (2H + 1))^3)."""
    s, n = system, system.n
    H = int(harmonics or basis.harmonics)
    bp = HBBasis(H, "full", max(4 * H + 4, 2 * basis.harmonics + 2 * H + 2))
    theta = 2 * np.pi * np.arange(bp.samples) / bp.samples
    d = basis.functions(theta) @ (A @ s.Bq.T)
    nb = len(bp)
    Cmat = np.diag(damping_q) if np.ndim(damping_q) == 1 else np.asarray(damping_q)
    C = bp.galerkin(s.tangent(d))
    Kh = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
    if s.elements.coupled:                                     # coupled elements: full tangent blocks (model/coupled.py)
        Kh += bp.galerkin_matrix(s.coupled_stiffness(d))
    Kh[np.diag_indices(nb * n)] += np.tile(s.omega2, nb)
    D = np.kron(derivative_matrix(bp), np.eye(n)) * omega
    Ch = np.kron(np.eye(nb), Cmat)
    m = nb * n
    L = np.zeros((2 * m, 2 * m))
    L[:m, m:] = np.eye(m)
    L[m:, :m] = -(D @ D + Ch @ D + Kh)
    L[m:, m:] = -(2.0 * D + Ch)
    lam, V = sla.eig(L, check_finite=False)
    mu = np.exp(lam[central_exponents(V[:m], bp, n)] * 2 * np.pi / omega)
    return mu[np.argsort(-np.abs(mu), kind="stable")]
