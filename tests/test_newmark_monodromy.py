"""The Newmark monodromy assembled with one triangular solve (newmark_monodromy.monodromy) against the step-by-step
Volterra recursion (monodromy_recursive) and against finite differences of the state sweep."""
import dataclasses

import numpy as np
import pytest

from nnm_solver.integrators.newmark import _sweep_tangents, sweep_sensitivity, sweep_state
from nnm_solver.integrators import newmark_monodromy
from nnm_solver.integrators.newmark_monodromy import _linear_map, monodromy


def monodromy_recursive(omega2, Bq, h, nsteps, Dseq, ncols):
    """The reference: the Volterra recursion step by step over all columns (the solver's assembly until 2026-12;
    plain Python here).  Exact derivative of the discrete flow map d[q_N; v_N]/d[q0; v0] (2n, 2n), low-rank form.

    The linearised step is, per mode i, z_{k+1} = A_i z_k + e_i b_i^T (w_k + w_{k+1}) with
    w_k = D_k Bq dq_k the spring-force perturbations (n_s each).  Only the n_s-dimensional
    deformations are propagated step by step (a discrete Volterra recursion through the impulse
    responses H(m) = Bq diag((A^m e)_q) Bq^T); the final state is then the block-diagonal linear
    map A^N plus one (n x N n_s) @ (N n_s x 2n) product.  Cost O(N^2 n_s^2 n + N n_s n^2) instead of
    O(N n^2 n_s) for propagating all 2n columns through every step.  ncols = n gives only the
    columns of dq0 (enough for reversible orbits that start at rest), ncols = 2n all of them.
    """
    n = omega2.shape[0]
    ns = Bq.shape[0]
    N = nsteps
    a11, a12, a21, a22, e1, e2 = _linear_map(omega2, h)
    # powers of A (per mode): P[k] = A^k, k = 0..N, and Ae[m] = A^m e, m = 0..N-1
    p11 = np.empty((N + 1, n))
    p12 = np.empty((N + 1, n))
    p21 = np.empty((N + 1, n))
    p22 = np.empty((N + 1, n))
    p11[0] = 1.0
    p12[0] = 0.0
    p21[0] = 0.0
    p22[0] = 1.0
    for k in range(N):
        p11[k + 1] = a11 * p11[k] + a12 * p21[k]
        p12[k + 1] = a11 * p12[k] + a12 * p22[k]
        p21[k + 1] = a21 * p11[k] + a22 * p21[k]
        p22[k + 1] = a21 * p12[k] + a22 * p22[k]
    ge1 = np.empty((N, n))
    ge2 = np.empty((N, n))
    for m in range(N):
        ge1[m] = p11[m] * e1 + p12[m] * e2
        ge2[m] = p21[m] * e1 + p22[m] * e2
    Sq = np.zeros((n, ncols))
    Sv = np.zeros((n, ncols))
    for i in range(n):
        Sq[i, i] = p11[N, i]
        Sv[i, i] = p21[N, i]
        if ncols > n:
            Sq[i, n + i] = p12[N, i]
            Sv[i, n + i] = p22[N, i]
    if ns == 0:
        return Sq, Sv
    # impulse responses of the deformations: H[m] = Bq diag(ge1[m]) Bq^T
    H = np.einsum("ai,mi,bi->mab", Bq, ge1, Bq)
    # kernel of w_j in dd_k: H(k-1) for j = 0, Kc(k-j) = H(k-j) + H(k-j-1) for 0 < j < k, H(0) for j = k
    Kc = np.zeros((N, ns, ns))
    Kc[1:] = H[1:] + H[:-1]
    # w_k = D_k dd_k, dd_k = Bq dq_k, for every column of [dq0, dv0]
    W = np.zeros((N + 1, ns, ncols))
    W[0, :, :n] = Bq * Dseq[0][:, None]
    eye = np.eye(ns)
    acc = np.empty((ns, ncols))
    for k in range(1, N + 1):
        for a in range(ns):
            for c in range(n):
                acc[a, c] = Bq[a, c] * p11[k, c]
            if ncols > n:
                for c in range(n):
                    acc[a, n + c] = Bq[a, c] * p12[k, c]
        for j in range(k):
            Kj = H[k - 1] if j == 0 else Kc[k - j]
            for a in range(ns):
                for b in range(ns):
                    c_ab = Kj[a, b]
                    if c_ab != 0.0:
                        for c in range(ncols):
                            acc[a, c] += c_ab * W[j, b, c]
        if ns == 1:
            f = Dseq[k, 0] / (1.0 - H[0, 0, 0] * Dseq[k, 0])
            for c in range(ncols):
                W[k, 0, c] = acc[0, c] * f
        else:
            dd = np.linalg.solve(eye - H[0] * Dseq[k][None, :], acc)
            for a in range(ns):
                for c in range(ncols):
                    W[k, a, c] = dd[a, c] * Dseq[k, a]
    # final state: sum_j A^(N-1-j) e b^T (w_j + w_{j+1})
    U1 = np.empty((n, N * ns))
    U2 = np.empty((n, N * ns))
    Sst = np.empty((N * ns, ncols))
    for j in range(N):
        m = N - 1 - j
        for s in range(ns):
            U1[:, j * ns + s] = ge1[m] * Bq[s]
            U2[:, j * ns + s] = ge2[m] * Bq[s]
            Sst[j * ns + s] = W[j, s] + W[j + 1, s]
    Sq += U1 @ Sst
    Sv += U2 @ Sst
    return Sq, Sv


@pytest.mark.parametrize("block", [128, 7])        # one block; several blocks of unequal length (25 = 3 x 7 + 4)
@pytest.mark.parametrize("n, ns, N", [(7, 1, 9), (12, 3, 16), (30, 4, 25)])
def test_triangular_assembly_matches_the_recursion(n, ns, N, block, monkeypatch):
    monkeypatch.setattr(newmark_monodromy, "KERNELS", dataclasses.replace(newmark_monodromy.KERNELS, volterra_block=block))
    rng = np.random.default_rng(n)
    omega2 = np.sort(rng.uniform(0.5, 400.0, n))
    Bq = rng.standard_normal((ns, n))
    Dseq = rng.uniform(-3.0, 3.0, (N + 1, ns))          # strong spring tangents, both signs
    h = 2 * np.pi / np.sqrt(omega2[0]) / 40
    for ncols in (n, 2 * n):
        Sq0, Sv0 = monodromy_recursive(omega2, Bq, h, N, Dseq, ncols)
        Sq, Sv = monodromy(omega2, Bq, h, N, Dseq, ncols)
        scale = max(np.abs(Sq0).max(), np.abs(Sv0).max())
        assert np.abs(Sq - Sq0).max() < 1e-12 * scale and np.abs(Sv - Sv0).max() < 1e-12 * scale
        Sq1, Sv1 = monodromy(omega2, Bq, h, N, Dseq, ncols, velocities=False)
        assert Sv1 is None and np.array_equal(Sq1, Sq)


def test_sensitivity_of_a_strongly_nonlinear_sweep_matches_finite_differences():
    rng = np.random.default_rng(1)
    n, ns = 6, 2
    omega2 = np.sort(rng.uniform(1.0, 50.0, n))
    Bq = rng.standard_normal((ns, n))
    powers = np.array([3, 5], dtype=np.int64)
    coeffs = np.array([[40.0, 5.0], [-3.0, 0.0]])
    kinks = np.zeros((ns, 0, 3))
    q0, v0 = 0.3 * rng.standard_normal(n), 0.2 * rng.standard_normal(n)
    h, N = 0.02, 60
    kern = (omega2, Bq, powers, coeffs, kinks)
    q, v, Sq, Sv, sq_h, sv_h, ok = sweep_sensitivity(q0, v0, h, N, *kern, True)
    assert ok and Sq.shape == (n, 2 * n)
    D = _sweep_tangents(q0, v0, h, N, *kern)[2]
    assert np.abs(D).max() > 1.0                         # the springs matter
    z0, eps = np.concatenate([q0, v0]), 1e-6
    for j in range(2 * n):
        dz = eps * np.eye(2 * n)[j]
        qp, vp, _ = sweep_state(*np.split(z0 + dz, 2), h, N, *kern)
        qm, vm, _ = sweep_state(*np.split(z0 - dz, 2), h, N, *kern)
        fd = np.concatenate([qp - qm, vp - vm]) / (2 * eps)
        assert np.allclose(np.concatenate([Sq[:, j], Sv[:, j]]), fd, rtol=1e-6, atol=1e-7)
