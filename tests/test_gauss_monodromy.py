"""The Gauss monodromy's assembly (integrators/gauss_monodromy.py: a compiled loop for the orbit-independent parts, the
Volterra recursion as one unit lower triangular solve) against the assembly it replaced (numpy's batched products and
the step-by-step recursion, plain Python here) and against finite differences of the state sweep."""
import dataclasses

import numpy as np
import pytest

import nnm_solver as nnm
from nnm_solver.integrators import gauss, gauss_monodromy
from nnm_solver.integrators.registry import get_integrator
from nnm_solver.model.modal import modal_system


def monodromy_reference(k, Bq, N, Dseq, ncols, velocities=True):
    """The reference: the solver's assembly until 2026-12 (numpy's batched 2 x 2 products, the Volterra recursion one
    step and one history term at a time).  d[q_N; v_N]/d[q0 (; v0)] as (Sq, Sv)."""
    n, ns, s = Bq.shape[1], Bq.shape[0], k.s
    m = s * ns
    P = np.empty((N + 1, n, 2, 2))
    P[0] = np.eye(2)[None]
    for r in range(N):
        P[r + 1] = k.A_lin @ P[r]
    Sq = np.zeros((n, ncols))
    Sv = np.zeros((n, ncols))
    i = np.arange(n)
    for S, row in ((Sq, 0), (Sv, 1)):
        S[i, i] = P[N, :, row, 0]
        if ncols > n:
            S[i, n + i] = P[N, :, row, 1]
    CA = k.C[None] @ P[:N]                                          # (N, n, s, 2)
    H = [np.einsum("ilj,xi,yi->lxjy", CA[r] @ k.E, Bq, Bq).reshape(m, m) for r in range(N - 1)]
    W = np.zeros((N, m, ncols))
    for kk in range(N):
        acc = np.zeros((m, ncols))
        acc[:, :n] = np.einsum("il,xi->lxi", CA[kk, :, :, 0], Bq).reshape(m, n)
        if ncols > n:
            acc[:, n:] = np.einsum("il,xi->lxi", CA[kk, :, :, 1], Bq).reshape(m, n)
        for j in range(kk):
            acc -= H[kk - 1 - j] @ W[j]
        W[kk] = np.linalg.solve(np.eye(m) + k.G * Dseq[kk][None, :], acc) * Dseq[kk][:, None]
    for j in range(N):
        AE = P[N - 1 - j] @ k.E                                     # (n, 2, s)
        for S, row in ((Sq, 0), (Sv, 1)):
            S -= np.einsum("il,xi->ilx", AE[:, row, :], Bq).reshape(n, m) @ W[j]
    return Sq, (Sv if velocities else None)


def _system():
    K = np.array([[2.0, -1, 0, 0], [-1, 2, -1, 0], [0, -1, 2, -1], [0, 0, -1, 2.5]])
    return modal_system(nnm.Model(np.diag([1.0, 2.0, 1.5, 1.2]), K, [
        nnm.CubicSpring(dof=0, k3=0.8), nnm.CubicSpring(dof=2, other=1, k3=-0.1), nnm.CubicSpring(dof=3, k3=2.0)]))


@pytest.mark.parametrize("stages", [2, 3])
@pytest.mark.parametrize("N", [1, 2, 7, 40])
def test_assembly_equals_the_reference(stages, N):
    system = _system()
    n, ns = system.n, system.Bq.shape[0]
    k = gauss.GaussConstants(system.omega2, system.Bq, 0.07, stages)
    Dseq = np.random.default_rng(N).uniform(-0.5, 3.0, size=(N, stages * ns))
    for ncols in (n, 2 * n):
        for velocities in (False, True):
            Sq, Sv = gauss_monodromy.monodromy(k, system.Bq, N, Dseq, ncols, velocities)
            Rq, Rv = monodromy_reference(k, system.Bq, N, Dseq, ncols, velocities)
            scale = np.max(np.abs(Rq))
            assert np.max(np.abs(Sq - Rq)) <= 1e-13 * scale
            if velocities:
                assert np.max(np.abs(Sv - Rv)) <= 1e-13 * np.max(np.abs(Rv))
            else:
                assert Sv is None


def test_blocks_of_the_volterra_solve(monkeypatch):
    """More steps than one block of the triangular solve (KERNELS.volterra_block): the earlier blocks enter by a
    matrix product; the same numbers as one block."""
    system = _system()
    n, ns = system.n, system.Bq.shape[0]
    k = gauss.GaussConstants(system.omega2, system.Bq, 0.05, 3)
    N = 23
    Dseq = np.random.default_rng(1).uniform(0.0, 2.0, size=(N, 3 * ns))
    one = gauss_monodromy.monodromy(k, system.Bq, N, Dseq, 2 * n, True)
    monkeypatch.setattr(gauss_monodromy, "KERNELS", dataclasses.replace(gauss_monodromy.KERNELS, volterra_block=5))
    blocks = gauss_monodromy.monodromy(k, system.Bq, N, Dseq, 2 * n, True)
    for a, b in zip(one, blocks):
        assert np.max(np.abs(a - b)) <= 1e-13 * np.max(np.abs(a))
    assert np.max(np.abs(one[0] - monodromy_reference(k, system.Bq, N, Dseq, 2 * n)[0])) <= 1e-13 * np.max(np.abs(one[0]))


def test_sweep_against_finite_differences():
    """The whole sensitivity sweep (its recorded tangents into this assembly) against central differences of the
    state sweep, at amplitudes where the springs matter."""
    system = _system()
    integ = get_integrator("gauss6")
    n = system.n
    z0 = np.random.default_rng(5).normal(size=2 * n)
    h, N = 0.08, 30
    _, _, Sq, Sv, _, _, ok = integ.sensitivity(system, z0[:n], z0[n:], h, N, True)
    assert ok
    S = np.vstack([Sq, Sv])
    fd = np.empty_like(S)
    eps = 1e-6
    for j in range(2 * n):
        zp, zm = z0.copy(), z0.copy()
        zp[j] += eps
        zm[j] -= eps
        a = integ.state(system, zp[:n], zp[n:], h, N)
        b = integ.state(system, zm[:n], zm[n:], h, N)
        fd[:, j] = (np.r_[a[0], a[1]] - np.r_[b[0], b[1]]) / (2 * eps)
    assert np.max(np.abs(S - fd)) < 1e-7 * np.max(np.abs(S))
    assert np.max(np.abs(S - np.eye(2 * n))) > 0.1          # (not a trivial map)


def test_no_springs_is_the_linear_map():
    system = modal_system(nnm.Model(np.eye(3), np.diag([1.0, 4.0, 9.0]), []))
    k = gauss.GaussConstants(system.omega2, system.Bq, 0.1, 3)
    Sq, Sv = gauss_monodromy.monodromy(k, system.Bq, 12, np.zeros((12, 0)), 6, True)
    P = np.linalg.matrix_power(k.A_lin, 12)
    assert np.allclose(Sq, np.hstack([np.diag(P[:, 0, 0]), np.diag(P[:, 0, 1])]), rtol=0, atol=1e-14)
    assert np.allclose(Sv, np.hstack([np.diag(P[:, 1, 0]), np.diag(P[:, 1, 1])]), rtol=0, atol=1e-14)


@pytest.mark.parametrize("N", [1, 7, 25])
def test_velocity_factors_are_the_monodromys_dv_dv0_block(N):
    """gauss_monodromy.velocity_factors: diag(d) - U W is monodromy's Sv[:, n:] (the dv0 columns alone)."""
    system = _system()
    n, ns = system.n, system.Bq.shape[0]
    k = gauss.GaussConstants(system.omega2, system.Bq, 0.07, 3)
    Dseq = np.random.default_rng(N).uniform(-0.5, 3.0, size=(N, 3 * ns))
    d, U, W = gauss_monodromy.velocity_factors(k, system.Bq, N, Dseq)
    assert U.shape == (n, N * 3 * ns) and W.shape == (N * 3 * ns, n)
    Sv = monodromy_reference(k, system.Bq, N, Dseq, 2 * n)[1][:, n:]
    assert np.max(np.abs(np.diag(d) - U @ W - Sv)) <= 1e-13 * np.max(np.abs(Sv))


def test_reversible_half_block_is_the_quarter_maps_formula():
    """gauss.reversible_half_block from the record of a dq0-columns-only sweep equals 2 Gvv^T Gqq - I of the full
    quarter map (all columns and velocity rows), at any state; and that map is symplectic (G^T J G = J, which the
    formula assumes) to round-off."""
    system = _system()
    n = system.n
    z0 = np.random.default_rng(3).normal(size=2 * n)
    h, N = 0.08, 30
    out, stages = gauss.sweep_sensitivity_stages(z0[:n], z0[n:], h, N, system.kernel, 3, False, False)
    assert out[-1] and out[3] is None and stages.nsteps == N and stages.Dseq.shape == (N, 3 * system.Bq.shape[0])
    A11 = gauss.reversible_half_block(out[2], stages, system.kernel, 3)
    _, _, Sq, Sv, _, _, ok = gauss.sweep_sensitivity(z0[:n], z0[n:], h, N, system.kernel, 3, True, True)
    # (the same arithmetic; bit for bit on one CPU, 1 ulp apart on another whose compiled loops vectorise the two
    # sweeps differently)
    assert np.max(np.abs(out[2] - Sq[:, :n])) <= 1e-14 * np.max(np.abs(Sq[:, :n]))
    G = np.vstack([Sq, Sv])
    J = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    assert np.max(np.abs(G.T @ J @ G - J)) < 1e-12 * np.max(np.abs(G)) ** 2
    assert np.max(np.abs(G - np.eye(2 * n))) > 0.1                       # (the springs matter)
    dense = 2 * Sv[:, n:].T @ Sq[:, :n] - np.eye(n)
    assert np.max(np.abs(A11 - dense)) <= 1e-13 * np.max(np.abs(dense))
    no_springs = modal_system(nnm.Model(np.eye(3), np.diag([1.0, 4.0, 9.0]), []))
    out, stages = gauss.sweep_sensitivity_stages(np.ones(3), np.zeros(3), 0.1, 5, no_springs.kernel, 3, False, False)
    P = np.linalg.matrix_power(gauss.GaussConstants(no_springs.omega2, no_springs.Bq, 0.1, 3).A_lin, 10)
    assert np.allclose(gauss.reversible_half_block(out[2], stages, no_springs.kernel, 3), np.diag(P[:, 0, 0]),
                       rtol=0, atol=1e-14)                             # the linear modes: cos 2 theta = 2 cos^2 - 1
