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

from ..model.laws import law_scalar
from ..jit import jit as _jit, lapack_solve, matmul_t, matvec
from .lowrank import DiagonalPlusLowRank
from .newmark_monodromy import monodromy as _monodromy, monodromy_factors as _monodromy_factors, one_element
from .settings import KERNELS

#: the step's Newton limits, compile-time constants of the kernels (settings.py: KERNELS)
NEWTON_MAX = KERNELS.newton_max
NEWTON_RTOL = KERNELS.newton_rtol


@_jit
def stage_forces(D, s, ns, powers, coeffs, kinks):
    """g and g' (s n_s,) each at the deformations D of s stages of n_s springs (stage-major)."""
    g = np.empty(s * ns)
    t = np.empty(s * ns)
    for l in range(s):
        for r in range(ns):
            g[l * ns + r], t[l * ns + r] = law_scalar(D[l * ns + r], r, powers, coeffs, kinks)
    return g, t


@_jit
def _solve_one(Dlin, G, powers, coeffs, kinks, Dguess):
    """solve_stages for a single unknown d + G g(d) = dlin, in scalars."""
    e = Dlin.shape[0] - 1                      # the element, 0 (a variable: law_scalar compiled once, for int64)
    dlin = Dlin[0]
    G0 = G[0, 0]
    scale = abs(dlin) + 1e-300
    D = Dguess[0]
    g, Dg = law_scalar(D, e, powers, coeffs, kinks)
    F = D + G0 * g - dlin
    nF = abs(F)
    for _ in range(NEWTON_MAX):
        if nF <= NEWTON_RTOL * scale:
            break
        delta = F / (1.0 + G0 * Dg)
        lam = 1.0
        for _ in range(30):
            D_try = D - lam * delta
            g_try, Dg_try = law_scalar(D_try, e, powers, coeffs, kinks)
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
def _residual(D, G, g, Dlin):
    """F = D + G g - Dlin and its norm (G g by BLAS, the call of numba's ``G @ g``; the rest by loops, which numba
    compiles quickly: numba's array expressions and ``@`` cost seconds of compilation each, issue 32)."""
    Gg = matvec(G, g)
    m = D.shape[0]
    F = np.empty(m)
    acc = 0.0
    for i in range(m):
        F[i] = D[i] + Gg[i] - Dlin[i]
    for i in range(m):
        acc += F[i] * F[i]
    return F, np.sqrt(acc)


@_jit
def _newton_matrix(G, Dg):
    """I + G diag(Dg)."""
    m = Dg.shape[0]
    J = np.empty((m, m))
    for i in range(m):
        for j in range(m):
            J[i, j] = (1.0 if i == j else 0.0) + G[i, j] * Dg[j]
    return J


@_jit
def solve_stages(Dlin, G, s, ns, powers, coeffs, kinks, Dguess, many):
    """Solve D + G g(D) = Dlin for the s n_s spring deformations of s implicit stages (Newmark: s = 1;
    Gauss collocation: gauss.py) by damped Newton; returns (D, J, g, Dg, ok), J = I + G diag(g'),
    g = g(D) and Dg = g'(D) at the solution.

    The Newton step is halved until the residual decreases (softening springs make the step
    equation fold; a full step from the explicit guess can overshoot near the fold).

    many = None: s n_s = 1 is known when compiling (``one_element``), only the scalar Newton is compiled.
    """
    if many is None:                           # pruned by numba when many is None: only the scalar path
        return _solve_one(Dlin, G, powers, coeffs, kinks, Dguess)
    m = s * ns
    if m == 1:                                 # one spring, one stage: scalar Newton (no LAPACK call)
        return _solve_one(Dlin, G, powers, coeffs, kinks, Dguess)
    D = Dguess.copy()
    acc = 0.0
    for i in range(m):
        acc += Dlin[i] * Dlin[i]
    scale = np.sqrt(acc) + 1e-300
    g, Dg = stage_forces(D, s, ns, powers, coeffs, kinks)
    F, nF = _residual(D, G, g, Dlin)
    J = _newton_matrix(G, Dg)
    for _ in range(NEWTON_MAX):
        if nF <= NEWTON_RTOL * scale:
            return D, J, g, Dg, True
        delta = lapack_solve(J, F)
        lam = 1.0
        for _ in range(30):
            D_try = np.empty(m)
            for i in range(m):
                D_try[i] = D[i] - lam * delta[i]
            g_try, Dg_try = stage_forces(D_try, s, ns, powers, coeffs, kinks)
            F_try, n_try = _residual(D_try, G, g_try, Dlin)
            if n_try < nF or lam < 1e-8:
                break
            lam *= 0.5
        D, F, nF, g, Dg = D_try, F_try, n_try, g_try, Dg_try
        J = _newton_matrix(G, Dg)
    return D, J, g, Dg, nF <= 1e-9 * scale


#: what the one compiled sweep (``_sweep``) keeps: the final state, every state, or the spring tangents and d/dh
_STATE, _RECORD, _TANGENTS = 0, 1, 2


@_jit
def _sweep(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, what, many):
    """nsteps of size h from (q0, v0): the one compiled kernel behind sweep_state, sweep_record and
    _sweep_tangents (one kernel, not three: each compiled caller of ``_step`` recompiles all of it, issue 32).

    Returns (q, v, Q, V, Dseq, sq_h, sv_h, k, ok): the final (or failed) state; Q, V (nsteps + 1, n) every state
    (what = _RECORD; rows 0..k are valid when a step failed, k steps done), else (0, n); Dseq (nsteps + 1, n_s) the
    spring tangents D_k = g'(d_k) and sq_h, sv_h = d[q_N; v_N]/dh (what = _TANGENTS), else empty and zero.
    many: ``one_element(Bq)``, None for a model with one element (the scalar solves only are compiled).
    """
    n = q0.shape[0]
    ns = Bq.shape[0]
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    c1p = -8.0 / h ** 3
    c2p = -4.0 / h ** 2
    hh = 0.5 * h * h
    # the constants of the step: S = 4/h^2 + Omega^2, G = Bq S^-1 Bq^T; the initial acceleration a
    S = np.empty(n)
    for i in range(n):
        S[i] = c1 + omega2[i]
    BqS = np.empty((ns, n))
    for r in range(ns):
        for i in range(n):
            BqS[r, i] = Bq[r, i] / S[i]
    G = matmul_t(BqS, Bq)                        # BqS @ Bq.T (the same BLAS call as numba's @)
    d = np.zeros(ns)                             # d = Bq q0, f = Bq^T g(d)
    f = np.zeros(n)
    for s_ in range(ns):
        acc = 0.0
        for i in range(n):
            acc += Bq[s_, i] * q0[i]
        d[s_] = acc
    for s_ in range(ns):
        gs = law_scalar(d[s_], s_, powers, coeffs, kinks)[0]
        for i in range(n):
            f[i] += Bq[s_, i] * gs
    a = np.empty(n)
    for i in range(n):
        a[i] = -omega2[i] * q0[i] - f[i]
    q = q0.copy()
    v = v0.copy()
    record = what == _RECORD
    tangents = what == _TANGENTS
    Q = np.empty((nsteps + 1 if record else 0, n))
    V = np.empty((nsteps + 1 if record else 0, n))
    Dseq = np.empty((nsteps + 1 if tangents else 0, ns))
    sq_h = np.zeros(n)
    sv_h = np.zeros(n)
    sa_h = np.zeros(n)
    if record:
        for i in range(n):
            Q[0, i] = q[i]
            V[0, i] = v[i]
    if tangents:
        for s_ in range(ns):
            Dseq[0, s_] = law_scalar(d[s_], s_, powers, coeffs, kinks)[1]
    invS = np.empty(n)
    for i in range(n):
        invS[i] = 1.0 / S[i]
    q1, v1, a1 = np.empty(n), np.empty(n), np.empty(n)
    dlin, dguess = np.empty(ns), np.empty(ns)
    wh = np.empty(ns)
    J0 = np.eye(0)
    for k in range(nsteps):
        # one Newmark step from (q, v, a) into the buffers (q1, v1, a1), without temporaries (the per-step
        # allocations dominate for small models): the Newton matrix J = I + G diag(g') and D1 = g'(d1) at the
        # spring deformations d1 of the new state
        for i in range(n):                      # y = r / S, r = 4/h^2 q + 4/h v + a
            q1[i] = (c1 * q[i] + c2 * v[i] + a[i]) / S[i]
        if ns == 0:
            for i in range(n):
                a1[i] = -omega2[i] * q1[i]
                v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
            J, D1, ok = J0, dlin, True
        else:
            for s_ in range(ns):
                acc = 0.0
                accg = 0.0
                for i in range(n):
                    acc += Bq[s_, i] * q1[i]
                    accg += Bq[s_, i] * (q[i] + h * v[i] + hh * a[i])
                dlin[s_] = acc
                dguess[s_] = accg
            d1, J, g1, D1, ok = solve_stages(dlin, G, 1, ns, powers, coeffs, kinks, dguess, many)
            for i in range(n):                  # q1 = (r - Bq^T g) / S, a1 = -Omega^2 q1 - Bq^T g
                f_ = 0.0
                for s_ in range(ns):
                    f_ += Bq[s_, i] * g1[s_]
                q1[i] -= f_ / S[i]
                a1[i] = -omega2[i] * q1[i] - f_
                v1[i] = v[i] + 0.5 * h * (a[i] + a1[i])
        if not ok:
            return q1, v1, Q, V, Dseq, sq_h, sv_h, k, False
        if tangents:
            for s_ in range(ns):
                Dseq[k + 1, s_] = D1[s_]
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
                if many is None:
                    wh[0] /= J[0, 0]
                elif ns == 1:
                    wh[0] /= J[0, 0]
                else:
                    x = lapack_solve(J, wh)
                    for s_ in range(ns):
                        wh[s_] = x[s_]
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
        if record:
            for i in range(n):
                Q[k + 1, i] = q[i]
                V[k + 1, i] = v[i]
    return q, v, Q, V, Dseq, sq_h, sv_h, nsteps, True


def sweep_state(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """Integrate nsteps of size h from (q0, v0). Returns (q, v, ok)."""
    q, v, _, _, _, _, _, _, ok = _sweep(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, _STATE, one_element(Bq))
    return q, v, ok


def sweep_record(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """Integrate and keep every state: (Q (nsteps+1, n), V (nsteps+1, n), ok)."""
    _, _, Q, V, _, _, _, k, ok = _sweep(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, _RECORD, one_element(Bq))
    if not ok:
        return Q[: k + 1], V[: k + 1], False
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


def _sweep_tangents(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks):
    """The state pass of sweep_sensitivity: (q, v, Dseq (nsteps + 1, n_s), sq_h, sv_h, ok)."""
    q, v, _, _, Dseq, sq_h, sv_h, _, ok = _sweep(q0, v0, h, nsteps, omega2, Bq, powers, coeffs, kinks, _TANGENTS, one_element(Bq))
    return q, v, Dseq, sq_h, sv_h, ok
