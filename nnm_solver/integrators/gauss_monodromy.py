r"""The exact monodromy of the discrete Gauss-Legendre map (gauss.py), assembled in low-rank form.

Per mode the linearised step is z_{k+1} = A z_k + E p_k, with the stage perturbations dQ_k = C z_k + F p_k and
p_k = -Bq^T w_k, w_k = Dg_k dd_k the stage force perturbations (s n_s).  Only the s n_s stage deformations are
propagated, by a discrete Volterra recursion (``_volterra``); the final state is the block-diagonal linear map
A^N plus one matrix product, as for Newmark (newmark_monodromy.py).  ``GaussConstants`` (gauss.py) carries A,
C, E, F, G of a step size.
"""
from __future__ import annotations

import numpy as np

from ..jit import jit as _jit, lapack_solve_many

__all__ = ["monodromy"]


@_jit
def _volterra(Hom, H, G, Dseq, ncols):
    """The stage force perturbations W (N, m, ncols), m = s n_s, of the monodromy's columns:
    (I + G Dg_k) dd_k = Hom_k - sum_{j<k} H(k-1-j) w_j,  w_k = Dg_k dd_k (see _monodromy)."""
    N = Hom.shape[0]
    m = Hom.shape[1]
    n = Hom.shape[3]
    W = np.zeros((N, m, ncols))
    eye = np.eye(m)
    for k in range(N):
        acc = np.empty((m, ncols))
        acc[:, :n] = Hom[k, :, 0, :]
        if ncols > n:
            acc[:, n:] = Hom[k, :, 1, :]
        for j in range(k):
            acc -= H[k - 1 - j] @ W[j]
        Jk = eye + G * Dseq[k][None, :]
        dd = lapack_solve_many(Jk, acc)
        W[k] = dd * Dseq[k][:, None]
    return W


def monodromy(k, Bq, nsteps, Dseq, ncols, velocities=True):
    """Exact derivative of the discrete flow map d[q_N; v_N]/d[q0 (; v0)]: (Sq, Sv) (n, ncols) each (Sv None
    unless velocities).

    Per mode the linearised step is z_{k+1} = A z_k + E p_k, dQ_k = C z_k + F p_k, p_k = -Bq^T w_k with
    w_k = Dg_k dd_k the stage force perturbations (s n_s).  Only dd_k is propagated:
    (I + G Dg_k) dd_k = Bq C A^k dz0 - sum_{j<k} H(k-1-j) w_j,  H(r) = sum_m (C A^r E)_m (x) b_m b_m^T,
    and dz_N = A^N dz0 - sum_j A^(N-1-j) E Bq^T w_j.
    """
    n = Bq.shape[1]
    ns = Bq.shape[0]
    s = k.s
    N = nsteps
    m = s * ns
    # per-mode powers A^r, r = 0..N
    P = np.empty((N + 1, n, 2, 2))
    P[0] = np.eye(2)[None]
    a = k.A_lin
    for r in range(N):
        P[r + 1, :, :, 0] = a[:, :, 0] * P[r, :, 0, 0][:, None] + a[:, :, 1] * P[r, :, 1, 0][:, None]
        P[r + 1, :, :, 1] = a[:, :, 0] * P[r, :, 0, 1][:, None] + a[:, :, 1] * P[r, :, 1, 1][:, None]
    diag_q = P[N, :, 0, :]   # (n, 2): dq_N / (dq0_m, dv0_m)
    diag_v = P[N, :, 1, :]
    cols = np.arange(n)
    Sq, Sv = np.zeros((n, ncols)), (np.zeros((n, ncols)) if velocities else None)
    for S, diag in ((Sq, diag_q), (Sv, diag_v)):
        if S is not None:
            S[cols, cols] = diag[:, 0]
            if ncols > n:
                S[cols, n + cols] = diag[:, 1]
    if ns == 0:
        return Sq, Sv
    CA = k.C[None] @ P[:N]                                # (N, n, s, 2): C A^r
    R = max(N - 1, 0)
    CAE = CA[:R] @ k.E[None]                              # (N-1, n, s, s): C A^r E
    BB = k.BB                                             # (ns^2, n)
    H = (np.ascontiguousarray(CAE.transpose(0, 2, 3, 1)).reshape(R * s * s, n) @ BB.T)   # (r, l, j, x, y)
    H = H.reshape(R, s, s, ns, ns).transpose(0, 1, 3, 2, 4).reshape(R, m, m)
    Hom = np.ascontiguousarray((CA.transpose(0, 2, 3, 1)[:, :, None, :, :] * Bq[None, None, :, None, :])
                               .reshape(N, m, 2, n))                  # Bq C A^k per mode, rows (l, r)
    W = _volterra(Hom, np.ascontiguousarray(H), k.G, Dseq, ncols).reshape(N * m, ncols)
    # final state: - sum_j A^(N-1-j) E Bq^T w_j
    AE = P[:N][::-1] @ k.E[None]                          # AE[j] = A^(N-1-j) E, (N, n, 2, s)
    Uq = (AE[:, :, 0, :].transpose(1, 0, 2)[:, :, :, None] * Bq.T[:, None, None, :]).reshape(n, N * m)
    Sq -= Uq @ W
    if velocities:
        Sv -= (AE[:, :, 1, :].transpose(1, 0, 2)[:, :, :, None] * Bq.T[:, None, None, :]).reshape(n, N * m) @ W
    return Sq, Sv
