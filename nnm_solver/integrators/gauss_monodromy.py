r"""The exact monodromy of the discrete Gauss-Legendre map (gauss.py), assembled in low-rank form.

Per mode the linearised step is z_{k+1} = A z_k + E p_k, with the stage perturbations dQ_k = C z_k + F p_k and
p_k = -Bq^T w_k, w_k = Dg_k dd_k the stage force perturbations (s n_s).  Only the s n_s stage deformations are
propagated, by a discrete Volterra recursion (``_volterra``); the final state is the block-diagonal linear map
A^N plus one matrix product, as for Newmark (newmark_monodromy.py).  ``GaussConstants`` (gauss.py) carries A,
C, E, F, G of a step size.

Cost (issue 52).  The parts that depend on the step h, N and the system only (the per-mode powers A^r, Bq C A^k,
the kernel H(r) = sum_m (C A^r E)_m (x) b_m b_m^T, the final map's factor A^(N-1-j) E Bq^T) are built by one
compiled loop (``_linear_parts``, O(N n s (s + n_s))) instead of numpy's batched 2 x 2 products; the Volterra
recursion is one unit lower triangular solve (``_volterra``: BLAS-3); what remains is that solve and the final
(n x N m) @ (N m x ncols) product.  On the aircraft (n = 548, 4 springs, gauss6; CPU time of one call,
benchmarks/README.md) a quarter period (N = 25) 21 -> 8 ms and a half period (N = 50) 39 -> 32 ms at load 4 (at load 9:
21 -> 17 and 41 -> 33 ms), the same numbers to round-off (tests/
test_gauss_monodromy.py: within 1e-13 of the assembly it replaced, and finite differences).  The orbit-independent
parts are not kept between calls: a run repeats a step h and N for 2 % of its sweeps (each Newton iterate has its
own period).
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import blas

from ..jit import jit as _jit, small_inverse
from .settings import KERNELS

__all__ = ["monodromy", "monodromy_factors", "velocity_factors", "directional", "subtract_product"]


@_jit
def _linear_parts(A_lin, C, E, Bq, N, velocities):
    """The orbit-independent parts of the monodromy of N steps: (PN (n, 2, 2) = A^N per mode, Hom (N, m, n) the
    stage deformations' response to dq0 = Bq C A^k e_1 and, when velocities, HomV (N, m, n) to dv0 (Bq C A^k e_2; else
    an empty array), CAE (N - 1, s, s, n) = C A^r E, Uq (n, N m) with Uq[:, j m + (l, r)] = (A^(N-1-j) E)[0, l]
    Bq[r] (the final dq's factor) and Uv the same for dv (empty unless velocities)).  m = s n_s, rows (l, r)."""
    n = A_lin.shape[0]
    s = C.shape[1]
    ns = Bq.shape[0]
    m = s * ns
    R = max(N - 1, 0)
    P = np.empty((N + 1, n, 2, 2))
    for i in range(n):
        P[0, i, 0, 0] = 1.0
        P[0, i, 0, 1] = 0.0
        P[0, i, 1, 0] = 0.0
        P[0, i, 1, 1] = 1.0
    for r in range(N):
        for i in range(n):
            for t in range(2):
                for c in range(2):
                    P[r + 1, i, t, c] = A_lin[i, t, 0] * P[r, i, 0, c] + A_lin[i, t, 1] * P[r, i, 1, c]
    nv = n if velocities else 0
    CA = np.empty((N, s, 2, n))             # C A^k per mode (columns: dq0, dv0)
    for k in range(N):
        for l in range(s):
            for i in range(n):
                CA[k, l, 0, i] = C[i, l, 0] * P[k, i, 0, 0] + C[i, l, 1] * P[k, i, 1, 0]
                CA[k, l, 1, i] = C[i, l, 0] * P[k, i, 0, 1] + C[i, l, 1] * P[k, i, 1, 1]
    Hom = np.empty((N, m, n))
    HomV = np.empty((N if velocities else 0, m, nv))
    CAE = np.empty((R, s, s, n))
    for k in range(N):
        for l in range(s):
            for r in range(ns):
                for i in range(n):
                    Hom[k, l * ns + r, i] = CA[k, l, 0, i] * Bq[r, i]
                if velocities:
                    for i in range(n):
                        HomV[k, l * ns + r, i] = CA[k, l, 1, i] * Bq[r, i]
            if k < R:
                for j in range(s):
                    for i in range(n):
                        CAE[k, l, j, i] = CA[k, l, 0, i] * E[i, 0, j] + CA[k, l, 1, i] * E[i, 1, j]
    Uq = np.empty((n, N * m))
    Uv = np.empty((nv, N * m))
    for i in range(n):
        for k in range(N):          # the final state's factor A^(N-1-k) E Bq^T (column block k)
            Pk = N - 1 - k
            for l in range(s):
                ae0 = P[Pk, i, 0, 0] * E[i, 0, l] + P[Pk, i, 0, 1] * E[i, 1, l]
                for r in range(ns):
                    Uq[i, k * m + l * ns + r] = ae0 * Bq[r, i]
                if velocities:
                    ae1 = P[Pk, i, 1, 0] * E[i, 0, l] + P[Pk, i, 1, 1] * E[i, 1, l]
                    for r in range(ns):
                        Uv[i, k * m + l * ns + r] = ae1 * Bq[r, i]
    return P[N].copy(), Hom, HomV, CAE, Uq, Uv


def _kernel(CAE, BB, s, ns):
    """H (R, m, m): H(r)[(l, x), (j, y)] = sum_m (C A^r E)_m[l, j] Bq[x, m] Bq[y, m]."""
    R = CAE.shape[0]
    m = s * ns
    if R == 0:
        return np.zeros((0, m, m))
    return (CAE.reshape(R * s * s, -1) @ BB.T).reshape(R, s, s, ns, ns).transpose(0, 1, 3, 2, 4).reshape(R, m, m)


@_jit
def _volterra_system(Hom, HomV, H, G, Dseq, ncols):
    """The Volterra recursion's unit lower triangular system L dd = B (see _volterra), assembled in one pass:
    B (N m, ncols) = J_k^-1 [Hom_k, HomV_k] block row by block row, L (N m, N m) with the blocks
    J_k^-1 H(k-1-j) Dg_j below the diagonal (J_k = I + G Dg_k, m x m: jit.small_inverse)."""
    N, m, n = Hom.shape
    B = np.empty((N * m, ncols))
    L = np.zeros((N * m, N * m))
    J = np.empty((m, m))
    for k in range(N):
        for a in range(m):
            for b in range(m):
                J[a, b] = G[a, b] * Dseq[k, b] + (1.0 if a == b else 0.0)
        Ji = small_inverse(J)
        for a in range(m):
            row = k * m + a
            for i in range(ncols):
                B[row, i] = 0.0
            for b in range(m):
                f = Ji[a, b]
                for i in range(n):
                    B[row, i] += f * Hom[k, b, i]
                if ncols > n:
                    for i in range(n):
                        B[row, n + i] += f * HomV[k, b, i]
            L[row, row] = 1.0
            for j in range(k):
                Hk = H[k - 1 - j]
                for c in range(m):
                    acc = 0.0
                    for b in range(m):
                        acc += Ji[a, b] * Hk[b, c]
                    L[row, j * m + c] = acc * Dseq[j, c]
    return B, L


def _volterra(Hom, HomV, H, G, Dseq, ncols):
    """The stage force perturbations W (N m, ncols), m = s n_s, of the monodromy's columns:
    (I + G Dg_k) dd_k = Hom_k - sum_{j<k} H(k-1-j) w_j,  w_k = Dg_k dd_k (see monodromy); columns n.. (ncols = 2n)
    from HomV.

    Each block row multiplied by J_k^-1 = (I + G Dg_k)^-1, the system in dd is unit lower triangular:
    dd_k + sum_{j<k} J_k^-1 H(k-1-j) Dg_j dd_j = J_k^-1 Hom_k; assembled by one compiled pass (_volterra_system) and
    solved in place by BLAS dtrsm (BLAS-3; O((N m)^2 ncols) in all, memory O((N m)^2 + N m ncols); longer sweeps
    than KERNELS.volterra_block steps by blocks, _volterra_blocked).  The same
    numbers as the block-by-block numpy assembly it replaced to round-off (tests/test_gauss_monodromy.py)."""
    if Hom.shape[0] > max(1, KERNELS.volterra_block):
        return _volterra_blocked(Hom, HomV, H, G, Dseq, ncols)
    B, L = _volterra_system(Hom, HomV, H, G, Dseq, ncols)
    # L dd = B as dd^T L^T = B^T: Fortran-ordered views of the C-ordered arrays, solved in place (unit lower triangular)
    dd = blas.dtrsm(1.0, L.T, B.T, side=1, lower=0, trans_a=0, diag=1, overwrite_b=1).T
    dd *= Dseq.reshape(-1)[:, None]
    return dd


def _volterra_blocked(Hom, HomV, H, G, Dseq, ncols):
    """_volterra for long sweeps (more than KERNELS.volterra_block steps): the stage force perturbations W (N m,
    ncols), m = s n_s, of the monodromy's columns:
    (I + G Dg_k) dd_k = Hom_k - sum_{j<k} H(k-1-j) w_j,  w_k = Dg_k dd_k (see monodromy); columns n.. (ncols = 2n)
    from HomV.

    Each block row multiplied by J_k^-1 = (I + G Dg_k)^-1 (m x m inverses, one batched product), the system in dd is unit lower
    triangular: dd_k + sum_{j<k} J_k^-1 H(k-1-j) Dg_j dd_j = J_k^-1 Hom_k, solved KERNELS.volterra_block steps at
    a time as newmark_monodromy.py's: the earlier blocks by one matrix product, the block by a triangular solve
    (BLAS-3; O((N m)^2 ncols) in all, memory O(block m N m))."""
    N, m, n = Hom.shape
    R = N - 1
    Dflat = Dseq.reshape(-1)
    J = np.eye(m)[None] + G[None] * Dseq[:, None, :]                       # (N, m, m)
    Hext = np.concatenate([H, np.zeros((1, m, m))])                        # Hext[R] = 0: the upper blocks
    dd = np.empty((N * m, ncols))
    block = max(1, KERNELS.volterra_block)
    for k0 in range(0, N, block):
        k1 = min(k0 + block, N)
        kk = np.arange(k0, k1)[:, None]
        jj = np.arange(k1)[None, :]
        idx = np.where(jj < kk, kk - 1 - jj, R)                            # (b, k1): H(k-1-j), 0 for j >= k
        rows = Hext[idx].transpose(0, 2, 1, 3).reshape(k1 - k0, m, k1 * m) * Dflat[None, None, :k1 * m]
        rhs = np.concatenate([Hom[k0:k1]] + ([HomV[k0:k1]] if ncols > n else []) + [rows], axis=2)
        X = np.linalg.inv(J[k0:k1]) @ rhs                                   # J_k^-1 [Hom_k, H(k-1-j) Dg_j]
        b = X[:, :, :ncols].reshape((k1 - k0) * m, ncols)
        Lk = X[:, :, ncols:].reshape((k1 - k0) * m, k1 * m)
        if k0:
            b -= Lk[:, :k0 * m] @ dd[:k0 * m]
        # L dd = b as dd^T L^T = b^T: Fortran-ordered views, solved in place by BLAS (unit lower triangular)
        L = np.ascontiguousarray(Lk[:, k0 * m:])
        dd[k0 * m:k1 * m] = blas.dtrsm(1.0, L.T, np.ascontiguousarray(b).T, side=1, lower=0, trans_a=0, diag=1,
                                       overwrite_b=1).T
    return dd * Dflat[:, None]


def monodromy_factors(k, Bq, nsteps, Dseq):
    """dq_N / dq0 as (d (n,), U (n, r), Vt (r, n)) with dq_N / dq0 = diag(d) + U @ Vt, r = nsteps s n_s: the diagonal
    is the linear modes' map (A^N)[0, 0], the low-rank term the stages' (lowrank.DiagonalPlusLowRank); the same map as
    monodromy's Sq with ncols = n, without its n x r by r x n product."""
    n = Bq.shape[1]
    N = int(nsteps)
    PN, Hom, HomV, CAE, Uq, _ = _linear_parts(k.A_lin, k.C, k.E, np.ascontiguousarray(Bq, dtype=float), N, False)
    if Bq.shape[0] == 0 or N == 0:
        return PN[:, 0, 0].copy(), np.zeros((n, 0)), np.zeros((0, n))
    W = _volterra(Hom, HomV, _kernel(CAE, k.BB, k.s, Bq.shape[0]), k.G, Dseq, n)
    return PN[:, 0, 0].copy(), -Uq, W


def velocity_factors(k, Bq, nsteps, Dseq):
    """dv_N / dv0 as (d (n,), U (n, r), W (r, n)) with dv_N / dv0 = diag(d) - U @ W, r = nsteps s n_s: the block
    Sv[:, n:] of monodromy's with ncols = 2n, without the dq0 columns' Volterra solve or any n x n product (the
    reversible half-period map, gauss.reversible_half_block, needs only this block beside the quarter map's dq/dq0)."""
    n = Bq.shape[1]
    N = int(nsteps)
    PN, Hom, HomV, CAE, Uq, Uv = _linear_parts(k.A_lin, k.C, k.E, np.ascontiguousarray(Bq, dtype=float), N, True)
    if Bq.shape[0] == 0 or N == 0:
        return PN[:, 1, 1].copy(), np.zeros((n, 0)), np.zeros((0, n))
    # the dv0 columns' system is the dq0 columns' with HomV for Hom (the same triangular L)
    W = _volterra(HomV, HomV[:0], _kernel(CAE, k.BB, k.s, Bq.shape[0]), k.G, Dseq, n)
    return PN[:, 1, 1].copy(), Uv, W


def directional(k, Bq, nsteps, Dseq, X):
    """(dq_N/dq0 @ X, dv_N/dq0 @ X) (n, p) each for a few real directions X (n, p) of the initial displacement (v0
    unchanged): monodromy's dq0 columns applied to X, from the Volterra recursion with the right-hand side Hom @ X (p
    columns instead of n; no n x n block is formed).  The Krein signatures of a few eigenvalues of a reversible
    orbit need dv(T/2)/dq0 only along their eigenvectors (ShootingStability.krein_form)."""
    X = np.ascontiguousarray(X, dtype=float)
    N = int(nsteps)
    PN, Hom, HomV, CAE, Uq, Uv = _linear_parts(k.A_lin, k.C, k.E, np.ascontiguousarray(Bq, dtype=float), N, True)
    SqX, SvX = PN[:, 0, 0][:, None] * X, PN[:, 1, 0][:, None] * X
    if Bq.shape[0] == 0 or N == 0 or X.shape[1] == 0:
        return SqX, SvX
    HomX = np.ascontiguousarray(Hom @ X)                         # (N, m, p): the stages' response to dq0 = X
    W = _volterra(HomX, HomX[:, :, :0], _kernel(CAE, k.BB, k.s, Bq.shape[0]), k.G, Dseq, X.shape[1])
    return SqX - Uq @ W, SvX - Uv @ W


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
    N = int(nsteps)
    PN, Hom, HomV, CAE, Uq, Uv = _linear_parts(k.A_lin, k.C, k.E, np.ascontiguousarray(Bq, dtype=float), N,
                                               bool(ncols > n or velocities))
    cols = np.arange(n)
    Sq, Sv = np.zeros((n, ncols)), (np.zeros((n, ncols)) if velocities else None)
    for S, row in ((Sq, 0), (Sv, 1)):
        if S is not None:
            S[cols, cols] = PN[:, row, 0]
            if ncols > n:
                S[cols, n + cols] = PN[:, row, 1]
    if ns == 0 or N == 0:
        return Sq, Sv
    W = _volterra(Hom, HomV, _kernel(CAE, k.BB, s, ns), k.G, Dseq, ncols)
    subtract_product(Sq, Uq, W)                           # - sum_j A^(N-1-j) E Bq^T w_j
    if velocities:
        subtract_product(Sv, Uv, W)
    return Sq, Sv


def subtract_product(S, U, W, alpha=1.0):
    """S -= alpha U @ W in place (C-ordered S (n, p), U (n, r), W (r, p)): BLAS dgemm on the transposed views, no
    temporary of S's size."""
    if U.shape[1] == 0 or S.size == 0:
        return
    out = blas.dgemm(-float(alpha), np.ascontiguousarray(W).T, np.ascontiguousarray(U).T, beta=1.0, c=S.T,
                     overwrite_c=1)
    if not np.shares_memory(out, S):      # (BLAS worked on a copy: write it back)
        S[...] = out.T
