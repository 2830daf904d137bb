r"""Forced, damped periodic responses by harmonic balance condensed onto the elements (the uncondensed form, the
model and the bases: ``forced_hb.py``).

**Condensed** (``CondensedForcedHBProblem``; modal damping only): in complex form, with the harmonic h's
coefficients a_h = A_cos - i A_sin (x = Re sum a_h e^{i h theta}), every mode's amplitude is

    a[h, k] = (phi_k . f delta_{h, 1} - b_k . F_h) / z_hk,    z_hk = w_k^2 - h^2 omega^2 + i 2 zeta_k w_k h omega,

F_h the element force coefficients (N) and b_k = Bq[:, k] the element deformations of mode k.  The
elements' deformation coefficients D_h = sum_k b_k a[h, k] then obey n_s equations per harmonic:

    R_h = D_h - delta_{h,1} d_lin(omega) + G_h(omega) F_h(D) = 0,
    G_h = sum_k b_k b_k^T / z_hk  (complex, m/N),   d_lin = sum_k b_k (phi_k . f) / z_1k  (m),

d_lin being the linear structure's response at the elements; the mean (h = 0) has G_0 = sum b_k b_k^T /
w_k^2.  Unknowns u = [D.ravel() (m); omega / w_ref], residuals in m: N_b n_s + 1 numbers whatever n.  With
damping, z_hk never vanishes: no pole, unlike the conservative condensed HB (``condensed_hb.py``).  The
eliminated amplitudes follow exactly from the formula above, so both forms have the same solutions.
"""
from __future__ import annotations

import numpy as np

from .condensed_hb import LinearPart, coupled_galerkin
from .forced_hb import _ForcedProtocol

__all__ = ["CondensedForcedHBProblem"]


class CondensedForcedHBProblem(_ForcedProtocol):
    """Forced harmonic balance condensed onto the elements' deformations (module docstring), for
    ``continuation.pseudo_arclength``; modal damping only.

    system : ModalSystem (its elements' force laws); basis : ForcedBasis; force_q (m,) modal force;
    c_modal (m,) modal damping coefficients 2 zeta_k w_k (1/s); w_ref (rad/s); linear : the LinearPart
    (default: every mode of ``system``; a truncated one is not supported here).
    """

    def __init__(self, system, basis, force_q, c_modal, w_ref, linear=None, max_rel_step=0.2,
                 max_rel_freq_step=0.01):
        self.sys = system
        self.lin = linear or LinearPart(system.omega2, system.Bq, system.Phi)
        if not self.lin.complete:
            raise ValueError("the forced condensed HB needs a complete modal basis (no residual flexibility)")
        self.basis = basis
        self.nb = len(basis)
        self.Bq = self.lin.Bq
        self.ns = self.Bq.shape[0]
        self.n = system.n
        self.fq = np.asarray(force_q, dtype=float)
        self.c = np.asarray(c_modal, dtype=float)
        self.w_ref = float(w_ref)
        self.pair_list, self.mean = basis.pairs()
        self.hs = np.array([h for h, _, _ in self.pair_list], dtype=float)
        self.jc = np.array([j for _, j, _ in self.pair_list], dtype=int)
        self.js = self.jc + 1
        self.i1 = int(np.flatnonzero(self.hs == 1)[0])                 # the fundamental among the pairs
        self.cos1 = basis.cos1
        self.Bf = self.Bq * self.fq[None, :]                           # (n_s, m) b_k (phi_k . f)
        if self.mean is not None:
            with np.errstate(divide="ignore"):
                self.G0 = (self.Bq / self.lin.omega2[None, :]) @ self.Bq.T
        self.max_rel_step = max_rel_step
        self.max_rel_freq_step = max_rel_freq_step

    # --------------------------------------------------------------- packing
    def unpack(self, u):
        """(D (N_b, n_s) m, omega rad/s)."""
        return u[:-1].reshape(self.nb, self.ns), u[-1] * self.w_ref

    def _z(self, w):
        """z_hk (n_h, m) = w_k^2 - h^2 omega^2 + i c_k h omega, and dz/domega."""
        h = self.hs[:, None]
        z = self.lin.omega2[None, :] - (h * w) ** 2 + 1j * self.c[None, :] * h * w
        dz = -2.0 * h * h * w + 1j * self.c[None, :] * h
        return z, dz

    def linear_start(self, omega):
        """u of the linear response (no elements) at omega."""
        z, _ = self._z(omega)
        D = np.zeros((self.nb, self.ns))
        d = self.load * (self.Bf @ (1.0 / z[self.i1]))
        D[self.cos1], D[self.cos1 + 1] = d.real, -d.imag
        return self.pack(D, omega)

    # --------------------------------------------------------------- equations
    def _parts(self, u):
        D, w = self.unpack(u)
        z, dz = self._z(w)
        W = 1.0 / z
        G = self._flex(W)                                                      # (n_h, n_s, n_s) complex
        d = self.basis.E @ D
        F = self.basis.P @ self.sys.force(d)                                   # (N_b, n_s)
        Fh = F[self.jc] - 1j * F[self.js]
        Rh = (D[self.jc] - 1j * D[self.js]) + (G @ Fh[:, :, None])[:, :, 0]
        Rh[self.i1] -= self.load * (self.Bf @ W[self.i1])
        R = np.zeros((self.nb, self.ns))
        R[self.jc], R[self.js] = Rh.real, -Rh.imag
        if self.mean is not None:
            R[self.mean] = D[self.mean] + self.G0 @ F[self.mean]
        return D, w, z, dz, W, G, d, F, Fh, R.ravel()

    def _flex(self, W):
        """sum_k b_k b_k^T W[h, k] (n_h, n_s, n_s) for weights W (n_h, m)."""
        return (self.Bq[None, :, :] * W[:, None, :]) @ self.Bq.T

    def residual(self, u):
        return self._parts(u)[-1]

    def flexibility(self, G):
        """The real form of the flexibility: (N_b, n_s, N_b, n_s), R = D + this . F (harmonic blocks
        [[Re G, Im G], [-Im G, Re G]] on the (cos, sin) pairs, G_0 on the mean)."""
        nb, ns = self.nb, self.ns
        Gr = np.zeros((nb, ns, nb, ns))
        for i, (_, jc, js) in enumerate(self.pair_list):
            Gr[jc, :, jc, :] = G[i].real
            Gr[jc, :, js, :] = G[i].imag
            Gr[js, :, jc, :] = -G[i].imag
            Gr[js, :, js, :] = G[i].real
        if self.mean is not None:
            Gr[self.mean, :, self.mean, :] = self.G0
        return Gr

    def jacobian(self, u):
        D, w, z, dz, W, G, d, F, Fh, r = self._parts(u)
        bs, nb, ns = self.basis, self.nb, self.ns
        nD = nb * ns
        if self.sys.elements.coupled:                 # coupled elements: their tangent blocks (condensed_hb.py)
            Gr = self.flexibility(G)
            JD = np.zeros((nb, ns, nb, ns))
            for u_, t_, C_ in coupled_galerkin(bs, self.sys.elements, d):
                JD[:, :, :, t_] += np.einsum("jsak,kal->jslk", Gr[:, :, :, u_], C_)
            JD = JD.reshape(nD, nD)
        else:
            C = bs.galerkin(self.sys.tangent(d))          # dF[j, s] / dD[l, s]
            JD = np.einsum("jsat,tal->jslt", self.flexibility(G), C).reshape(nD, nD)
        JD[np.diag_indices(nD)] += 1.0
        dW = -dz * W * W                                                          # d(1/z) / domega
        dRh = (self._flex(dW) @ Fh[:, :, None])[:, :, 0]
        dRh[self.i1] -= self.load * (self.Bf @ dW[self.i1])
        dR = np.zeros((nb, ns))
        dR[self.jc], dR[self.js] = dRh.real, -dRh.imag
        return r, np.hstack([JD, (dR.ravel() * self.w_ref)[:, None]])

    # --------------------------------------------------------------- the eliminated amplitudes
    def modal_coefficients(self, u):
        """(A (N_b, m) modal Fourier coefficients of every mode, recovered exactly, omega rad/s)."""
        D, w = self.unpack(u)
        z, _ = self._z(w)
        F = self.basis.P @ self.sys.force(self.basis.E @ D)
        Fh = F[self.jc] - 1j * F[self.js]
        ah = -(Fh @ self.Bq) / z                                                 # (n_h, m)
        ah[self.i1] += self.load * self.fq / z[self.i1]
        A = np.zeros((self.nb, self.lin.m))
        A[self.jc], A[self.js] = ah.real, -ah.imag
        if self.mean is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                A[self.mean] = -(F[self.mean] @ self.Bq) / self.lin.omega2
        return A, w
