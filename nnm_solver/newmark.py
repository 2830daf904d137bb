r"""Newmark time integration in modal coordinates, with the exact sensitivity of the discrete map.

Equation of motion in mass-normalised modal coordinates q (x = Phi q):

    q'' + Omega^2 q + Bq^T g(Bq q) = 0,      g(d) = k3 * d^3   (one entry per spring)

Average-acceleration Newmark (beta = 1/4, gamma = 1/2), step h:

    q_{k+1} = q_k + h v_k + h^2/4 (a_k + a_{k+1})                        (N1)
    v_{k+1} = v_k + h/2 (a_k + a_{k+1})                                  (N2)
    a_{k+1} = -Omega^2 q_{k+1} - Bq^T g(d_{k+1}),  d_{k+1} = Bq q_{k+1}    (equilibrium)

Eliminating a_{k+1}:  S q_{k+1} + Bq^T g(d) = r,  S = 4/h^2 + Omega^2,  r = 4/h^2 q_k + 4/h v_k + a_k.
Since S is diagonal, the implicit step reduces to the n_s spring deformations only:

    d + G g(d) = Bq S^{-1} r,    G = Bq S^{-1} Bq^T  (n_s x n_s, constant for a given h)

solved by Newton to round-off, then q_{k+1} = S^{-1}(r - Bq^T g(d)).  One step costs O(n n_s).

Sensitivity (seed eq. 13-14, discretised): differentiating the step gives, for every column of
dq_k/dz0, the same diagonal-plus-rank-n_s linear system with the converged Newton matrix
(I + G D), D = diag(g'(d)).  It is propagated in the same sweep, so the monodromy is the exact
derivative of the discrete map (no finite differences); its cost is O(n * m * n_s) per step for
m columns.  The derivative with respect to the step h is carried as one extra column, which gives
the exact dH/dT of the discrete shooting function.

The kernels are compiled with numba when it is installed (same source runs in plain Python).
"""
from __future__ import annotations

import numpy as np

try:  # numba compiles the time-stepping loops; the same code runs uncompiled without it
    import numba

    _jit = numba.njit(cache=True, nogil=True)
except ImportError:  # pragma: no cover
    numba = None

    def _jit(f):
        return f

NEWTON_MAX = 40
NEWTON_RTOL = 1e-13


@_jit
def _solve_springs(dlin, G, k3, dguess):
    """Solve d + G k3 d^3 = dlin (n_s unknowns) by Newton; returns (d, J, ok), J = I + G diag(g')."""
    ns = dlin.shape[0]
    d = dguess.copy()
    J = np.eye(ns)
    scale = np.sqrt(np.sum(dlin * dlin)) + 1e-300
    for _ in range(NEWTON_MAX):
        gd = k3 * d ** 3
        F = d + G @ gd - dlin
        J = np.eye(ns) + G * (3.0 * k3 * d ** 2)[None, :]
        if np.sqrt(np.sum(F * F)) <= NEWTON_RTOL * scale:
            return d, J, True
        d = d - np.linalg.solve(J, F)
    gd = k3 * d ** 3
    F = d + G @ gd - dlin
    J = np.eye(ns) + G * (3.0 * k3 * d ** 2)[None, :]
    return d, J, np.sqrt(np.sum(F * F)) <= 1e-9 * scale


@_jit
def _step(q, v, a, d, h, omega2, Bq, k3, G, S):
    """One Newmark step; returns (q1, v1, a1, d1, J, ok)."""
    r = (4.0 / h ** 2) * q + (4.0 / h) * v + a
    y = r / S
    if Bq.shape[0] == 0:
        q1 = y
        a1 = -omega2 * q1
        return q1, v + 0.5 * h * (a + a1), a1, d, np.eye(0), True
    dlin = Bq @ y
    dguess = Bq @ (q + h * v + 0.5 * h * h * a)
    d1, J, ok = _solve_springs(dlin, G, k3, dguess)
    fnl = Bq.T @ (k3 * d1 ** 3)
    q1 = (r - fnl) / S
    a1 = -omega2 * q1 - fnl
    v1 = v + 0.5 * h * (a + a1)
    return q1, v1, a1, d1, J, ok


@_jit
def _start(q0, omega2, Bq, k3, h):
    S = 4.0 / h ** 2 + omega2
    G = (Bq / S[None, :]) @ Bq.T
    d = Bq @ q0
    a = -omega2 * q0 - Bq.T @ (k3 * d ** 3)
    return S, G, d, a


@_jit
def sweep_state(q0, v0, h, nsteps, omega2, Bq, k3):
    """Integrate nsteps of size h from (q0, v0). Returns (q, v, ok)."""
    S, G, d, a = _start(q0, omega2, Bq, k3, h)
    q = q0.copy()
    v = v0.copy()
    for _ in range(nsteps):
        q, v, a, d, J, ok = _step(q, v, a, d, h, omega2, Bq, k3, G, S)
        if not ok:
            return q, v, False
    return q, v, True


@_jit
def sweep_record(q0, v0, h, nsteps, omega2, Bq, k3):
    """Integrate and keep every state: (Q (nsteps+1, n), V (nsteps+1, n), ok)."""
    n = q0.shape[0]
    Q = np.empty((nsteps + 1, n))
    V = np.empty((nsteps + 1, n))
    S, G, d, a = _start(q0, omega2, Bq, k3, h)
    q = q0.copy()
    v = v0.copy()
    Q[0] = q
    V[0] = v
    for k in range(nsteps):
        q, v, a, d, J, ok = _step(q, v, a, d, h, omega2, Bq, k3, G, S)
        if not ok:
            return Q[: k + 1], V[: k + 1], False
        Q[k + 1] = q
        V[k + 1] = v
    return Q, V, True


@_jit
def sweep_sensitivity(q0, v0, h, nsteps, omega2, Bq, k3):
    """Integrate with the sensitivity of the final state.

    Returns (q, v, Sq, Sv, sq_h, sv_h, ok): Sq = dq_N/d[q0; v0] (n, 2n), Sv = dv_N/d[q0; v0],
    sq_h = dq_N/dh, sv_h = dv_N/dh (n,).
    """
    n = q0.shape[0]
    ns = Bq.shape[0]
    S, G, d, a = _start(q0, omega2, Bq, k3, h)
    q = q0.copy()
    v = v0.copy()
    Sq = np.zeros((n, 2 * n))
    Sv = np.zeros((n, 2 * n))
    for i in range(n):
        Sq[i, i] = 1.0
        Sv[i, n + i] = 1.0
    Dk = 3.0 * k3 * d ** 2
    Sa = -omega2[:, None] * Sq - Bq.T @ (Dk[:, None] * (Bq @ Sq))
    sq_h = np.zeros(n)
    sv_h = np.zeros(n)
    sa_h = np.zeros(n)
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    c1p = -8.0 / h ** 3
    c2p = -4.0 / h ** 2
    invS = 1.0 / S
    for _ in range(nsteps):
        q1, v1, a1, d1, J, ok = _step(q, v, a, d, h, omega2, Bq, k3, G, S)
        if not ok:
            return q1, v1, Sq, Sv, sq_h, sv_h, False
        D1 = 3.0 * k3 * d1 ** 2
        # columns d/dz0
        Y = (c1 * Sq + c2 * Sv + Sa) * invS[:, None]
        # column d/dh (the step size also enters through c1, c2 and (N2))
        yh = (c1 * sq_h + c2 * sv_h + sa_h + c1p * (q - q1) + c2p * v) * invS
        if ns > 0:
            W = np.linalg.solve(J, Bq @ Y)
            wh = np.linalg.solve(J, Bq @ yh)
            F = Bq.T @ (D1[:, None] * W)
            fh = Bq.T @ (D1 * wh)
            Sq1 = Y - F * invS[:, None]
            sq1_h = yh - fh * invS
            Sa1 = -omega2[:, None] * Sq1 - F
            sa1_h = -omega2 * sq1_h - fh
        else:
            Sq1 = Y
            sq1_h = yh
            Sa1 = -omega2[:, None] * Sq1
            sa1_h = -omega2 * sq1_h
        Sv = Sv + (0.5 * h) * (Sa + Sa1)
        sv_h = sv_h + 0.5 * h * (sa_h + sa1_h) + 0.5 * (a + a1)
        Sq = Sq1
        Sa = Sa1
        sq_h = sq1_h
        sa_h = sa1_h
        q, v, a, d = q1, v1, a1, d1
    return q, v, Sq, Sv, sq_h, sv_h, True
