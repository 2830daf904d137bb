r"""Newmark and Gauss-Legendre steps in the full modal space, for models whose elements couple deformations.

The kernels of newmark.py and gauss.py solve the implicit step on the n_s spring deformations with a diagonal
element tangent diag(g'(d)).  A coupled element (model/coupled.py: PolynomialStiffness) has a full m x m tangent
block, so models that hold one take these kernels instead (registry.py chooses): the same schemes, solved by
Newton in the n modal coordinates,

    f(q) = -Omega^2 q - f_nl(q),   f_nl = Bq^T g(Bq q),   K(q) = d f_nl / dq = Bq^T T(d) Bq,

T block-diagonal (the springs' g' and the coupled blocks), and the exact sensitivity of the discrete map carried
as columns through every step (the classical forward sensitivity, O(n^3) a step: these kernels are meant for
models of up to a few hundred modes, reduced-order models and beams).

Newmark (average acceleration, step h, c1 = 4 / h^2):
    (c1 + Omega^2) q1 + f_nl(q1) = c1 q + (4 / h) v + a,   a1 = f(q1),   v1 = v + h (a + a1) / 2.
Its derivative with respect to the state and to h (delta h = 1 on the extra column):
    (c1 + Omega^2 + K1) dq1 = c1 dq + (4 / h) dv + da + c1 v1 dh,  da1 = -(Omega^2 + K1) dq1,
    dv1 = dv + h (da + da1) / 2 + (a + a1) dh / 2.
Gauss (s stages, Nystrom form as in gauss.py): R_l = Q_l - q - c_l h v - h^2 sum_j Abar_lj f(Q_j) = 0,
    J = I + h^2 Abar (x) (Omega^2 + K_j);  J dQ = dq 1 + h c dv + dh (c v + 2 h Abar f(Q)),
    dq1 = dq + h dv + dh (v + 2 h bbar.f(Q)) + h^2 bbar.df,  dv1 = dv + dh b.f(Q) + h b.df,  df_l = -(Omega^2 + K_l) dQ_l.
Tested against finite differences of the state sweeps (tests/test_polynomial_stiffness.py).  A step whose Newton
iteration meets a NaN or an infinity (an orbit that escapes, a NaN start) ends the sweep with ok = False, the failed
orbit the corrector refuses, instead of the LinAlgError of the linear solve (tests/test_general_nan.py).

The dense stage LU is O((s n)^3) a Newton iteration.  A model whose physical tangent is banded (a beam: every
element's force on a few neighbouring DOFs) and whose modal basis is complete takes general_band.py instead for the
Gauss schemes: the same iteration with the stage system solved as one band matrix in physical coordinates
(``stage_solver`` decides, with KERNELS.band_solver; measured in benchmarks/README.md, "von Karman beam").
"""
from __future__ import annotations

import numpy as np

from ..jit import jit as _jit, lapack_solve, lapack_solve_many, matmul_t
from ..model.coupled import coupled_force_tangent
from ..model.laws import law_scalar
from . import general_band
from .step_newton import NEWTON_MAX, newton_end as _newton_end, stage_guess

@_jit
def force_stiffness(q, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width):
    """(f_nl (n,), K (n, n)) at the modal displacement q: Bq^T g(Bq q) and Bq^T T Bq."""
    nd = Bq.shape[0]
    n = q.shape[0]
    d = np.zeros(nd)
    for r in range(nd):
        acc = 0.0
        for i in range(n):
            acc += Bq[r, i] * q[i]
        d[r] = acc
    g = np.zeros(nd)
    T = np.zeros((nd, width))                       # T[r0 + a, b]: local column b of the element's block
    for r in range(ns):
        g[r], T[r, 0] = law_scalar(d[r], r, powers, coeffs, kinks)
    coupled_force_tangent(d, index, ex, co, g, T)
    f = np.zeros(n)
    YT = np.zeros((n, nd))                          # (T Bq)^T
    for r in range(ns):
        t = T[r, 0]
        for i in range(n):
            f[i] += Bq[r, i] * g[r]
            YT[i, r] = t * Bq[r, i]
    for e in range(index.shape[0]):
        r0, m = index[e, 0], index[e, 1]
        for a in range(m):
            ga = g[r0 + a]
            for i in range(n):
                f[i] += Bq[r0 + a, i] * ga
                acc = 0.0
                for b in range(m):
                    acc += T[r0 + a, b] * Bq[r0 + b, i]
                YT[i, r0 + a] = acc
    return f, matmul_t(BqT, YT)


@_jit
def _sweep_start(q0, v0, nsteps, record, ncols):
    """The state, the recorded trajectory's arrays (its first row set) and the sensitivity seed of a sweep (both
    schemes): SQ, SV (n, ncols + 1) with the identity on the first ncols entries of [q0; v0]; sens, m = ncols + 1."""
    n = q0.shape[0]
    q = q0.copy()
    v = v0.copy()
    Q = np.empty((nsteps + 1 if record else 0, n))
    V = np.empty((nsteps + 1 if record else 0, n))
    if record:
        Q[0] = q
        V[0] = v
    sens = ncols > 0
    m = ncols + 1 if sens else 0
    SQ = np.zeros((n, m))
    SV = np.zeros((n, m))
    if sens:
        for i in range(n):
            if i < ncols:
                SQ[i, i] = 1.0
            if n + i < ncols:
                SV[i, n + i] = 1.0
    return q, v, Q, V, SQ, SV, sens, m


@_jit
def _newmark(q0, v0, h, nsteps, omega2, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width, record, ncols):
    """Newmark sweep; returns (q, v, Q, V, SQ, SV, k, ok): Q, V every state when record (else (0, n)); SQ, SV
    (n, ncols + 1) the derivatives of the final state with respect to the first ncols entries of [q0; v0] and to h
    (last column) when ncols > 0 (else (n, 0)); k the steps done."""
    n = q0.shape[0]
    c1 = 4.0 / h ** 2
    c2 = 4.0 / h
    S = c1 + omega2
    f, K = force_stiffness(q0, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width)
    a = -omega2 * q0 - f
    q, v, Q, V, SQ, SV, sens, m = _sweep_start(q0, v0, nsteps, record, ncols)
    SA = np.zeros((n, m))
    if sens:
        SA = -(omega2[:, None] * SQ) - K @ SQ
    for k in range(nsteps):
        r = c1 * q + c2 * v + a
        q1 = q + h * v + (0.5 * h * h) * a
        scale = np.sqrt(np.sum(r * r)) + 1e-300
        ok = False
        J = np.eye(n)
        for it in range(NEWTON_MAX + 1):
            f, K = force_stiffness(q1, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width)
            R = S * q1 + f - r
            nR = np.sqrt(np.sum(R * R))
            J = K.copy()
            for i in range(n):
                J[i, i] += S[i]
            stop, ok = _newton_end(it, nR, J, scale)
            if stop:
                break
            q1 = q1 - lapack_solve(J, R)
        a1 = -omega2 * q1 - f
        v1 = v + (0.5 * h) * (a + a1)
        if not ok:
            return q1, v1, Q, V, SQ, SV, k, False
        if sens:
            rhs = c1 * SQ + c2 * SV + SA
            rhs[:, ncols] += c1 * v1
            SQ1 = lapack_solve_many(J, rhs)
            SA1 = -(omega2[:, None] * SQ1) - K @ SQ1
            SV = SV + (0.5 * h) * (SA + SA1)
            SV[:, ncols] += 0.5 * (a + a1)
            SQ = np.ascontiguousarray(SQ1)
            SA = SA1
        q, v, a = q1, v1, a1
        if record:
            Q[k + 1] = q
            V[k + 1] = v
    return q, v, Q, V, SQ, SV, nsteps, True


@_jit
def _gauss(q0, v0, h, nsteps, omega2, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width, Abar, b, bbar, c,
           record, ncols):
    """Gauss-Legendre sweep (s = len(b) stages), outputs as _newmark's."""
    n = q0.shape[0]
    s = b.shape[0]
    f, K = force_stiffness(q0, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width)
    a = -omega2 * q0 - f
    q, v, Q, V, SQ, SV, sens, m = _sweep_start(q0, v0, nsteps, record, ncols)
    N = s * n
    X = np.empty((s, n))
    for l in range(s):
        tl = c[l] * h
        X[l] = q + tl * v + (0.5 * tl * tl) * a
    F = np.empty((s, n))
    Ks = np.empty((s, n, n))
    for k in range(nsteps):
        base = np.empty((s, n))
        for l in range(s):
            base[l] = q + (c[l] * h) * v
        scale = np.sqrt(np.sum(base * base)) + 1e-300
        ok = False
        J = np.eye(N)
        for it in range(NEWTON_MAX + 1):
            for l in range(s):
                fl, Kl = force_stiffness(X[l], Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width)
                F[l] = -omega2 * X[l] - fl
                Ks[l] = Kl
            R = np.empty(N)
            for l in range(s):
                acc = X[l] - base[l]
                for j in range(s):
                    acc = acc - (h * h * Abar[l, j]) * F[j]
                R[l * n:(l + 1) * n] = acc
            nR = np.sqrt(np.sum(R * R))
            J = np.eye(N)
            for l in range(s):
                for j in range(s):
                    w = h * h * Abar[l, j]
                    for i in range(n):
                        for p in range(n):
                            J[l * n + i, j * n + p] += w * Ks[j, i, p]
                        J[l * n + i, j * n + i] += w * omega2[i]
            stop, ok = _newton_end(it, nR, J, scale)
            if stop:
                break
            dX = lapack_solve(J, R)
            for l in range(s):
                X[l] = X[l] - dX[l * n:(l + 1) * n]
        q1 = q + h * v
        v1 = v.copy()
        for l in range(s):
            q1 += (h * h * bbar[l]) * F[l]
            v1 += (h * b[l]) * F[l]
        if not ok:
            return q1, v1, Q, V, SQ, SV, k, False
        if sens:
            rhs = np.empty((N, m))
            for l in range(s):
                rhs[l * n:(l + 1) * n] = SQ + (h * c[l]) * SV
                extra = c[l] * v
                for j in range(s):
                    extra = extra + (2.0 * h * Abar[l, j]) * F[j]
                rhs[l * n:(l + 1) * n, ncols] += extra
            dQ = lapack_solve_many(J, rhs)
            SQ1 = SQ + h * SV
            SV1 = SV.copy()
            ext_q = v.copy()
            ext_v = np.zeros(n)
            for l in range(s):
                dQl = np.ascontiguousarray(dQ[l * n:(l + 1) * n])
                df = -(omega2[:, None] * dQl) - Ks[l] @ dQl
                SQ1 += (h * h * bbar[l]) * df
                SV1 += (h * b[l]) * df
                ext_q += (2.0 * h * bbar[l]) * F[l]
                ext_v += b[l] * F[l]
            SQ1[:, ncols] += ext_q
            SV1[:, ncols] += ext_v
            SQ, SV = SQ1, SV1
        # the next step's first guess: the collocation polynomial of this step extrapolated (here: Taylor)
        f1, K = force_stiffness(q1, Bq, BqT, ns, powers, coeffs, kinks, index, ex, co, width)
        a = -omega2 * q1 - f1
        q, v = q1, v1
        stage_guess(X, q, v, a, c, h)
        if record:
            Q[k + 1] = q
            V[k + 1] = v
    return q, v, Q, V, SQ, SV, nsteps, True


def kernel_args(system):
    """The model arguments of the general kernels: (omega2, Bq, BqT, n_springs, powers, coeffs, kinks, index,
    exponents, coefficients, width) of a ModalSystem (width: the largest m of a coupled element, at least 1)."""
    index, ex, co = system.elements.table
    width = int(max(index[:, 1].max(initial=1), 1))
    return (system.omega2, system.Bq, np.ascontiguousarray(system.Bq.T), int(system.elements.n_springs),
            system.powers, system.coefficients, system.kinks, index, ex, co, width)


def _scheme(stages):
    if stages == 1:
        return _newmark, ()
    from .gauss import tableau
    A, b, c = tableau(stages)
    return _gauss, (np.ascontiguousarray(A @ A), b, np.ascontiguousarray(A.T @ b), c)


def stage_solver(system, stages):
    """How the implicit stages of a step are solved: "band" (general_band.py: physical coordinates, the tangent's
    band) for Gauss schemes on a complete modal basis whose band pays (KERNELS.band_solver), else "dense" (the
    modal kernels here)."""
    return "band" if stages >= 2 and general_band.layout(system) is not None else "dense"


def sweep(system, stages, q0, v0, h, nsteps, record=False, ncols=0, solver=None):
    """(q, v, Q, V, SQ, SV, k, ok) of the scheme with ``stages`` (1: Newmark) from the modal state (q0, v0);
    solver "dense" or "band" (default: stage_solver's choice)."""
    fn, tab = _scheme(stages)
    args = kernel_args(system)
    if (solver or stage_solver(system, stages)) == "band":
        return general_band.sweep(general_band.layout(system, always=True), args, tab, q0, v0, h, nsteps, record,
                                  ncols)
    return fn(np.ascontiguousarray(q0, dtype=float), np.ascontiguousarray(v0, dtype=float), float(h), int(nsteps),
              *args, *tab, bool(record), int(ncols))


def state(system, stages, q0, v0, h, nsteps):
    q, v, _, _, _, _, _, ok = sweep(system, stages, q0, v0, h, nsteps)
    return q, v, ok


def record(system, stages, q0, v0, h, nsteps):
    _, _, Q, V, _, _, k, ok = sweep(system, stages, q0, v0, h, nsteps, record=True)
    return (Q, V, True) if ok else (Q[: k + 1], V[: k + 1], False)


def sensitivity(system, stages, q0, v0, h, nsteps, all_columns=True, velocities=True):
    """(q, v, Sq, Sv, sq_h, sv_h, ok) as newmark.sweep_sensitivity (Sv None unless velocities)."""
    n = len(q0)
    ncols = 2 * n if all_columns else n
    q, v, _, _, SQ, SV, _, ok = sweep(system, stages, q0, v0, h, nsteps, ncols=ncols)
    if not ok:
        return q, v, np.zeros((n, ncols)), np.zeros((n, ncols)), np.zeros(n), np.zeros(n), False
    return q, v, SQ[:, :ncols], (SV[:, :ncols] if velocities else None), SQ[:, ncols], SV[:, ncols], True
