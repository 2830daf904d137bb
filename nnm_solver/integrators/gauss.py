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
finite differences).

Per-mode rotation of the linear discrete map: the stability function of the s-stage Gauss method is
the (s, s) Pade approximant of exp, R(z) = P(z) / P(-z), so a step rotates a mode of frequency w by
2 arg P(i h w) (see ``rotation``), which gives the discrete linear period exactly.
"""
from __future__ import annotations

import math
import threading
from functools import lru_cache

import numpy as np

from ..jit import jit as _jit, lapack_solve
from ..model.laws import law_force
from .gauss_monodromy import monodromy as _monodromy, monodromy_factors as _monodromy_factors
from .lowrank import DiagonalPlusLowRank
from .newmark import solve_stages
from .settings import KERNELS

__all__ = ["tableau", "rotation", "GaussConstants", "constants", "sweep_state", "sweep_record",
           "sweep_sensitivity", "sweep_factors"]


@lru_cache(maxsize=None)
def tableau(s):
    """Butcher tableau (A (s, s), b (s,), c (s,)) of the s-stage Gauss-Legendre method (order 2s).

    c are the roots of the shifted Legendre polynomial of degree s on [0, 1]; A_lj = int_0^{c_l} L_j,
    b_j = int_0^1 L_j with L_j the Lagrange polynomials on c (collocation).
    """
    x, _ = np.polynomial.legendre.leggauss(s)
    c = 0.5 * (x + 1.0)
    A = np.empty((s, s))
    b = np.empty(s)
    for j in range(s):
        others = np.delete(c, j)
        L = np.poly1d(np.poly(others) / np.prod(c[j] - others))
        Li = np.polyint(L)
        b[j] = Li(1.0) - Li(0.0)
        A[:, j] = Li(c) - Li(0.0)
    return A, b, c


def rotation(y, s):
    """Angle (rad) by which one step of the s-stage Gauss method rotates a linear mode, y = h w.

    R(iy) = P(iy) / conj(P(iy)) with P the numerator of the (s, s) Pade approximant of exp:
    P(z) = sum_k (2s - k)! s! / ((2s)! k! (s - k)!) z^k; s = 1 is the trapezoidal rule (Newmark's
    average acceleration, 2 atan(y / 2)).
    """
    z = 1j * np.asarray(y, dtype=float)
    P = sum(math.factorial(2 * s - k) * math.factorial(s) / (math.factorial(2 * s) * math.factorial(k)
                                                              * math.factorial(s - k)) * z ** k for k in range(s + 1))
    return 2.0 * np.angle(P)


class GaussConstants:
    """The step-size dependent constants of one model and one h (s stages).

    C1, Cc (n, s): stage responses to q and v (Q_lin = C1 q + h Cc v per mode); F (n, s, s) = h^2 M^-1 Abar;
    G (s n_s, s n_s) the stage-deformation coupling; A_lin (n, 2, 2), E (n, 2, s), C (n, s, 2) the per-mode
    linear step of the sensitivities.
    """

    def __init__(self, omega2, Bq, h, s):
        A, b, c = (x.copy() for x in _tableau(s))
        Abar = A @ A
        bbar = A.T @ b
        self.s, self.h = s, h
        self.b, self.bbar, self.c, self.Abar = b, bbar, c, Abar
        Bq = np.ascontiguousarray(Bq, dtype=float)
        ns, n = Bq.shape
        self.BB = (Bq[:, None, :] * Bq[None, :, :]).reshape(ns * ns, n)          # b_m b_m^T per mode
        (self.Minv, self.C1, self.Cc, self.F, self.G, self.C, self.A_lin,
         self.E) = _step_constants(np.asarray(omega2, dtype=float), Bq, float(h), Abar, b, bbar, c)


@_jit
def _step_constants(omega2, Bq, h, Abar, b, bbar, c):
    """GaussConstants' arrays in one compiled pass over the modes (numpy's batched 3 x 3 inverses and products took
    2-4 ms a step size on the aircraft, one per Newton iterate: each has its own period): per mode M = I + h^2 w^2
    Abar, Minv = M^-1 (Gauss-Jordan, partial pivoting), C1 = Minv 1, Cc = Minv c, F = h^2 Minv Abar, C = [C1, h Cc],
    A_lin = L - w^2 U C, E = U (I - w^2 F) with L = [[1, h], [0, 1]], U = [h^2 bbar; h b]; and G (s n_s, s n_s),
    G[(l, x), (j, y)] = sum_i F_i[l, j] Bq[x, i] Bq[y, i]."""
    n = omega2.shape[0]
    s = b.shape[0]
    ns = Bq.shape[0]
    Minv = np.empty((n, s, s))
    C1 = np.empty((n, s))
    Cc = np.empty((n, s))
    F = np.empty((n, s, s))
    C = np.empty((n, s, 2))
    A_lin = np.empty((n, 2, 2))
    E = np.empty((n, 2, s))
    W = np.empty((s, 2 * s))
    U = np.empty((2, s))
    for l in range(s):
        U[0, l] = h * h * bbar[l]
        U[1, l] = h * b[l]
    for i in range(n):
        hw = h * h * omega2[i]
        for a in range(s):
            for j in range(s):
                W[a, j] = hw * Abar[a, j] + (1.0 if a == j else 0.0)
                W[a, s + j] = 1.0 if a == j else 0.0
        for col in range(s):
            piv = col
            for a in range(col + 1, s):
                if abs(W[a, col]) > abs(W[piv, col]):
                    piv = a
            if piv != col:
                for j in range(2 * s):
                    t = W[col, j]
                    W[col, j] = W[piv, j]
                    W[piv, j] = t
            d = 1.0 / W[col, col]
            for j in range(2 * s):
                W[col, j] *= d
            for a in range(s):
                if a != col:
                    f = W[a, col]
                    for j in range(2 * s):
                        W[a, j] -= f * W[col, j]
        for a in range(s):
            acc1 = 0.0
            accc = 0.0
            for j in range(s):
                m = W[a, s + j]
                Minv[i, a, j] = m
                acc1 += m
                accc += m * c[j]
            C1[i, a] = acc1
            Cc[i, a] = accc
            C[i, a, 0] = acc1
            C[i, a, 1] = h * accc
            for j in range(s):
                acc = 0.0
                for k in range(s):
                    acc += W[a, s + k] * Abar[k, j]
                F[i, a, j] = h * h * acc
        w2 = omega2[i]
        for t in range(2):
            for col in range(2):
                acc = 0.0
                for l in range(s):
                    acc += U[t, l] * C[i, l, col]
                A_lin[i, t, col] = (1.0 if t == col else 0.0) + (h if (t == 0 and col == 1) else 0.0) - w2 * acc
            for j in range(s):
                acc = 0.0
                for l in range(s):
                    acc += U[t, l] * ((1.0 if l == j else 0.0) - w2 * F[i, l, j])
                E[i, t, j] = acc
    G = np.zeros((s * ns, s * ns))
    for l in range(s):
        for j in range(s):
            for x in range(ns):
                for y in range(ns):
                    acc = 0.0
                    for i in range(n):
                        acc += F[i, l, j] * Bq[x, i] * Bq[y, i]
                    G[l * ns + x, j * ns + y] = acc
    return Minv, C1, Cc, F, G, C, A_lin, E


_TABLEAUX = {}


def _tableau(s):
    """tableau(s), computed once per s (GaussConstants copies the arrays)."""
    if s not in _TABLEAUX:
        _TABLEAUX[s] = tableau(s)
    return _TABLEAUX[s]


def constants(system, h, s):
    """GaussConstants of a ModalSystem for the step h (s) and s stages."""
    return _constants(system.omega2, system.Bq, h, s)


#: GaussConstants kept for reuse (KERNELS.gauss_constants_kept of them); the same objects are read only, so a reuse
#: gives the same numbers bit for bit
_recent = []                   # (omega2, Bq, h, s, GaussConstants), most recent first
_recent_lock = threading.Lock()


def _constants(omega2, Bq, h, s):
    """GaussConstants(omega2, Bq, h, s), the same object for the same arrays (identity) and h of a recent call."""
    h = float(h)
    with _recent_lock:
        for entry in _recent:
            if entry[0] is omega2 and entry[1] is Bq and entry[2] == h and entry[3] == s:
                return entry[4]
    k = GaussConstants(omega2, Bq, h, s)
    with _recent_lock:
        _recent.insert(0, (omega2, Bq, h, s, k))
        del _recent[KERNELS.gauss_constants_kept:]
    return k


@_jit
def _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, C1, Cc, F, G, b, bbar, c):
    """One Gauss step from (q, v) with a = f(q). Returns (q1, v1, a1, P, fQ, J, Dg, ok):
    P (s, n) the stage element forces -Bq^T g, fQ (s, n) = f(Q) at the stages, J the converged Newton
    matrix and Dg the stage tangents."""
    n = q.shape[0]
    ns = Bq.shape[0]
    s = b.shape[0]
    Qlin = np.empty((s, n))
    for l in range(s):
        Qlin[l] = C1[:, l] * q + h * Cc[:, l] * v
    P = np.zeros((s, n))
    J = np.eye(s * ns)
    Dg = np.zeros(s * ns)
    ok = True
    if ns > 0:
        Dlin = np.empty(s * ns)
        Dguess = np.empty(s * ns)
        for l in range(s):
            Dlin[l * ns:(l + 1) * ns] = Bq @ Qlin[l]
            tl = c[l] * h
            Dguess[l * ns:(l + 1) * ns] = Bq @ (q + tl * v + 0.5 * tl * tl * a)
        D, J, g, Dg, ok = solve_stages(Dlin, G, s, ns, powers, coeffs, kinks, Dguess, 0)
        for l in range(s):
            P[l] = -(Bq.T @ g[l * ns:(l + 1) * ns])
    fQ = np.empty((s, n))
    for l in range(s):
        Ql = Qlin[l].copy()
        for j in range(s):
            Ql += F[:, l, j] * P[j]
        fQ[l] = -omega2 * Ql + P[l]
    q1 = q + h * v
    v1 = v.copy()
    for l in range(s):
        q1 += (h * h * bbar[l]) * fQ[l]
        v1 += (h * b[l]) * fQ[l]
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
        # r0[l, m] = sq 1 + c_l (v + h sv) + 2 h (Abar fQ)_l ;  Q'lin = Minv r0
        r0 = np.empty((s, n))
        for l in range(s):
            acc = sq + c[l] * (v + h * sv)
            for j in range(s):
                acc = acc + (2.0 * h * Abar[l, j]) * fQ[j]
            r0[l] = acc
        Qp = np.zeros((s, n))
        for l in range(s):
            for j in range(s):
                Qp[l] += Minv[:, l, j] * r0[j]
        Pp = np.zeros((s, n))
        if ns > 0:
            rhs = np.empty(s * ns)
            for l in range(s):
                rhs[l * ns:(l + 1) * ns] = Bq @ Qp[l]
            dd = lapack_solve(J, rhs)
            w = Dg * dd
            for l in range(s):
                Pp[l] = -(Bq.T @ w[l * ns:(l + 1) * ns])
            for l in range(s):
                for j in range(s):
                    Qp[l] += F[:, l, j] * Pp[j]
        sq1 = sq + v + h * sv
        sv1 = sv.copy()
        for l in range(s):
            fp = -omega2 * Qp[l] + Pp[l]
            sq1 += (2.0 * h * bbar[l]) * fQ[l] + (h * h * bbar[l]) * fp
            sv1 += b[l] * fQ[l] + (h * b[l]) * fp
        sq, sv = sq1, sv1
        q, v, a = q1, v1, a1
    return q, v, sq, sv, Dseq, True


def sweep_sensitivity(q0, v0, h, nsteps, system_kernel, s, all_columns=True, velocities=True):
    """Integrate with the sensitivity of the final state (same outputs as newmark.sweep_sensitivity).

    Returns (q, v, Sq, Sv, sq_h, sv_h, ok): Sq = dq_N/d[q0; v0] (n, 2n or n), Sv = dv_N/d[q0; v0], and
    sq_h = dq_N/dh, sv_h = dv_N/dh (n,).
    """
    omega2, Bq, powers, coeffs, kinks = system_kernel
    k = _constants(omega2, Bq, h, s)
    n = q0.shape[0]
    ncols = 2 * n if all_columns else n
    q, v, sq, sv, Dseq, ok = _sweep_with_h(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, k.C1, k.Cc, k.F,
                                           k.G, k.b, k.bbar, k.c, k.Abar, k.Minv)
    if not ok:
        return q, v, np.zeros((n, ncols)), np.zeros((n, ncols)), sq, sv, False
    Sq, Sv = _monodromy(k, Bq, nsteps, Dseq, ncols, velocities)
    return q, v, Sq, Sv, sq, sv, True


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
