r"""Gauss-Legendre collocation in modal coordinates, with the exact sensitivity of the discrete map.

Equation of motion (modal.py):  q'' = f(q) = -Omega^2 q - Bq^T g(Bq q).

The s-stage Gauss-Legendre Runge-Kutta method (order 2s; symplectic and symmetric, so the discrete
flow of a conservative system keeps its energy bounded and its linear modes on the unit circle)
applied to [q' = v, v' = f(q)], with its Butcher tableau (A, b, c), reads in Nystrom form

    Q_l = q + c_l h v + h^2 sum_j Abar_lj f(Q_j),      Abar = A A               (stages)
    q1  = q + h v + h^2 sum_j bbar_j f(Q_j),           bbar = A^T b = b (1 - c)
    v1  = v + h sum_j b_j f(Q_j).

Since Omega^2 is diagonal, the linear part of the stage equations is solved per mode,
(I + h^2 w_m^2 Abar) Q_m = q_m 1 + h c v_m + h^2 Abar p_m, with p_l = -Bq^T g(d_l) the element
forces at stage l, so only the s n_s stage deformations d_l = Bq Q_l are unknown:

    D + G g(D) = Dlin,   G[(l, r), (j, t)] = sum_m F_m[l, j] Bq[r, m] Bq[t, m],  F_m = h^2 M_m^-1 Abar,

solved by Newton to round-off (the same damped Newton as Newmark's springs, newmark.solve_stages).
One step costs O(n s n_s) plus an (s n_s)^2 solve, like Newmark with s times as many springs.

Sensitivities.  The linearised step is, per mode, z_{k+1} = A_m z_k + E_m p_k (z = (dq, dv)), with the
stage perturbations dQ_k = C_m z_k + F_m p_k and p_k = -Bq^T (D_k dd_k), D_k = g'(d_k) at the stages.
The monodromy is assembled exactly, as for Newmark, from the per-mode linear maps and a recursion on
the s n_s stage deformations only (gauss_monodromy.py); the derivative with respect to h is carried as
one extra column in the sweep.  Both are the exact derivatives of the discrete map (tested against
finite differences).  The map is symplectic and, for odd forces, reversible: the half-period block A11 of a
reversible orbit follows from its quarter-period map (``reversible_half_block``), without the second quarter's sweep.

Per-mode rotation of the linear discrete map: the stability function of the s-stage Gauss method is
the (s, s) Pade approximant of exp, R(z) = P(z) / P(-z), so a step rotates a mode of frequency w by
2 arg P(i h w) (see ``rotation``), which gives the discrete linear period exactly.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..jit import jit as _jit, lapack_solve
from ..model.laws import law_force
from .gauss_constants import GaussConstants, _constants, constants, rotation, tableau  # noqa: F401 (the names gauss gave)
from .gauss_monodromy import (directional as _directional, monodromy as _monodromy, monodromy_factors as _monodromy_factors,
                              subtract_product as _subtract_product, velocity_factors as _velocity_factors)
from .lowrank import DiagonalPlusLowRank
from .newmark import solve_stages

__all__ = ["tableau", "rotation", "GaussConstants", "constants", "sweep_state", "sweep_record",
           "sweep_sensitivity", "sweep_factors", "SweepStages", "sweep_sensitivity_stages", "reversible_half_block",
           "sweep_directional"]


@_jit
def _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c):
    """One Gauss step from (q, v) with a = f(q). Returns (q1, v1, a1, P, fQ, J, Dg, ok):
    P (s, n) the stage element forces -Bq^T g, fQ (s, n) = f(Q) at the stages, J the converged Newton
    matrix and Dg the stage tangents."""
    n = q.shape[0]
    ns = Bq.shape[0]
    s = b.shape[0]
    Qlin = np.empty((s, n))
    for i in range(n):              # (one pass over the modes, rows of C1 and Cc contiguous: the same numbers as
        qi, vi = q[i], v[i]         # numpy's C1[:, l] * q + h * Cc[:, l] * v)
        for l in range(s):
            Qlin[l, i] = C1[i, l] * qi + (h * Cc[i, l]) * vi
    P = np.zeros((s, n))
    J = np.eye(s * ns)
    Dg = np.zeros(s * ns)
    ok = True
    if ns > 0:
        Dlin = np.empty(s * ns)
        Dguess = np.empty(s * ns)
        x = np.empty(n)
        for l in range(s):
            Dlin[l * ns:(l + 1) * ns] = Bq @ Qlin[l]
            tl = c[l] * h
            t2 = 0.5 * tl * tl
            for i in range(n):                  # q + tl v + tl^2 a / 2 without numpy's temporaries
                x[i] = (q[i] + tl * v[i]) + t2 * a[i]
            Dguess[l * ns:(l + 1) * ns] = Bq @ x
        D, J, g, Dg, ok = solve_stages(Dlin, G, s, ns, powers, coeffs, kinks, Dguess, 0)
        for l in range(s):
            P[l] = -(Bq.T @ g[l * ns:(l + 1) * ns])
    # f(Q_l) = -w^2 (Qlin_l + sum_j F_lj P_j) + P_l, then q1, v1: one pass over the modes (each F[i] contiguous),
    # each mode's operations in numpy's order (the same numbers)
    fQ = np.empty((s, n))
    q1 = np.empty(n)
    v1 = np.empty(n)
    for i in range(n):
        qi = q[i] + h * v[i]
        vi = v[i]
        w2 = -omega2[i]
        for l in range(s):
            Ql = Qlin[l, i]
            for j in range(s):
                Ql += F[i, l, j] * P[j, i]
            f = w2 * Ql + P[l, i]
            fQ[l, i] = f
            qi += (h * h * bbar[l]) * f
            vi += (h * b[l]) * f
        q1[i] = qi
        v1[i] = vi
    if ns > 0:
        a1 = -omega2 * q1 - Bq.T @ law_force(Bq @ q1, powers, coeffs, kinks)
    else:
        a1 = -omega2 * q1
    return q1, v1, a1, P, fQ, J, Dg, ok


@_jit
def _accel(q, omega2, Bq, powers, coeffs, kinks):
    if Bq.shape[0] == 0:
        return -omega2 * q
    return -omega2 * q - Bq.T @ law_force(Bq @ q, powers, coeffs, kinks)


@_jit
def sweep_state(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c):
    """Integrate nsteps of size h from (q0, v0). Returns (q, v, ok)."""
    q = q0.copy()
    v = v0.copy()
    a = _accel(q, omega2, Bq, powers, coeffs, kinks)
    for _ in range(nsteps):
        q, v, a, P, fQ, J, Dg, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c)
        if not ok:
            return q, v, False
    return q, v, True


@_jit
def sweep_record(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c):
    """Integrate and keep every state: (Q (nsteps+1, n), V (nsteps+1, n), ok)."""
    n = q0.shape[0]
    Q = np.empty((nsteps + 1, n))
    V = np.empty((nsteps + 1, n))
    q = q0.copy()
    v = v0.copy()
    a = _accel(q, omega2, Bq, powers, coeffs, kinks)
    Q[0] = q
    V[0] = v
    for k in range(nsteps):
        q, v, a, P, fQ, J, Dg, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c)
        if not ok:
            return Q[: k + 1], V[: k + 1], False
        Q[k + 1] = q
        V[k + 1] = v
    return Q, V, True


@_jit
def _sweep_with_h(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c, Abar, Minv):
    """State sweep that records the stage tangents (nsteps, s n_s) and carries d[q; v]/dh.

    Differentiating the stage equations in h (q', v' the sensitivities of the current state):
    (I + h^2 w^2 Abar) Q' = q' 1 + c (v + h v') + 2 h Abar f(Q) + h^2 Abar p',  p' = -Bq^T (Dg Bq Q'),
    q1' = q' + v + h v' + 2 h bbar.f(Q) + h^2 bbar.f'(Q),  v1' = v' + b.f(Q) + h b.f'(Q).
    """
    n = q0.shape[0]
    ns = Bq.shape[0]
    s = b.shape[0]
    Dseq = np.zeros((nsteps, s * ns))
    q = q0.copy()
    v = v0.copy()
    a = _accel(q, omega2, Bq, powers, coeffs, kinks)
    sq = np.zeros(n)
    sv = np.zeros(n)
    for k in range(nsteps):
        q1, v1, a1, P, fQ, J, Dg, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c)
        if not ok:
            return q1, v1, sq, sv, Dseq, False
        Dseq[k] = Dg
        # r0[l, m] = sq 1 + c_l (v + h sv) + 2 h (Abar fQ)_l ;  Q'lin = Minv r0: one pass over the modes (each
        # Minv[i] contiguous), each mode's operations in the order of numpy's expressions (the same numbers)
        Qp = np.empty((s, n))
        r0 = np.empty(s)
        for i in range(n):
            base = v[i] + h * sv[i]
            for l in range(s):
                acc = sq[i] + c[l] * base
                for j in range(s):
                    acc = acc + (2.0 * h * Abar[l, j]) * fQ[j, i]
                r0[l] = acc
            for l in range(s):
                acc = 0.0
                for j in range(s):
                    acc += Minv[i, l, j] * r0[j]
                Qp[l, i] = acc
        Pp = np.zeros((s, n))
        if ns > 0:
            rhs = np.empty(s * ns)
            for l in range(s):
                rhs[l * ns:(l + 1) * ns] = Bq @ Qp[l]
            dd = lapack_solve(J, rhs)
            w = Dg * dd
            for l in range(s):
                Pp[l] = -(Bq.T @ w[l * ns:(l + 1) * ns])
            for i in range(n):
                for l in range(s):
                    acc = Qp[l, i]
                    for j in range(s):
                        acc += F[i, l, j] * Pp[j, i]
                    Qp[l, i] = acc
        sq1 = np.empty(n)
        sv1 = np.empty(n)
        for i in range(n):
            a_q = (sq[i] + v[i]) + h * sv[i]
            a_v = sv[i]
            w2 = -omega2[i]
            for l in range(s):
                fp = w2 * Qp[l, i] + Pp[l, i]
                a_q += (2.0 * h * bbar[l]) * fQ[l, i] + (h * h * bbar[l]) * fp
                a_v += b[l] * fQ[l, i] + (h * b[l]) * fp
            sq1[i] = a_q
            sv1[i] = a_v
        sq, sv = sq1, sv1
        q, v, a = q1, v1, a1
    return q, v, sq, sv, Dseq, True


def sweep_sensitivity(q0, v0, h, nsteps, system_kernel, s, all_columns=True, velocities=True):
    """Integrate with the sensitivity of the final state (same outputs as newmark.sweep_sensitivity).

    Returns (q, v, Sq, Sv, sq_h, sv_h, ok): Sq = dq_N/d[q0; v0] (n, 2n or n), Sv = dv_N/d[q0; v0], and
    sq_h = dq_N/dh, sv_h = dv_N/dh (n,).
    """
    return sweep_sensitivity_stages(q0, v0, h, nsteps, system_kernel, s, all_columns, velocities)[0]


@dataclass(frozen=True)
class SweepStages:
    """What a sensitivity sweep of nsteps steps of size h (s) leaves for more columns of its map at the same orbit: the
    stage tangents Dseq (nsteps, s n_s) (reversible_half_block)."""

    h: float
    nsteps: int
    Dseq: np.ndarray


def sweep_sensitivity_stages(q0, v0, h, nsteps, system_kernel, s, all_columns=True, velocities=True):
    """sweep_sensitivity's outputs and the sweep's SweepStages (None when the sweep failed)."""
    omega2, Bq, powers, coeffs, kinks = system_kernel
    k = _constants(omega2, Bq, h, s)
    n = q0.shape[0]
    ncols = 2 * n if all_columns else n
    q, v, sq, sv, Dseq, ok = _sweep_with_h(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, k.C1, k.Cc, k.F,
                                           k.G, k.b, k.bbar, k.c, k.Abar, k.Minv)
    if not ok:
        return (q, v, np.zeros((n, ncols)), np.zeros((n, ncols)), sq, sv, False), None
    Sq, Sv = _monodromy(k, Bq, nsteps, Dseq, ncols, velocities)
    return (q, v, Sq, Sv, sq, sv, True), SweepStages(float(h), int(nsteps), Dseq)


def reversible_half_block(Gqq, stages, system_kernel, s):
    r"""A11 = dq(2 t)/dq0 (n, n) of a symmetric reversible orbit (v0 = 0, q(t) = 0 at t = nsteps h) from its
    quarter-period map G = d[q; v](t)/d[q0; v0]: Gqq = dq(t)/dq0 (the quarter-period shooting Jacobian's) and the
    sweep's SweepStages, without integrating from t to 2 t.

    The discrete Gauss map phi of q'' = f(q) with an odd f is symmetric (reversible: R phi R = phi^-1 for R = diag(I,
    -I)) and commutes with -I, so P phi P = phi^-1 for P = diag(-I, I).  At z1 = (0, v1), a fixed point of P, the map
    over the next quarter period is D phi(z1) = P G^-1 P, so the half-period map is M = P G^-1 P G; the scheme is
    symplectic (G^-1 = -J G^T J), hence M_qq = Gvv^T Gqq + Gqv^T Gvq = 2 Gvv^T Gqq - I (G^T J G = J: Gqq^T Gvv -
    Gvq^T Gqv = I).  With Gvv = diag(d) - U W (gauss_monodromy.velocity_factors, rank r = nsteps s n_s):

        A11 = 2 diag(d) Gqq - 2 W^T (U^T Gqq) - I,

    two n x r x n products (the half-period sweep's monodromy: one n x 2r x n product after a Volterra solve of twice
    the size and twice the steps).  Exact for the discrete orbit when q(t) = 0; a converged shooting point has q(t) =
    O(tol) |q0|, and A11 then differs from the half-period sweep's by about that (tests/test_quarter_period.py)."""
    omega2, Bq, _, _, _ = system_kernel
    k = _constants(omega2, Bq, stages.h, s)
    d, U, W = _velocity_factors(k, Bq, stages.nsteps, stages.Dseq)
    Gqq = np.ascontiguousarray(Gqq[:, :Gqq.shape[0]])
    A = (2.0 * d)[:, None] * Gqq
    A[np.diag_indices_from(A)] -= 1.0
    if U.shape[1]:
        _subtract_product(A, np.ascontiguousarray(W.T), U.T @ Gqq, 2.0)
    return A


def sweep_factors(q0, v0, h, nsteps, system_kernel, s):
    """Integrate with dq_N/dq0 kept as a diagonal plus a low-rank term of rank nsteps s n_s: (q, v,
    DiagonalPlusLowRank, ok), the same map as sweep_sensitivity's Sq with all_columns=False (lowrank.py; None when
    the sweep fails)."""
    omega2, Bq, powers, coeffs, kinks = system_kernel
    k = _constants(omega2, Bq, h, s)
    q, v, _, _, Dseq, ok = _sweep_with_h(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, k.C1, k.Cc, k.F, k.G,
                                         k.b, k.bbar, k.c, k.Abar, k.Minv)
    if not ok:
        return q, v, None, False
    return q, v, DiagonalPlusLowRank(*_monodromy_factors(k, Bq, nsteps, Dseq)), True


def sweep_directional(q0, v0, h, nsteps, system_kernel, s, X):
    """Integrate with the derivative of the final state along a few initial displacements X (n, p): (q, v, dq_N/dq0 @
    X, dv_N/dq0 @ X, ok), the same numbers as sweep_sensitivity's Sq @ X and Sv @ X to round-off at the cost of a
    state sweep and a Volterra solve of p columns (gauss_monodromy.directional)."""
    omega2, Bq, powers, coeffs, kinks = system_kernel
    k = _constants(omega2, Bq, h, s)
    X = np.asarray(X, dtype=float)
    q, v, _, _, Dseq, ok = _sweep_with_h(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, k.C1, k.Cc, k.F,
                                         k.G, k.b, k.bbar, k.c, k.Abar, k.Minv)
    if not ok:
        return q, v, np.zeros_like(X), np.zeros_like(X), False
    SqX, SvX = _directional(k, Bq, nsteps, Dseq, X)
    return q, v, SqX, SvX, True
