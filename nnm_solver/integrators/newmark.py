r"""Newmark time integration in modal coordinates, with the exact sensitivity of the discrete map.

Equation of motion in mass-normalised modal coordinates q (x = Phi q):

    q'' + Omega^2 q + Bq^T g(Bq q) = 0,      g(d): the element force laws (elements.py), one per spring

Average-acceleration Newmark (beta = 1/4, gamma = 1/2), step h:

    q_{k+1} = q_k + h v_k + h^2/4 (a_k + a_{k+1})                        (N1)
    v_{k+1} = v_k + h/2 (a_k + a_{k+1})                                  (N2)
    a_{k+1} = -Omega^2 q_{k+1} - Bq^T g(d_{k+1}),  d_{k+1} = Bq q_{k+1}    (equilibrium)

Eliminating a_{k+1}:  S q_{k+1} + Bq^T g(d) = r,  S = 4/h^2 + Omega^2,  r = 4/h^2 q_k + 4/h v_k + a_k.
Since S is diagonal, the implicit step reduces to the n_s spring deformations only:

    d + G g(d) = Bq S^{-1} r,    G = Bq S^{-1} Bq^T  (n_s x n_s, constant for a given h)

solved by Newton to round-off, then q_{k+1} = S^{-1}(r - Bq^T g(d)).  One step costs O(n n_s).

Sensitivity (seed eq. 13-14, discretised): differentiating the step gives the same
diagonal-plus-rank-n_s linear system with the converged Newton matrix (I + G D), D = diag(g'(d)).
The sweep records D_k at every step; the monodromy is then assembled exactly from the per-mode
linear Newmark map and a recursion on the n_s spring deformations only (newmark_monodromy.py), so it is
the exact derivative of the discrete map (no finite differences) without pushing 2n columns through
every step.  The derivative with respect to the step h is carried as one extra column during the
sweep, which gives the exact dH/dT of the discrete shooting function.

The kernels are compiled with numba when it is installed (same source runs in plain Python).
Their model arguments are ``ModalSystem.kernel`` = (omega2, Bq, powers, coeffs, kinks).
"""
from __future__ import annotations

import numpy as np

from ..model.laws import law_force, law_force_tangent, law_scalar
from ..jit import jit as _jit
from .lowrank import DiagonalPlusLowRank
from .newmark_monodromy import monodromy as _monodromy, monodromy_factors as _monodromy_factors

NEWTON_MAX = 40
NEWTON_RTOL = 1e-13


@_jit
def stage_forces(D, s, ns, powers, coeffs, kinks):
    """g and g' (s n_s,) each at the deformations D of s stages of n_s springs (stage-major)."""
    g = np.empty(s * ns)
    t = np.empty(s * ns)
    for l in range(s):
        gl, tl = law_force_tangent(D[l * ns:(l + 1) * ns], powers, coeffs, kinks)
        g[l * ns:(l + 1) * ns] = gl
        t[l * ns:(l + 1) * ns] = tl
    return g, t


@_jit
def _solve_one(Dlin, G, powers, coeffs, kinks, Dguess):
    """solve_stages for a single unknown d + G g(d) = dlin, in scalars."""
    dlin = Dlin[0]
    G0 = G[0, 0]
    scale = abs(dlin) + 1e-300
    D = Dguess[0]
    g, Dg = law_scalar(D, 0, powers, coeffs, kinks)
    F = D + G0 * g - dlin
    nF = abs(F)
    for _ in range(NEWTON_MAX):
        if nF <= NEWTON_RTOL * scale:
            break
        delta = F / (1.0 + G0 * Dg)
        lam = 1.0
        for _ in range(30):
            D_try = D - lam * delta
            g_try, Dg_try = law_scalar(D_try, 0, powers, coeffs, kinks)
            F_try = D_try + G0 * g_try - dlin
            if abs(F_try) < nF or lam < 1e-8:
                break
            lam *= 0.5
        D, F, nF, g, Dg = D_try, F_try, abs(F_try), g_try, Dg_try
    J = np.empty((1, 1))
    J[0, 0] = 1.0 + G0 * Dg
    out = np.empty(3)
    out[0], out[1], out[2] = D, g, Dg
    return out[0:1], J, out[1:2], out[2:3], nF <= NEWTON_RTOL * scale or nF <= 1e-9 * scale


@_jit
def solve_stages(Dlin, G, s, ns, powers, coeffs, kinks, Dguess):
    """Solve D + G g(D) = Dlin for the s n_s spring deformations of s implicit stages (Newmark: s = 1;
    Gauss collocation: gauss.py) by damped Newton; returns (D, J, g, Dg, ok), J = I + G diag(g'),
    g = g(D) and Dg = g'(D) at the solution.

    The Newton step is halved until the residual decreases (softening springs make the step
    equation fold; a full step from the explicit guess can overshoot near the fold).
    """
    m = s * ns
    if m == 1:                                 # one spring, one stage: scalar Newton (no LAPACK call)
        return _solve_one(Dlin, G, powers, coeffs, kinks, Dguess)
    D = Dguess.copy()
    scale = np.sqrt(np.sum(Dlin * Dlin)) + 1e-300
    g, Dg = stage_forces(D, s, ns, powers, coeffs, kinks)
    F = D + G @ g - Dlin
    nF = np.sqrt(np.sum(F * F))
    J = np.eye(m) + G * Dg[None, :]
    for _ in range(NEWTON_MAX):
        if nF <= NEWTON_RTOL * scale:
            return D, J, g, Dg, True
        delta = np.linalg.solve(J, F)
        lam = 1.0
        for _ in range(30):
            D_try = D - lam * delta
            g_try, Dg_try = stage_forces(D_try, s, ns, powers, coeffs, kinks)
            F_try = D_try + G @ g_try - Dlin
            n_try = np.sqrt(np.sum(F_try * F_try))
            if n_try < nF or lam < 1e-8:
                break
            lam *= 0.5
        D, F, nF, g, Dg = D_try, F_try, n_try, g_try, Dg_try
        J = np.eye(m) + G * Dg[None, :]
    return D, J, g, Dg, nF <= 1e-9 * scale


@_jit
def bq_dot(Bq, y):
    """Bq @ y (n_s,) by loops: no BLAS call, whose overhead dominates for small models."""
    ns, n = Bq.shape
    out = np.zeros(ns)
    for s in range(ns):
        acc = 0.0
        for i in range(n):
            acc += Bq[s, i] * y[i]
        out[s] = acc
    return out


@_jit
def bqt_dot(Bq, g):
    """Bq^T @ g (n,) by loops (see bq_dot)."""
    ns, n = Bq.shape
    out = np.zeros(n)
    for s in range(ns):
        gs = g[s]
        for i in range(n):
            out[i] += Bq[s, i] * gs
    return out


@_jit
def _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, G, S, q1, v1, a1, dlin, dguess):
    """One Newmark step from (q, v, a) into the buffers (q1, v1, a1), without temporaries (the per-step
    allocations dominate for small models).  Returns (d1, J, D1, ok): spring deformations, Newton matrix
    I + G diag(g'), D1 = g'(d1)."""
    n = q.shape[0]
    ns = Bq.shape[0]
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    hh = 0.5 * h * h
    for i in range(n):                          # y = r / S, r = 4/h^2 q + 4/h v + a
        q1[i] = (c1 * q[i] + c2 * v[i] + a[i]) / S[i]
    if ns == 0:
        for i in range(n):
            a1[i] = -omega2[i] * q1[i]
            v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
        return dlin, np.eye(0), dlin, True
    for s_ in range(ns):
        acc = 0.0
        accg = 0.0
        for i in range(n):
            acc += Bq[s_, i] * q1[i]
            accg += Bq[s_, i] * (q[i] + h * v[i] + hh * a[i])
        dlin[s_] = acc
        dguess[s_] = accg
    d1, J, g1, D1, ok = solve_stages(dlin, G, 1, ns, powers, coeffs, kinks, dguess)
    for i in range(n):                          # q1 = (r - Bq^T g) / S, a1 = -Omega^2 q1 - Bq^T g
        f = 0.0
        for s_ in range(ns):
            f += Bq[s_, i] * g1[s_]
        q1[i] -= f / S[i]
        a1[i] = -omega2[i] * q1[i] - f
        v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
    return d1, J, D1, ok


@_jit
def _start(q0, omega2, Bq, powers, coeffs, kinks, h):
    S = 4.0 / h ** 2 + omega2
    G = (Bq / S[None, :]) @ Bq.T
    d = bq_dot(Bq, q0)
    a = -omega2 * q0 - bqt_dot(Bq, law_force(d, powers, coeffs, kinks))
    return S, G, d, a


@_jit
def sweep_state(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """Integrate nsteps of size h from (q0, v0). Returns (q, v, ok)."""
    S, G, d, a = _start(q0, omega2, Bq, powers, coeffs, kinks, h)
    n = q0.shape[0]
    q, v = q0.copy(), v0.copy()
    q1, v1, a1 = np.empty(n), np.empty(n), np.empty(n)
    dlin, dguess = np.empty(Bq.shape[0]), np.empty(Bq.shape[0])
    for _ in range(nsteps):
        d, J, D, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, G, S, q1, v1, a1, dlin, dguess)
        q, q1 = q1, q
        v, v1 = v1, v
        a, a1 = a1, a
        if not ok:
            return q, v, False
    return q, v, True


@_jit
def sweep_record(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """Integrate and keep every state: (Q (nsteps+1, n), V (nsteps+1, n), ok)."""
    n = q0.shape[0]
    Q = np.empty((nsteps + 1, n))
    V = np.empty((nsteps + 1, n))
    S, G, d, a = _start(q0, omega2, Bq, powers, coeffs, kinks, h)
    q, v = q0.copy(), v0.copy()
    q1, v1, a1 = np.empty(n), np.empty(n), np.empty(n)
    dlin, dguess = np.empty(Bq.shape[0]), np.empty(Bq.shape[0])
    Q[0] = q
    V[0] = v
    for k in range(nsteps):
        d, J, D, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, G, S, q1, v1, a1, dlin, dguess)
        q, q1 = q1, q
        v, v1 = v1, v
        a, a1 = a1, a
        if not ok:
            return Q[: k + 1], V[: k + 1], False
        Q[k + 1] = q
        V[k + 1] = v
    return Q, V, True


def sweep_sensitivity(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, all_columns=True, velocities=True):
    """Integrate with the sensitivity of the final state.

    Returns (q, v, Sq, Sv, sq_h, sv_h, ok): Sq = dq_N/d[q0; v0] (n, 2n), Sv = dv_N/d[q0; v0],
    sq_h = dq_N/dh, sv_h = dv_N/dh (n,).  all_columns=False: only the n columns of dq0; velocities=False: Sv is
    None (not assembled).  The state pass (_sweep_tangents) records the spring tangents D_k = g'(d_k) and
    carries the single d/dh column; the columns come from newmark_monodromy.monodromy.
    """
    n = q0.shape[0]
    ncols = 2 * n if all_columns else n
    q, v, Dseq, sq_h, sv_h, ok = _sweep_tangents(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks)
    if not ok:
        return q, v, np.zeros((n, ncols)), np.zeros((n, ncols)), sq_h, sv_h, False
    Sq, Sv = _monodromy(omega2, Bq, h, nsteps, Dseq, ncols, velocities)
    return q, v, Sq, Sv, sq_h, sv_h, True


def sweep_factors(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """Integrate with dq_N/dq0 kept as a diagonal plus a low-rank term: (q, v, DiagonalPlusLowRank, ok), the
    same map as sweep_sensitivity's Sq with all_columns=False (lowrank.py; None when the sweep fails)."""
    q, v, Dseq, _, _, ok = _sweep_tangents(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks)
    if not ok:
        return q, v, None, False
    return q, v, DiagonalPlusLowRank(*_monodromy_factors(omega2, Bq, h, nsteps, Dseq)), True


@_jit
def _sweep_tangents(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """The state pass of sweep_sensitivity: (q, v, Dseq (nsteps + 1, n_s), sq_h, sv_h, ok)."""
    n = q0.shape[0]
    ns = Bq.shape[0]
    S, G, d, a = _start(q0, omega2, Bq, powers, coeffs, kinks, h)
    q = q0.copy()
    v = v0.copy()
    Dseq = np.empty((nsteps + 1, ns))
    Dseq[0] = law_force_tangent(d, powers, coeffs, kinks)[1]
    sq_h = np.zeros(n)
    sv_h = np.zeros(n)
    sa_h = np.zeros(n)
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    c1p = -8.0 / h ** 3
    c2p = -4.0 / h ** 2
    invS = 1.0 / S
    q1, v1, a1 = np.empty(n), np.empty(n), np.empty(n)
    dlin, dguess = np.empty(ns), np.empty(ns)
    wh = np.empty(ns)
    for k in range(nsteps):
        d1, J, D1, ok = _step(q, v, a, h, omega2, Bq, powers, coeffs, kinks, G, S, q1, v1, a1, dlin, dguess)
        if not ok:
            return q1, v1, Dseq, sq_h, sv_h, False
        Dseq[k + 1] = D1
        # the step size enters through c1, c2 and (N2); the d/dh column is updated in place:
        # y_h = (c1 sq_h + c2 sv_h + sa_h + c1' (q - q1) + c2' v) / S,  w_h = J^-1 Bq y_h,  f_h = Bq^T (D1 w_h)
        for i in range(n):
            sq_h[i] = (c1 * sq_h[i] + c2 * sv_h[i] + sa_h[i] + c1p * (q[i] - q1[i]) + c2p * v[i]) * invS[i]
        if ns > 0:
            for s_ in range(ns):
                acc = 0.0
                for i in range(n):
                    acc += Bq[s_, i] * sq_h[i]
                wh[s_] = acc
            if ns == 1:
                wh[0] /= J[0, 0]
            else:
                wh[:] = np.linalg.solve(J, wh)
        for i in range(n):
            fh = 0.0
            for s_ in range(ns):
                fh += Bq[s_, i] * D1[s_] * wh[s_]
            sq_h[i] -= fh * invS[i]
            sa1 = -omega2[i] * sq_h[i] - fh
            sv_h[i] += 0.5 * h * (sa_h[i] + sa1) + 0.5 * (a[i] + a1[i])
            sa_h[i] = sa1
        q, q1 = q1, q
        v, v1 = v1, v
        a, a1 = a1, a
    return q, v, Dseq, sq_h, sv_h, True
