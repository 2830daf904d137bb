r"""The energy of a condensed harmonic-balance orbit (condensed_hb.py) and its gradient in closed form.

The orbit u = [D; a beta; omega / w_r] has the modal amplitudes A[j, k] = -W[j, k] b_k . F[j] (A[cos 1, r] = a),
W[j, k] = 1 / (w_k^2 - h_j^2 omega^2) (zero for the followed mode r at the fundamental), F = P g(E D).  At t = 0,
q0 = sum_j c_j(0) A[j] and v0 = omega v1, v1 = sum_j c_j'(0) A[j], and its energy (J) is

    E = |v0|^2 / 2 + q0^T Omega^2 q0 / 2 + sum_s V_s(sum_j c_j(0) D[j, s])    (+ the left-out modes' share, below)

For a truncated basis (a Ritz basis: R0, R1, the residual flexibility of the modes left out) the left-out modes add
f0^T R0 f0 / 2 + f0^T R1 f1 + g^T R1 g / 2 with f0 = sum_j c_j(0) F[j], f1 = sum_j c_j(0) h_j^2 omega^2 F[j] and
g = omega sum_j c_j'(0) F[j] (their quasi-static displacement and velocity to first order in (omega / w_k)^2).

Its gradient, by the chain rule (``energy_gradient``), with Lambda = dE/dA = c(0) (Omega^2 q0)^T + omega^2 c'(0) v1^T:

    dE/dF[j]      = -(Lambda[j] * W[j]) Bq^T                    (+ the left-out modes' terms)
    dE/dD[l, t]   = sum_(j, u) dE/dF[j, u] dF[j, u]/dD[l, t]  + c_l(0) g_t(sum_j c_j(0) D[j])
    dE/da         = Lambda[cos 1, r]
    dE/domega     = omega |v1|^2 + sum_(j, k) Lambda[j, k] 2 h_j^2 omega W[j, k] A[j, k]   (+ left-out terms)

with dF/dD the Galerkin blocks of the element tangents (CondensedHBProblem.galerkin_blocks).  One evaluation costs
O(N_b n_s m + N_b^2 N n_d) like one energy, where the central differences it replaces (HBProblem.energy_gradient_fd)
cost 2 (N_b n_s + 2) energies; the two agree to the differences' own error (tests/test_per_point.py).
"""
from __future__ import annotations

import numpy as np

__all__ = ["condensed_energy", "condensed_energy_gradient"]


def _sym(R):
    return 0.5 * (R + R.T)


def condensed_energy(prob, u):
    """Energy (J) of the orbit u of the CondensedHBProblem prob (module docstring)."""
    A, w, F, Omega2 = prob.amplitudes(u)
    c0, s0 = prob.basis.state_at_zero()
    q0, v0 = c0 @ A, w * (s0 @ A)
    E = 0.5 * v0 @ v0 + 0.5 * q0 @ (prob.lin.omega2 * q0)
    D = prob.unpack(u)[0]
    E += float(np.sum(prob.sys.elements.potential(c0 @ D)))
    if not prob.lin.complete:
        # left-out modes: q_k(0) = -sum_j c_j(0) b_k . F_j / (w_k^2 - Omega2_j) to first order in Omega2 / w_k^2
        f0, f1 = c0 @ F, (c0 * Omega2) @ F
        E += 0.5 * (f0 @ prob.lin.R0 @ f0 + 2 * f0 @ prob.lin.R1 @ f1)
        g = w * (s0 @ F)
        E += 0.5 * g @ prob.lin.R1 @ g
    return float(E)


def condensed_energy_gradient(prob, u):
    """dE/du (J per unit of u) of ``condensed_energy`` in closed form (module docstring)."""
    D, a, w = prob.unpack(u)
    A, W, F, Omega2, d = prob.amplitude_parts(u)
    lin, c0, s0 = prob.lin, *prob.basis.state_at_zero()
    q0, v1 = c0 @ A, s0 @ A
    Lam = np.outer(c0, lin.omega2 * q0) + (w * w) * np.outer(s0, v1)          # dE/dA (N_b, m)
    gF = -(Lam * W) @ lin.Bq.T                                               # dE/dF through A (N_b, n_d)
    gw = w * (v1 @ v1) + float(np.sum(Lam * (2.0 * w * prob.h2)[:, None] * W * A))
    if not lin.complete:
        R0, R1, R1s = lin.R0, lin.R1, _sym(lin.R1)
        f0, f1, fs = c0 @ F, (c0 * Omega2) @ F, s0 @ F
        g = w * fs
        gf0 = _sym(R0) @ f0 + R1 @ f1                                        # dE/df0
        gf1 = R1.T @ f0                                                      # dE/df1
        gF += np.outer(c0, gf0) + np.outer(c0 * Omega2, gf1) + w * np.outer(s0, R1s @ g)
        gw += float(gf1 @ ((c0 * 2.0 * w * prob.h2) @ F)) + float(g @ R1s @ fs)
    gD = np.zeros_like(D)
    for rows, cols, C in prob.galerkin_blocks(d):                 # C[i, j, l] = dF[j, rows_i] / dD[l, cols_i]
        gD[:, cols] += np.einsum("ji,ijl->li", gF[:, rows], C)
    gD += np.outer(c0, prob.sys.force((c0 @ D)[None])[0])                      # the element potentials at t = 0
    return np.concatenate([gD.ravel(), [Lam[prob.cos1, prob.r] / prob.beta, gw * prob.w_r]])
