r"""The exact monodromy of the discrete Newmark map (newmark.py), assembled in low-rank form.

The linearised Newmark step is, per mode i, z_{k+1} = A_i z_k + e_i b_i^T (w_k + w_{k+1}), z = (dq, dv), with
w_k = D_k Bq dq_k the spring-force perturbations (n_s each, D_k = g'(d_k) recorded by the state sweep).  Only
the n_s-dimensional deformations are propagated step by step, by a discrete Volterra recursion through the
impulse responses of the linear modes; the final state is then the block-diagonal linear map A^N plus one
(n x N n_s) @ (N n_s x 2n) product: the exact derivative of the discrete map without pushing 2n columns
through every step.

The Volterra recursion is one block lower-triangular system in the N n_s deformations with ncols right-hand
sides (one per column of the monodromy), solved KERNELS.volterra_block steps at a time: the earlier steps enter a block
by one matrix product and the block by a triangular solve, both BLAS-3 (O((N n_s)^2 ncols) in all, memory
O(N n_s ncols)).  tests/test_newmark_monodromy.py checks it against the step-by-step recursion over all
columns it replaced (about twice as fast at n = 548).
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import blas

from ..jit import jit as _jit, lapack_inv
from .settings import KERNELS


def one_element(Bq):
    """The kernels' marker argument ``many``: None for a model with one nonlinear element, whose kernels are
    compiled with the scalar solves only (numba drops the branches of ``many is None`` when compiling: no
    LAPACK call, issue 32), else 0 (the general kernels, which also handle one element)."""
    return None if Bq.shape[0] == 1 else 0


@_jit
def _linear_map(omega2, h):
    """Per-mode linear Newmark transition z_{k+1} = A z_k + e (b^T s_k), z = (dq, dv).

    Returns the four entries of A (n,) each and the two entries of e (n,) each.  (Loops, not numpy
    expressions: numba compiles them in a fraction of the time, issue 32.)
    """
    n = omega2.shape[0]
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    a11, a12, a21, a22 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    e1, e2 = np.empty(n), np.empty(n)
    for i in range(n):
        w2 = omega2[i]
        S = c1 + w2
        alpha = (c1 - w2) / S
        beta = c2 / S
        gam = 1.0 / S
        a11[i] = alpha
        a12[i] = beta
        a21[i] = -(0.5 * h) * w2 * (1.0 + alpha)
        a22[i] = 1.0 - (0.5 * h) * w2 * beta
        e1[i] = -gam
        e2[i] = 0.5 * h * (w2 * gam - 1.0)
    return a11, a12, a21, a22, e1, e2


@_jit
def _powers(omega2, h, N):
    """Per-mode powers of the linear map A^k, k = 0..N: their first row P11, P12 (N + 1, n), the second row of A^N
    (p21, p22 (n,)), and ge1, ge2 (N, n) with (ge1[m], ge2[m]) = A^m e, m = 0..N-1."""
    n = omega2.shape[0]
    a11, a12, a21, a22, e1, e2 = _linear_map(omega2, h)
    P11 = np.empty((N + 1, n))
    P12 = np.empty((N + 1, n))
    p21 = np.empty(n)
    p22 = np.empty(n)
    ge1 = np.empty((N, n))
    ge2 = np.empty((N, n))
    for i in range(n):
        p11_, p12_, p21_, p22_ = 1.0, 0.0, 0.0, 1.0
        A11, A12, A21, A22, E1, E2 = a11[i], a12[i], a21[i], a22[i], e1[i], e2[i]
        for m in range(N + 1):
            P11[m, i] = p11_
            P12[m, i] = p12_
            if m == N:
                break
            ge1[m, i] = p11_ * E1 + p12_ * E2
            ge2[m, i] = p21_ * E1 + p22_ * E2
            p11_, p12_, p21_, p22_ = (A11 * p11_ + A12 * p21_, A11 * p12_ + A12 * p22_,
                                      A21 * p11_ + A22 * p21_, A21 * p12_ + A22 * p22_)
        p21[i] = p21_
        p22[i] = p22_
    return P11, P12, p21, p22, ge1, ge2


@_jit
def _volterra_terms(Bq, N, Dseq, ncols, P11, P12, ge1, many):
    """The pieces of the Volterra recursion (module docstring) for the deformations' perturbations dd_k, k = 1..N:

        (I - H0 D_k) dd_k - sum_{0<j<k} Kc(k-j) D_j dd_j = F_k,   F_k = free_k + H(k-1) w_0,

    with H(m) = Bq diag(ge1[m]) Bq^T the impulse responses, Kc(m) = H(m) + H(m-1), free_k the response of the
    deformations to the initial state through the linear modes.  Returns (Kc (N, n_s, n_s), M (N + 1, n_s, n_s)
    with M_k = (I - H0 D_k)^-1, F (N n_s, ncols))."""
    n = Bq.shape[1]
    ns = Bq.shape[0]
    H = np.zeros((N, ns, ns))
    for m in range(N):
        for a in range(ns):
            for b in range(a, ns):
                acc = 0.0
                for i in range(n):
                    acc += Bq[a, i] * ge1[m, i] * Bq[b, i]
                H[m, a, b] = acc
                H[m, b, a] = acc
    Kc = np.zeros((N, ns, ns))
    for m in range(1, N):
        for a in range(ns):
            for b in range(ns):
                Kc[m, a, b] = H[m, a, b] + H[m - 1, a, b]
    M = np.zeros((N + 1, ns, ns))
    F = np.empty((N * ns, ncols))
    W0 = np.empty((ns, n))                      # w_0 = D_0 Bq dq0 (the dv0 columns have w_0 = 0)
    for a in range(ns):
        for c in range(n):
            W0[a, c] = Bq[a, c] * Dseq[0, a]
    A = np.empty((ns, ns))
    for k in range(1, N + 1):
        if many is None:                # one element (one_element): no LAPACK call compiled
            M[k, 0, 0] = 1.0 / (1.0 - H[0, 0, 0] * Dseq[k, 0])
        elif ns == 1:
            M[k, 0, 0] = 1.0 / (1.0 - H[0, 0, 0] * Dseq[k, 0])
        else:
            for a in range(ns):
                for b in range(ns):
                    A[a, b] = (1.0 if a == b else 0.0) - H[0, a, b] * Dseq[k, b]
            Minv = lapack_inv(A)
            for a in range(ns):
                for b in range(ns):
                    M[k, a, b] = Minv[a, b]
        r0 = (k - 1) * ns
        for a in range(ns):
            for c in range(n):
                acc = Bq[a, c] * P11[k, c]
                for b in range(ns):
                    acc += H[k - 1, a, b] * W0[b, c]
                F[r0 + a, c] = acc
            if ncols > n:
                for c in range(n):
                    F[r0 + a, n + c] = Bq[a, c] * P12[k, c]
    return Kc, M, F


@_jit
def _history(Kc, k0, k1, j0, j1, ns):
    """T ((k1 - k0) n_s, (j1 - j0) n_s): block (k - k0, j - j0) = Kc(k - j), the kernel of the earlier steps
    j0 <= j < j1 in the right-hand sides of the steps k0 <= k < k1 (all j < k): their terms are T @ [w_j0; ...]."""
    T = np.empty(((k1 - k0) * ns, (j1 - j0) * ns))
    for k in range(k0, k1):
        for j in range(j0, j1):
            K = Kc[k - j]
            for a in range(ns):
                for b in range(ns):
                    T[(k - k0) * ns + a, (j - j0) * ns + b] = K[a, b]
    return T


@_jit
def _block_system(Kc, M, Dseq, k0, k1, ns, rhs):
    """The unit lower-triangular system of the steps k0 <= k < k1: L (m, m) with blocks -M_k Kc(k - j) D_j (j < k in
    the block) and the identity on the diagonal; rhs (m, ncols) is multiplied by M_k block by block, in place."""
    m = (k1 - k0) * ns
    L = np.zeros((m, m))
    tmp = np.empty(ns)
    for k in range(k0, k1):
        r0 = (k - k0) * ns
        for c in range(rhs.shape[1]):                 # rhs_k <- M_k rhs_k
            for a in range(ns):
                acc = 0.0
                for b in range(ns):
                    acc += M[k, a, b] * rhs[r0 + b, c]
                tmp[a] = acc
            for a in range(ns):
                rhs[r0 + a, c] = tmp[a]
        for j in range(k0, k):
            c0 = (j - k0) * ns
            for a in range(ns):
                for b in range(ns):
                    acc = 0.0
                    for t in range(ns):
                        acc += M[k, a, t] * Kc[k - j, t, b]
                    L[r0 + a, c0 + b] = -acc * Dseq[j, b]
        for a in range(ns):
            L[r0 + a, r0 + a] = 1.0
    return L


def _volterra(Bq, N, Dseq, ncols, P11, P12, ge1):
    """w_k = D_k dd_k for k = 0..N, ((N + 1) n_s, ncols): the Volterra system solved block by block,
    KERNELS.volterra_block steps at a time: each earlier block enters by a matrix product, the block itself by a
    triangular solve (BLAS-3)."""
    n = Bq.shape[1]
    ns = Bq.shape[0]
    Kc, M, F = _volterra_terms(Bq, N, Dseq, ncols, P11, P12, ge1, one_element(Bq))
    W = np.zeros(((N + 1) * ns, ncols))
    W[:ns, :n] = Bq * Dseq[0][:, None]
    block = KERNELS.volterra_block
    for k0 in range(1, N + 1, block):
        k1 = min(k0 + block, N + 1)
        rhs = F[(k0 - 1) * ns:(k1 - 1) * ns]
        for j0 in range(1, k0, block):          # the earlier blocks
            j1 = min(j0 + block, k0)
            rhs += _history(Kc, k0, k1, j0, j1, ns) @ W[j0 * ns:j1 * ns]
        L = _block_system(Kc, M, Dseq, k0, k1, ns, rhs)
        # L dd = rhs as dd^T L^T = rhs^T: L.T and rhs.T are Fortran-ordered views, solved in place by BLAS
        dd = blas.dtrsm(1.0, L.T, rhs.T, side=1, lower=0, trans_a=0, diag=1, overwrite_b=1).T
        W[k0 * ns:k1 * ns] = dd * Dseq[k0:k1].reshape(-1)[:, None]
    return W


def _low_rank(Bq, N, Dseq, ncols, P11, P12, ge1):
    """(U1 (n, N n_s), Sst (N n_s, ncols)): the elements' part of dq_N / d[q0 (; v0)] is U1 @ Sst."""
    n = Bq.shape[1]
    ns = Bq.shape[0]
    W = _volterra(Bq, N, Dseq, ncols, P11, P12, ge1)    # w_k = D_k dd_k, k = 0..N
    Sst = W[:-ns] + W[ns:]                       # w_j + w_{j+1}, j = 0..N-1
    # final state: sum_j A^(N-1-j) e b^T (w_j + w_{j+1}); column j ns + s of U is ge[N-1-j] * Bq[s]
    rev = ge1[::-1]
    U1 = (rev[:, None, :] * Bq[None, :, :]).reshape(N * ns, n).T
    return U1, Sst


def monodromy_factors(omega2, Bq, h, nsteps, Dseq):
    """dq_N / dq0 as (d (n,), U (n, r), Vt (r, n)) with dq_N / dq0 = diag(d) + U @ Vt, r = nsteps n_s: the
    diagonal is the linear modes' map, the low-rank term the elements' (lowrank.DiagonalPlusLowRank)."""
    N = int(nsteps)
    P11, P12, p21, p22, ge1, ge2 = _powers(omega2, h, N)
    if Bq.shape[0] == 0 or N == 0:
        n = omega2.shape[0]
        return P11[N].copy(), np.zeros((n, 0)), np.zeros((0, n))
    U1, Sst = _low_rank(Bq, N, Dseq, omega2.shape[0], P11, P12, ge1)
    return P11[N].copy(), U1, Sst


def monodromy(omega2, Bq, h, nsteps, Dseq, ncols, velocities=True):
    """Exact derivative of the discrete flow map: (Sq, Sv) = d[q_N; v_N]/d[q0 (; v0)] (n, ncols) each.

    ncols = n: only the columns of dq0 (reversible orbits that start at rest); 2n: all.  velocities=False skips
    Sv (returned as None): the shooting Jacobian of quarter-period shooting and the multipliers of reversible
    orbits need only Sq.
    """
    n = omega2.shape[0]
    ns = Bq.shape[0]
    N = int(nsteps)
    P11, P12, p21, p22, ge1, ge2 = _powers(omega2, h, N)
    Sq = np.zeros((n, ncols))
    idx = np.arange(n)
    Sq[idx, idx] = P11[N]
    if ncols > n:
        Sq[idx, n + idx] = P12[N]
    Sv = None
    if velocities:
        Sv = np.zeros((n, ncols))
        Sv[idx, idx] = p21
        if ncols > n:
            Sv[idx, n + idx] = p22
    if ns == 0 or N == 0:
        return Sq, Sv
    U1, Sst = _low_rank(Bq, N, Dseq, ncols, P11, P12, ge1)
    Sq += U1 @ Sst
    if velocities:
        U2 = (ge2[::-1][:, None, :] * Bq[None, :, :]).reshape(N * ns, n).T
        Sv += U2 @ Sst
    return Sq, Sv
