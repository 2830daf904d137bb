r"""Compiled kernels of the condensed orbit's energy and its gradient (condensed_energy.py's formulas), for models whose
elements are springs: the modes' kinetic and linear potential energy at t = 0 and the element potentials, with the
amplitudes of each mode made and used in the same pass (nothing of size N_b m stored).  The equations' kernels and
the shared pieces (forces, weights, amplitudes, Galerkin blocks) are condensed_kernels.py's; the units are
condensed_hb.py's.
"""
from __future__ import annotations

import numpy as np

from ..jit import jit
from ..model.laws import law_scalar
from .condensed_kernels import _forces, _galerkin, _modal_amplitudes, _weights, jit_modes, unknowns

__all__ = ["energy_gradient"]


@jit_modes
def _modal_energy(A, W, c0, s0, omega2, Bq, w, h2, gradient):
    """(kinetic / w^2 x 2, potential x 2, gF (N_b, n_s), gw part, Lambda[cos 1, r] needs the caller): the sums over the
    modes of condensed_energy.py's formulas; gF and the omega derivative's sum only when ``gradient``."""
    nb, m = A.shape
    ns = Bq.shape[0]
    q0 = np.zeros(m)
    v1 = np.zeros(m)
    for j in range(nb):
        for k in range(m):
            q0[k] += c0[j] * A[j, k]
            v1[k] += s0[j] * A[j, k]
    kin = 0.0
    pot = 0.0
    for k in range(m):
        kin += v1[k] * v1[k]
        pot += omega2[k] * q0[k] * q0[k]
    gF = np.zeros((nb if gradient else 0, ns))
    gw = 0.0
    if gradient:
        lw = np.empty(m)
        for j in range(nb):
            for k in range(m):
                lw[k] = (c0[j] * omega2[k] * q0[k] + w * w * s0[j] * v1[k]) * W[j, k]
            acc = 0.0
            for k in range(m):
                acc += lw[k] * A[j, k]
            gw += acc * (2.0 * w * h2[j])
            for s in range(ns):
                acc = 0.0
                for k in range(m):
                    acc += lw[k] * Bq[s, k]
                gF[j, s] = -acc
    return kin, pot, gF, gw, q0, v1


@jit
def energy_gradient(u, want_gradient, with_potential, cos1, r, beta, w_r, h2, fund, c0, s0, Bq, omega2, E, P, powers,
                    coeffs, kinks):
    """(energy, gradient): the modes' kinetic and linear potential energy at t = 0 (J), with the element potentials
    at t = 0 when ``with_potential`` (polynomial laws only: a table without kinks, whose potentials need the
    dilogarithm; else the caller adds them) and, when ``want_gradient``, dE/du of the whole energy (J per unit of u;
    the elements' part included: its derivative needs only the forces at t = 0), condensed_energy.py's formulas in
    passes over the modes (a complete basis)."""
    nb = h2.shape[0]
    ns = Bq.shape[0]
    nD = nb * ns
    a, w, D = unknowns(u, nb, ns, beta, w_r)
    d, F, tg = _forces(D, E, P, powers, coeffs, kinks, want_gradient)
    W, W2 = _weights(w, h2, fund, r, omega2, False)
    A = _modal_amplitudes(F, W, Bq, cos1, r, a)
    kin, pot, gF, gw, q0, v1 = _modal_energy(A, W, c0, s0, omega2, Bq, w, h2, want_gradient)
    energy = 0.5 * (w * w) * kin + 0.5 * pot
    x0 = np.zeros(ns)
    for l in range(nb):
        for t in range(ns):
            x0[t] += c0[l] * D[l, t]
    if with_potential:
        for s in range(ns):
            for i in range(powers.shape[0]):
                p = powers[i]
                energy += coeffs[s, i] * x0[s] ** (p + 1) / (p + 1)
    if not want_gradient:
        return energy, np.zeros(0)
    gw += w * kin
    lam_a = c0[cos1] * omega2[r] * q0[r] + w * w * s0[cos1] * v1[r]        # dE/dA[cos 1, r]
    C = _galerkin(tg, E, P)
    g0 = np.empty(ns)                          # the element forces at t = 0
    for t in range(ns):
        g0[t] = law_scalar(x0[t], t, powers, coeffs, kinks)[0]
    grad = np.zeros(nD + 2)
    for l in range(nb):
        for t in range(ns):
            acc = 0.0
            for j in range(nb):
                acc += gF[j, t] * C[t, j, l]
            acc += c0[l] * g0[t]
            grad[l * ns + t] = acc
    grad[nD] = lam_a / beta
    grad[nD + 1] = gw * w_r
    return energy, grad

