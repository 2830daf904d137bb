r"""Compiled kernels of the condensed harmonic-balance equations (condensed_hb.py) and of their energy
(condensed_energy.py), for models whose elements are springs (the element table of model/element_set.py: no coupled
element).

The numpy forms evaluate the flexibility G_j = sum_k b_k b_k^T W[j, k] as batched products on (N_b, n_s, m) arrays
and the energy through the modal amplitudes A (N_b, m): on the aircraft (m = 548 modes, n_s = 4 springs, N_b = 5)
90-200 us of numpy calls per evaluation, most of it call overhead.  Here each evaluation is one pass over the m modes:

* the flexibility from the element pairs b_s b_t of each mode, kept as ``pairs`` (m, n_s (n_s + 1) / 2): G_j and its
  slope dG_j / dOmega2_j = sum_k b_k b_k^T W[j, k]^2 (for the Jacobian) in N_b n_s (n_s + 1) / 2 m multiply-adds
  each, G symmetric (plus the residual flexibility R0 + Omega2_j R1 of a truncated basis, not necessarily symmetric);
* the element forces and stiffnesses at the N samples by the spring laws' kernel (model/laws.py);
* the energy and its gradient (condensed_energy.py's formulas) with the amplitudes of each mode made and used in
  the same pass, nothing of size N_b m stored (condensed_energy_kernels.py, on this module's pieces).

They round differently from the numpy forms (the sums in another order): the same equations, the results within a
few ulps (tests/test_per_point_kernels.py checks residual, Jacobian, energy and gradient against the numpy forms and
the gradient against central differences).  The units are condensed_hb.py's: D (N_b, n_s) m, a sqrt(kg) m,
omega rad/s, u = [D.ravel(); a beta; omega / w_r].
"""
from __future__ import annotations

import numpy as np

from ..jit import jit, numba
from ..model.laws import law_scalar
from .spring_kernels import int_power

__all__ = ["AVAILABLE", "kernel_arguments", "element_pairs", "flexibility", "residual_jacobian", "chord_residual",
           "unknowns", "amplitudes"]

#: the kernels are compiled (numba installed); without numba the numpy forms are used (a Python loop over the
#: modes would be far slower than them)
AVAILABLE = numba is not None

if AVAILABLE:
    #: the loops over the modes: IEEE division (1 / 0 = inf at an exact internal resonance, no Python check, so
    #: the loop vectorises) and sums over the modes reassociated (vectorised; deterministic, the order fixed by the
    #: compiled code)
    jit_modes = numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc", "contract"})
else:  # pragma: no cover
    jit_modes = jit


def kernel_arguments(prob):
    """The constant arguments of the compiled kernels for the CondensedHBProblem prob: (equations, energy), or None
    where the numpy forms are used (coupled elements, or numba absent); the energy's None for a truncated basis."""
    if not AVAILABLE or prob.sys.elements.coupled:
        return None
    lin, bs, sys = prob.lin, prob.basis, prob.sys
    pairs, index = element_pairs(lin.Bq)
    fund = np.zeros(prob.nb, dtype=bool)
    fund[prob.fund] = True
    table = (np.ascontiguousarray(bs.E, dtype=float), np.ascontiguousarray(bs.P, dtype=float), sys.powers,
             sys.coefficients, sys.kinks)
    common = (prob.cos1, prob.r, float(prob.beta), prob.w_r, np.ascontiguousarray(prob.h2), fund)
    equations = common + (np.ascontiguousarray(prob.b_r), lin.omega2, pairs, index, lin.R0, lin.R1,
                          lin.complete) + table
    c0, s0 = bs.state_at_zero()
    energy = None if not lin.complete else ((sys.kinks.shape[1] == 0,) + common + (
        np.ascontiguousarray(c0, dtype=float), np.ascontiguousarray(s0, dtype=float),
        np.ascontiguousarray(lin.Bq, dtype=float), lin.omega2) + table)
    return equations, energy


def element_pairs(Bq):
    """(pairs (P, m), index (n_s, n_s)): pairs[index[s, t], k] = Bq[s, k] Bq[t, k] for s <= t (P = n_s (n_s + 1) / 2),
    index symmetric."""
    ns = Bq.shape[0]
    index = np.zeros((ns, ns), dtype=np.int64)
    rows = []
    for s in range(ns):
        for t in range(s, ns):
            index[s, t] = index[t, s] = len(rows)
            rows.append(Bq[s] * Bq[t])
    return np.ascontiguousarray(np.array(rows)), index


@jit_modes
def _weights(w, h2, fund, r, omega2, squared):
    """W (N_b, m): W[j, k] = 1 / (w_k^2 - h_j^2 w^2), zero for the followed mode r at the fundamental (fund[j]); inf
    at an exact internal resonance.  With ``squared`` also W^2 (else an empty array)."""
    nb, m = h2.shape[0], omega2.shape[0]
    W = np.empty((nb, m))
    W2 = np.empty((nb if squared else 0, m))
    for j in range(nb):
        Om = h2[j] * w * w
        for k in range(m):
            W[j, k] = 1.0 / (omega2[k] - Om)
        if fund[j]:
            W[j, r] = 0.0
        if squared:
            for k in range(m):
                W2[j, k] = W[j, k] * W[j, k]
    return W, W2


@jit_modes
def _row_products(V, rows):
    """out[j, p] = sum_k V[j, k] rows[p, k] (N_b, P)."""
    nb, P, m = V.shape[0], rows.shape[0], rows.shape[1]
    out = np.empty((nb, P))
    for j in range(nb):
        for p in range(P):
            acc = 0.0
            for k in range(m):
                acc += V[j, k] * rows[p, k]
            out[j, p] = acc
    return out


@jit
def flexibility(w, h2, fund, r, omega2, pairs, index, R0, R1, complete, slope):
    """(G, dG) (N_b, n_s, n_s) each at the frequency w (rad/s): G_j = sum_k b_k b_k^T / (w_k^2 - h_j^2 w^2) over the
    modes but the followed mode r at the fundamental (fund[j]), + R0 + h_j^2 w^2 R1 unless complete; dG its slope in
    Omega2_j (W^2 in place of W, + R1), only when ``slope`` (else zeros).  An exact internal resonance gives inf."""
    nb = h2.shape[0]
    ns = index.shape[0]
    W, W2 = _weights(w, h2, fund, r, omega2, slope)
    Gp = _row_products(W, pairs)
    dGp = _row_products(W2, pairs) if slope else np.zeros((nb, pairs.shape[0]))
    G = np.empty((nb, ns, ns))
    dG = np.zeros((nb, ns, ns))
    for j in range(nb):
        Om = h2[j] * w * w
        for s in range(ns):
            for t in range(ns):
                G[j, s, t] = Gp[j, index[s, t]]
                if slope:
                    dG[j, s, t] = dGp[j, index[s, t]]
                if not complete:
                    G[j, s, t] += R0[s, t] + Om * R1[s, t]
                    if slope:
                        dG[j, s, t] += R1[s, t]
    return G, dG


@jit
def _forces(D, E, P, powers, coeffs, kinks, tangents):
    """(d (N, n_s), F (N_b, n_s), g' (N, n_s)): the sampled deformations d = E D, the force coefficients F = P g(d) and
    (when ``tangents``; else zeros) the sampled stiffnesses."""
    N, nb = E.shape
    ns = D.shape[1]
    d = np.zeros((N, ns))
    for n in range(N):
        for s in range(ns):
            acc = 0.0
            for l in range(nb):
                acc += E[n, l] * D[l, s]
            d[n, s] = acc
    g = np.empty((N, ns))
    tg = np.zeros((N, ns))
    polynomial = kinks.shape[1] == 0
    for n in range(N):
        for s in range(ns):
            x = d[n, s]
            if polynomial:
                # law_scalar's polynomial sums written out, the same numbers: its call with its arrays (not
                # inlined, ~30 ns) cost more than the law, a third of a residual on the aircraft
                f = t = 0.0
                for i in range(powers.shape[0]):
                    c = coeffs[s, i]
                    if c != 0.0:
                        p = powers[i]
                        xp1 = int_power(x, p - 1)
                        f += c * xp1 * x
                        t += p * c * xp1
            else:
                f, t = law_scalar(x, s, powers, coeffs, kinks)
            g[n, s] = f
            if tangents:
                tg[n, s] = t
    F = np.zeros((nb, ns))
    for j in range(nb):
        for s in range(ns):
            acc = 0.0
            for n in range(N):
                acc += P[j, n] * g[n, s]
            F[j, s] = acc
    return d, F, tg


@jit
def _galerkin(tg, E, P):
    """C (n_s, N_b, N_b): C[s, j, l] = sum_n P[j, n] g'_s(t_n) E[n, l] (hb_basis.HBBasis.galerkin)."""
    N, nb = E.shape
    ns = tg.shape[1]
    C = np.zeros((ns, nb, nb))
    for s in range(ns):
        for n in range(N):
            t = tg[n, s]
            for j in range(nb):
                pt = P[j, n] * t
                for l in range(nb):
                    C[s, j, l] += pt * E[n, l]
    return C


@jit
def unknowns(u, nb, ns, beta, w_r):
    """(a, omega rad/s, D (nb, ns) m) of the condensed unknowns u = [D (nb ns, m); a beta; omega / w_r]."""
    nD = nb * ns
    return u[nD] / beta, u[nD + 1] * w_r, u[:nD].reshape((nb, ns))


@jit
def residual_jacobian(u, want_jacobian, cos1, r, beta, w_r, h2, fund, b_r, omega2, pairs, index, R0, R1, complete,
                      E, P, powers, coeffs, kinks):
    """(residual, Jacobian) of the condensed equations at u (condensed_hb.CondensedHBProblem: residual [R_D; R_a beta /
    w_r^2] in m, Jacobian (len(r), N_b n_s + 2)); the Jacobian only when ``want_jacobian`` (else (0, 0))."""
    nb = h2.shape[0]
    ns = b_r.shape[0]
    nD = nb * ns
    a, w, D = unknowns(u, nb, ns, beta, w_r)
    G, dG = flexibility(w, h2, fund, r, omega2, pairs, index, R0, R1, complete, want_jacobian)
    d, F, tg = _forces(D, E, P, powers, coeffs, kinks, want_jacobian)
    nf = 0
    for j in range(nb):
        if fund[j]:
            nf += 1
    res = np.empty(nD + nf)
    for j in range(nb):
        for s in range(ns):
            acc = D[j, s]
            for t in range(ns):
                acc += G[j, s, t] * F[j, t]
            if j == cos1:
                acc -= a * b_r[s]
            res[j * ns + s] = acc
    c = beta / (w_r * w_r)
    i = 0
    for j in range(nb):
        if fund[j]:
            acc = 0.0
            for s in range(ns):
                acc += F[j, s] * b_r[s]
            if j == cos1:
                acc += (w_r * w_r - w * w) * a
            res[nD + i] = acc * c
            i += 1
    if not want_jacobian:
        return res, np.zeros((0, 0))
    C = _galerkin(tg, E, P)
    J = np.zeros((nD + nf, nD + 2))
    for j in range(nb):
        for s in range(ns):
            row = j * ns + s
            for l in range(nb):
                for t in range(ns):
                    J[row, l * ns + t] = G[j, s, t] * C[t, j, l]
            J[row, row] += 1.0
            acc = 0.0
            for t in range(ns):
                acc += dG[j, s, t] * F[j, t]
            J[row, nD + 1] = acc * (2.0 * h2[j] * w) * w_r
    for s in range(ns):
        J[cos1 * ns + s, nD] = -b_r[s] / beta
    i = 0
    for j in range(nb):
        if fund[j]:
            row = nD + i
            for l in range(nb):
                for t in range(ns):
                    J[row, l * ns + t] = c * b_r[t] * C[t, j, l]
            if j == cos1:
                J[row, nD] = (w_r * w_r - w * w) / (w_r * w_r)
                J[row, nD + 1] = -2.0 * w * a * c * w_r
            i += 1
    return res, J


@jit
def chord_residual(u, args):
    """The residual of ``residual_jacobian`` at u, args its constants (``kernel_arguments``' equations): the corrector's
    compiled chord iterations call it (continuation/chord.py, as a first-class function)."""
    return residual_jacobian(u, False, *args)[0]


@jit_modes
def _modal_amplitudes(F, W, Bq, cos1, r, a):
    """A (N_b, m): A[j, k] = -W[j, k] b_k . F[j], A[cos 1, r] = a."""
    nb, m = W.shape
    ns = Bq.shape[0]
    A = np.zeros((nb, m))
    for j in range(nb):
        for s in range(ns):
            f = F[j, s]
            for k in range(m):
                A[j, k] += f * Bq[s, k]
        for k in range(m):
            A[j, k] *= -W[j, k]
    A[cos1, r] = a
    return A


@jit
def amplitudes(u, cos1, r, beta, w_r, h2, fund, Bq, omega2, E, P, powers, coeffs, kinks):
    """(A, F): the modal Fourier coefficients A (N_b, m) of the orbit u (A[j, k] = -W[j, k] b_k . F[j], A[cos 1, r] =
    a) and the element force coefficients F (N_b, n_s)."""
    nb = h2.shape[0]
    ns = Bq.shape[0]
    nD = nb * ns
    w = u[nD + 1] * w_r
    d, F, tg = _forces(u[:nD].reshape((nb, ns)), E, P, powers, coeffs, kinks, False)
    W, W2 = _weights(w, h2, fund, r, omega2, False)
    return _modal_amplitudes(F, W, Bq, cos1, r, u[nD] / beta), F
