r"""The general Gauss-Legendre kernel in physical coordinates, its stage system solved as one band matrix.

general.py integrates q'' = -Omega^2 q - f_nl(q) in the n modal coordinates, where the tangent of a distributed
nonlinearity (an element on every Gauss point of a beam or a plate) is a full n x n matrix and the stage system
J = I + h^2 Abar (x) (Omega^2 + K_j) (s n x s n, a stage's own K_j in each block column) is solved by dense LU:
O((s n)^3) a Newton iteration, and the sensitivity's s n x (2 n + 1) solve O(n^3) a step.

The same Newton iteration with its linear algebra in physical coordinates x = Phi q (Phi complete and
M-orthonormal: Phi^T M Phi = I, Phi^T K Phi = Omega^2, Phi Phi^T = M^{-1}).  The state, the stage values Q_l and the
residual stay modal, R_l = Q_l - q - c_l h v - h^2 sum_j Abar_lj F_j with F_j = -Omega^2 Q_j - Phi^T f(Phi Q_j)
(the linear part exact per mode, the nonlinear force f = B^T g(B x) from the sparse rows of B); the Newton step is

    dQ = (I (x) Phi^T M) Jx^{-1} (I (x) M Phi) R,   Jx = I (x) M + h^2 (Abar (x) I) blockdiag(K_t(X_j))
                                                       = (I (x) Phi^-T) J (I (x) Phi^-1),

K_t = K + B^T T B the physical tangent: banded for a beam.  With the DOFs renumbered to a narrow band (band.py)
and the stages interleaved (row s i + l: DOF i of stage l), Jx is a band matrix of half-bandwidth s (w + 1) - 1:
its LU is O(n s^3 w^2), a Newton iteration O(n^2) (the maps Phi, Phi^T of the stages) instead of O((s n)^3).
The iterates are the modal kernel's, so the orbit agrees with general.py to round-off (measured 1e-15 to 1e-14 of
its largest entry, 8-32 element beams).  The sensitivity columns are carried in physical coordinates (mapped in by
Phi at the start and out by Phi^T M at the end, O(n^3) once a sweep), O(n^2 s^2 w) a step:

    Jx dX = (I (x) M) Y,   Y_l = Sx + h c_l Sv  (extra column c_l v + 2 h sum_j Abar_lj a_j),
    h^2 K_l dX_l = sum_j (Abar^-1)_lj M (Y_j - dX_j)          (the stage equations: no product with K, no M solve)
    Sx1 = Sx + h Sv - sum_l beta_l (Y_l - dX_l) (+ v + 2 h bbar.a),   Sv1 = Sv - sum_l gamma_l (Y_l - dX_l) / h (+ b.a),

beta = Abar^-T bbar, gamma = Abar^-T b.  The monodromy agrees with the modal kernel's to 2e-10 - 3e-9 of its
largest entry (8-64 element beams): the round-off of solving in physical coordinates, where the stage matrix holds
the beam's stiffest (axial) modes at h w_max ~ 270 (16 elements, 100 steps a period) next to its bending ones; the
same differences on the linear beam, whose modal kernel is exact per mode (tests/test_general_band.py: the dense
path, central differences of the state, energy conservation).
"""
from __future__ import annotations

import threading
import weakref

import numpy as np

from ..jit import jit as _jit, matvec
from ..model.coupled import coupled_force_tangent
from ..model.laws import law_scalar
from .band import band_layout, band_lu, band_solve
from .settings import KERNELS
from .step_newton import NEWTON_MAX, newton_end, stage_guess

__all__ = ["layout", "sweep"]


@_jit
def force_tangent(x, Kb, w, Bp, Bi, Bx, ns, powers, coeffs, kinks, index, ex, co, width, tangent):
    """(f (n,), Kt (n, 2 w + 1)): the nonlinear force B^T g(B x) at the physical displacement x and, when tangent,
    the band tangent of the internal force K x + f, K + B^T T B (Kb the band of K; else Kt is (0, 0))."""
    n = x.shape[0]
    nd = Bp.shape[0] - 1
    d = np.zeros(nd)
    for r in range(nd):
        acc = 0.0
        for k in range(Bp[r], Bp[r + 1]):
            acc += Bx[k] * x[Bi[k]]
        d[r] = acc
    g = np.zeros(nd)
    T = np.zeros((nd, width))
    for r in range(ns):
        g[r], T[r, 0] = law_scalar(d[r], r, powers, coeffs, kinks)
    coupled_force_tangent(d, index, ex, co, g, T)
    f = np.zeros(n)
    for r in range(nd):
        for k in range(Bp[r], Bp[r + 1]):
            f[Bi[k]] += Bx[k] * g[r]
    if not tangent:
        return f, np.zeros((0, 0))
    Kt = Kb.copy()
    for r in range(ns):
        t = T[r, 0]
        for k1 in range(Bp[r], Bp[r + 1]):
            i = Bi[k1]
            for k2 in range(Bp[r], Bp[r + 1]):
                Kt[i, Bi[k2] - i + w] += t * Bx[k1] * Bx[k2]
    for e in range(index.shape[0]):
        r0, m = index[e, 0], index[e, 1]
        for a in range(m):
            for bb in range(m):
                t = T[r0 + a, bb]
                if t == 0.0:
                    continue
                for k1 in range(Bp[r0 + a], Bp[r0 + a + 1]):
                    i = Bi[k1]
                    ta = t * Bx[k1]
                    for k2 in range(Bp[r0 + bb], Bp[r0 + bb + 1]):
                        Kt[i, Bi[k2] - i + w] += ta * Bx[k2]
    return f, Kt


@_jit
def _stage_matrix(Mb, Kts, w, h2Abar):
    """Jx in band storage for band_lu: (N, 3 kb + 1), kb = s (w + 1) - 1, stages interleaved (row s i + l)."""
    s = Kts.shape[0]
    n = Mb.shape[0]
    kb = s * (w + 1) - 1
    Jb = np.zeros((s * n, 3 * kb + 1))
    for i in range(n):
        for p in range(max(0, i - w), min(n - 1, i + w) + 1):
            col = p - i + w
            mv = Mb[i, col]
            for l in range(s):
                I = s * i + l
                for j in range(s):
                    val = h2Abar[l, j] * Kts[j, i, col]
                    if l == j:
                        val += mv
                    Jb[I, s * p + j - I + kb] = val
    return Jb, kb


@_jit
def _gauss_band(q0, v0, h, nsteps, omega2, Phi, PhiT, PhiT_M, MPhi, Mb, Kb, w, Bp, Bi, Bx, ns, powers, coeffs, kinks, index,
                ex, co, width, Abar, b, bbar, c, beta, gamma, record, Sx0, Sv0):
    """Gauss sweep: the state, the stages and the Newton residual in modal coordinates (as general._gauss, the
    linear part Omega^2 q exact), the nonlinear force and the Newton matrix in physical ones (x = Phi q, its band);
    the sensitivity columns in physical coordinates (Sx0, Sv0 (n, m) their seed, m = 0: none; the last column is
    the derivative in h).  Returns (q, v, Q, V, Sx, Sv, k, ok) as general._gauss, Sx, Sv physical."""
    n = q0.shape[0]
    s = b.shape[0]
    m = Sx0.shape[1]
    sens = m > 0
    h2Abar = (h * h) * Abar
    q = q0.copy()
    v = v0.copy()
    Q = np.empty((nsteps + 1 if record else 0, n))
    V = np.empty((nsteps + 1 if record else 0, n))
    if record:
        Q[0] = q
        V[0] = v
    Sx = Sx0.copy()
    Sv = Sv0.copy()
    fq, _ = force_tangent(matvec(Phi, q), Kb, w, Bp, Bi, Bx, ns, powers, coeffs, kinks, index, ex, co, width,
                          False)
    a = -omega2 * q - matvec(PhiT, fq)
    X = np.empty((s, n))
    for l in range(s):
        tl = c[l] * h
        X[l] = q + tl * v + (0.5 * tl * tl) * a
    F = np.empty((s, n))
    Kts = np.empty((s, n, 2 * w + 1))
    base = np.empty((s, n))
    for k in range(nsteps):
        for l in range(s):
            base[l] = q + (c[l] * h) * v
        scale = np.sqrt(np.sum(base * base)) + 1e-300
        ok = False
        Jb = np.zeros((1, 1))
        kb = 0
        for it in range(NEWTON_MAX + 1):
            for l in range(s):
                fl, Kts[l] = force_tangent(matvec(Phi, X[l]), Kb, w, Bp, Bi, Bx, ns, powers, coeffs, kinks, index,
                                           ex, co, width, True)
                F[l] = -omega2 * X[l] - matvec(PhiT, fl)
            rhs = np.empty((s * n, 1))
            nR2 = 0.0
            for l in range(s):
                R = X[l] - base[l]
                for j in range(s):
                    R = R - h2Abar[l, j] * F[j]
                nR2 += np.sum(R * R)
                MR = matvec(MPhi, R)
                for i in range(n):
                    rhs[s * i + l, 0] = MR[i]
            nR = np.sqrt(nR2)
            Jb, kb = _stage_matrix(Mb, Kts, w, h2Abar)
            stop, ok = newton_end(it, nR, Jb, scale)
            if stop:
                break
            piv, fine = band_lu(Jb, kb, kb)
            if not fine:
                break
            band_solve(Jb, piv, kb, kb, rhs)
            dX = np.empty(n)
            for l in range(s):
                for i in range(n):
                    dX[i] = rhs[s * i + l, 0]
                X[l] = X[l] - matvec(PhiT_M, dX)
        q1 = q + h * v
        v1 = v.copy()
        for l in range(s):
            q1 += (h * h * bbar[l]) * F[l]
            v1 += (h * b[l]) * F[l]
        if ok and sens:
            piv, ok = band_lu(Jb, kb, kb)
        if not ok:
            return q1, v1, Q, V, Sx, Sv, k, False
        if sens:
            _sensitivity_step(Sx, Sv, h, v, F, Phi, Mb, w, Jb, piv, kb, Abar, b, bbar, c, beta, gamma)
        f1, _ = force_tangent(matvec(Phi, q1), Kb, w, Bp, Bi, Bx, ns, powers, coeffs, kinks, index, ex, co, width,
                              False)
        a = -omega2 * q1 - matvec(PhiT, f1)
        q, v = q1, v1
        stage_guess(X, q, v, a, c, h)
        if record:
            Q[k + 1] = q
            V[k + 1] = v
    return q, v, Q, V, Sx, Sv, nsteps, True


@_jit
def _sensitivity_step(Sx, Sv, h, vq, Fq, Phi, Mb, w, Jb, piv, kb, Abar, b, bbar, c, beta, gamma):
    """One step of the physical sensitivity columns (Sx, Sv (n, m), updated in place; the last column the derivative
    in h), with the stage matrix's LU (Jb, piv) at the converged stages, the modal velocity vq and the stage
    accelerations Fq (s, n)."""
    n, m = Sx.shape
    s = b.shape[0]
    ncols = m - 1
    v = matvec(Phi, vq)
    F = np.empty((s, n))
    for l in range(s):
        F[l] = matvec(Phi, Fq[l])
    rhs0 = np.empty((s * n, m))                         # the stage equations' right-hand sides Sx + h c_l Sv (+ extra)
    for l in range(s):
        extra = c[l] * v
        for j in range(s):
            extra = extra + (2.0 * h * Abar[l, j]) * F[j]
        hc = h * c[l]
        for i in range(n):
            for col in range(m):
                rhs0[s * i + l, col] = Sx[i, col] + hc * Sv[i, col]
            rhs0[s * i + l, ncols] += extra[i]
    rhs = np.empty((s * n, m))
    for i in range(n):
        MS = np.zeros((s, m))
        for p in range(max(0, i - w), min(n - 1, i + w) + 1):
            mv = Mb[i, p - i + w]
            if mv != 0.0:
                for l in range(s):
                    for col in range(m):
                        MS[l, col] += mv * rhs0[s * p + l, col]
        for l in range(s):
            rhs[s * i + l] = MS[l]
    band_solve(Jb, piv, kb, kb, rhs)
    Gx = np.zeros((n, m))                               # h^2 M^-1 sum_l bbar_l K_l dX_l, from the stage equations
    Gv = np.zeros((n, m))                               # h M^-1 sum_l b_l K_l dX_l
    for l in range(s):
        bl = beta[l]
        gl = gamma[l] / h
        for i in range(n):
            for col in range(m):
                r = rhs0[s * i + l, col] - rhs[s * i + l, col]
                Gx[i, col] += bl * r
                Gv[i, col] += gl * r
    ext_q = v.copy()
    ext_v = np.zeros(n)
    for l in range(s):
        ext_q += (2.0 * h * bbar[l]) * F[l]
        ext_v += b[l] * F[l]
    for i in range(n):
        for col in range(m):
            Sx[i, col] += h * Sv[i, col] - Gx[i, col]
            Sv[i, col] -= Gv[i, col]
        Sx[i, ncols] += ext_q[i]
        Sv[i, ncols] += ext_v[i]


_layouts = weakref.WeakKeyDictionary()
_layouts_lock = threading.Lock()


def layout(system, always=False):
    """The BandLayout of a ModalSystem in its complete modal basis (band.band_layout), computed once per system;
    None when the basis is not complete (a Ritz basis of fewer modes: no physical form) or, unless always, when the
    band does not pay (KERNELS.band_solver: then no band arrays are built)."""
    if system.n != system.model.n:
        return None
    with _layouts_lock:
        per = _layouts.setdefault(system, {})
        if always not in per:
            index = system.elements.table[0]
            per[always] = band_layout(system.model.M, system.model.K_linear, system.elements.B, index, system.Phi,
                                      system.PhiT_M, accept=None if always else KERNELS.band_solver)
        return per[always]


def sweep(lay, args, tab, q0, v0, h, nsteps, record=False, ncols=0):
    """general.sweep's (q, v, Q, V, SQ, SV, k, ok) by the band kernel: lay a system's layout(), args its
    general.kernel_args, tab = (Abar, b, bbar, c) of the Gauss tableau."""
    omega2, _, _, ns, powers, coeffs, kinks, index, ex, co, width = args
    n = lay.Phi.shape[0]
    m = ncols + 1 if ncols > 0 else 0
    Abar, b, bbar, _ = tab
    beta, gamma = np.linalg.solve(Abar.T, bbar), np.linalg.solve(Abar.T, b)     # K dX from the stage equations
    S0 = np.zeros((2 * n, m))                       # the seed: identity on the first ncols entries of [q0; v0]
    S0[np.arange(ncols), np.arange(ncols)] = 1.0
    q, v, Q, V, Sx, Sv, k, ok = _gauss_band(
        np.ascontiguousarray(q0, dtype=float), np.ascontiguousarray(v0, dtype=float), float(h), int(nsteps), omega2,
        lay.Phi, lay.PhiT, lay.PhiT_M, lay.MPhi, lay.Mb, lay.Kb, lay.w, lay.Bp, lay.Bi, lay.Bx, ns, powers, coeffs,
        kinks, index, ex, co, width, *tab, beta, gamma, bool(record), np.ascontiguousarray(lay.Phi @ S0[:n]),
        np.ascontiguousarray(lay.Phi @ S0[n:]))
    return q, v, Q, V, lay.PhiT_M @ Sx, lay.PhiT_M @ Sv, k, ok
