r"""Forced, damped periodic responses by harmonic balance, uncondensed and condensed onto the elements.

The model, excited by a cosine force f(t) = f cos(omega t) (f (n,) in N), with viscous damping, in
mass-normalised modal coordinates x = Phi q (``model/modal.py``):

    q'' + C_q q' + Omega^2 q + Bq^T g(Bq q) = Phi^T f cos(omega t),

C_q = diag(2 zeta_k w_k) (modal damping; ratios zeta_k) plus Phi^T C Phi for a damping matrix C.  The
forcing fixes the time origin: there is no phase condition and no free time shift, and a damped forced
orbit is not symmetric in time (its displacement has sine terms), so the NNMs' "odd" cosine basis does
not apply.  Bases (``ForcedBasis``):

* ``"full"``: the mean and cos(h theta), sin(h theta), h = 1..H (theta = omega t): any periodic response;
* ``"odd"``: cos and sin of the odd harmonics 1, 3, ..., <= H.  For odd element forces (f_nl(-x) = -f_nl(x))
  and a force at the fundamental only, the half-wave symmetric responses x(t + T/2) = -x(t) satisfy the
  full equations exactly with only odd harmonics: the same orbits at half the unknowns.  It misses the
  responses that break that symmetry (a symmetry-breaking bifurcation, rare for cubic springs; Hill's
  method in the full basis flags the orbits where one starts).

**Uncondensed** (``ForcedHBProblem``): the Galerkin equations for the modal coefficients A (N_b, n),
c_j = cos or sin(h_j theta), D_theta the derivative matrix of the basis (``hill.derivative_matrix``):

    R = (Omega^2 - h^2 omega^2) A + omega (D_theta A) C_q^T + P g(E A Bq^T) Bq - delta_{j, cos 1} Phi^T f = 0

Unknowns u = [A.ravel() (sqrt(kg) m); omega / w_ref]; residuals / w_ref^2 (units of A).  n N_b equations
in n N_b + 1 unknowns: a curve in (A, omega), continued in the arclength (``continuation/engine.py``).

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

**Stability** (``damped_hill_multipliers``): Hill's method as in ``hill.py`` with the damping terms,
(D^2 + C D + K_h) a + lambda (2 D + C) a + lambda^2 a = 0, D = omega D_theta (x) I, C = I (x) C_q;
the 2n exponents of smallest wave-number centroid kept, mu = exp(lambda T).  A forced orbit has no
trivial pair (no free time shift).  Cheaper, and for any model size: the **fold test**
(``fold_sign``), the sign of det dR/d(unknowns) at fixed omega.  dR/dA at fixed omega is Hill's matrix
L(lambda) at lambda = 0, whose determinant is positive for lambda -> +inf; it is negative exactly when an
odd number of real multipliers exceeds 1, which happens through the folds of the curve (saddle-node),
the usual loss of stability of forced responses.  The condensed Jacobian has the same sign (det dR/dA =
det(dynamic stiffness) det(I + G C), the first positive with damping).  It does not see instabilities
through a complex pair (Neimark-Sacker) or -1 (period doubling).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from .condensed_hb import LinearPart
from .hb_basis import HBBasis
from .hill import derivative_matrix

__all__ = ["FORCED_BASES", "ForcedBasis", "ForcedHBProblem", "CondensedForcedHBProblem", "damped_hill_multipliers"]

#: bases of forced responses: "full" (mean, cos and sin of 1..H), "odd" (cos and sin of odd harmonics)
FORCED_BASES = ("full", "odd")


class ForcedBasis(HBBasis):
    """Harmonic basis of forced responses: orders h (N_b,), sine (N_b,) bool, E (N, N_b), P (N_b, N).

    kind "full": 1, cos 1, sin 1, ..., cos H, sin H; kind "odd": cos 1, sin 1, cos 3, sin 3, ... (odd
    harmonics <= H).  Each sine follows the cosine of its order (what ``hill.derivative_matrix`` needs).
    """

    def __init__(self, harmonics, kind="full", samples=None):
        H = int(harmonics)
        if kind not in FORCED_BASES:
            raise ValueError(f"kind must be one of {FORCED_BASES}, got {kind!r}")
        orders = np.arange(1, H + 1) if kind == "full" else np.arange(1, H + 1, 2)
        self.h = np.repeat(orders, 2)
        self.sine = np.tile([False, True], len(orders))
        if kind == "full":
            self.h = np.concatenate([[0], self.h])
            self.sine = np.concatenate([[False], self.sine])
        self.kind = kind
        self.harmonics = H
        self.samples = int(samples) if samples is not None else 4 * H + 4
        theta = 2.0 * np.pi * np.arange(self.samples) / self.samples
        self.E = self.functions(theta)
        w = np.where(self.h == 0, 1.0, 2.0) / self.samples
        self.P = self.E.T * w[:, None]

    @property
    def cos1(self):
        """Index of cos(theta)."""
        return int(np.flatnonzero((self.h == 1) & ~self.sine)[0])

    def pairs(self):
        """(h, j_cos, j_sin) of every harmonic h >= 1, and the index of the mean (None without one)."""
        jc = np.flatnonzero((self.h > 0) & ~self.sine)
        mean = np.flatnonzero(self.h == 0)
        return [(int(self.h[j]), int(j), int(j) + 1) for j in jc], (int(mean[0]) if len(mean) else None)


def _max_step(wp, max_rel_state, max_rel_freq):
    """Largest step along a scaled tangent wp whose last entry is the frequency's (as shooting's
    balanced_max_step, with a margin of 0.8 on the frequency)."""
    return min(max_rel_state / max(np.linalg.norm(wp[:-1]), 1e-300), 0.8 * max_rel_freq / max(abs(wp[-1]), 1e-300))


class _ForcedProtocol:
    """What the uncondensed and condensed forced problems share: packing of omega, the engine's
    step norm and step limits, the force scale ``load`` (1: the given force; the start ramps it)."""

    load = 1.0

    def error(self, u, r):
        """Relative residual ||r|| / ||unknown coefficients|| (both in the same units)."""
        return float(np.linalg.norm(r) / max(np.linalg.norm(u[:-1]), 1e-300))

    def accept(self, u, J):
        pass

    def scale(self, u):
        """Weights of the balanced step norm: 1 / |coefficients| on those, 1 / (omega / w_ref) on the frequency."""
        s = np.full(len(u), 1.0 / max(np.linalg.norm(u[:-1]), 1e-300))
        s[-1] = 1.0 / abs(u[-1])
        return s

    def max_step(self, u, p):
        return _max_step(self.scale(u) * p, self.max_rel_step, self.max_rel_freq_step)

    def check_step(self, u_old, u_new):
        change = abs(u_old[-1] / u_new[-1] - 1)
        if change > self.max_rel_freq_step:
            return f"the frequency changed by {100 * change:.2f} % in one step"
        return ""

    def frequency(self, u):
        """omega (rad/s) of u."""
        return float(u[-1] * self.w_ref)

    def with_frequency(self, u, omega):
        v = np.array(u, dtype=float)
        v[-1] = omega / self.w_ref
        return v

    def solve_at_frequency(self, u, tol, max_iter=30):
        """Newton at the fixed frequency of u from u: (u, converged)."""
        u = np.array(u, dtype=float)
        for _ in range(max_iter):
            r, J = self.jacobian(u)
            if not np.all(np.isfinite(r)):
                return u, False
            if self.error(u, r) < tol:
                return u, True
            try:
                du = np.linalg.solve(J[:, :-1], -r)
            except np.linalg.LinAlgError:
                return u, False
            u[:-1] += du
        r = self.residual(u)
        return u, bool(np.all(np.isfinite(r)) and self.error(u, r) < tol)

    def fold_sign(self, J):
        """Sign (+1 / -1; 0 if singular) of det dR/d(coefficients) at fixed frequency (module docstring)."""
        sign, _ = np.linalg.slogdet(J[:, :-1])
        return int(sign)


class ForcedHBProblem(_ForcedProtocol):
    """Uncondensed forced harmonic balance (module docstring), for ``continuation.pseudo_arclength``.

    system : ModalSystem; basis : ForcedBasis; force_q (n,) modal force Phi^T f (N / sqrt(kg));
    damping_q : (n,) modal damping coefficients c_k = 2 zeta_k w_k (1/s) or an (n, n) modal damping
    matrix; w_ref : reference angular frequency (rad/s) of the unknown omega / w_ref.
    """

    def __init__(self, system, basis, force_q, damping_q, w_ref, max_rel_step=0.2, max_rel_freq_step=0.01):
        self.sys = system
        self.n = system.n
        self.basis = basis
        self.nb = len(basis)
        self.fq = np.asarray(force_q, dtype=float)
        c = np.asarray(damping_q, dtype=float)
        self.Cq = c if c.ndim == 2 else np.diag(c)
        self.c_diag = None if c.ndim == 2 else c
        self.w_ref = float(w_ref)
        self.h2 = (basis.h.astype(float) ** 2)[:, None]
        self.Dm = derivative_matrix(basis)
        self.cos1 = basis.cos1
        self.max_rel_step = max_rel_step
        self.max_rel_freq_step = max_rel_freq_step

    # --------------------------------------------------------------- packing
    def pack(self, A, omega):
        return np.concatenate([np.asarray(A, dtype=float).ravel(), [omega / self.w_ref]])

    def unpack(self, u):
        return u[:-1].reshape(self.nb, self.n), u[-1] * self.w_ref

    def modal_coefficients(self, u):
        """(A (N_b, n) modal Fourier coefficients, omega rad/s) of the orbit u."""
        A, w = self.unpack(u)
        return A.copy(), w

    def linear_start(self, omega):
        """u of the linear response (no elements) at omega."""
        A = _linear_modal_response(self.sys.omega2, self.Cq, self.fq, omega, self.basis) * self.load
        return self.pack(A, omega)

    def _damp(self, V):
        return V * self.c_diag[None, :] if self.c_diag is not None else V @ self.Cq.T

    # --------------------------------------------------------------- equations
    def _parts(self, u):
        A, w = self.unpack(u)
        s = self.sys
        d = self.basis.E @ (A @ s.Bq.T)
        F = self.basis.P @ (s.force(d) @ s.Bq)
        V = self.Dm @ A
        R = (s.omega2[None, :] - self.h2 * w * w) * A + w * self._damp(V) + F
        R[self.cos1] -= self.load * self.fq
        return A, w, d, V, R.ravel() / self.w_ref ** 2

    def residual(self, u):
        return self._parts(u)[-1]

    def jacobian(self, u):
        A, w, d, V, r = self._parts(u)
        s, bs, nb, n = self.sys, self.basis, self.nb, self.n
        C = bs.galerkin(s.tangent(d))
        J = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
        J[np.diag_indices(nb * n)] += (s.omega2[None, :] - self.h2 * w * w).ravel()
        J += w * np.kron(self.Dm, self.Cq)
        J /= self.w_ref ** 2
        dw = (-2.0 * self.h2 * w * A + self._damp(V)).ravel() / self.w_ref
        return r, np.hstack([J, dw[:, None]])


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
    def pack(self, D, omega):
        return np.concatenate([np.asarray(D, dtype=float).ravel(), [omega / self.w_ref]])

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
        C = bs.galerkin(self.sys.tangent(d))          # dF[j, s] / dD[l, s]
        nD = nb * ns
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


def _linear_modal_response(omega2, Cq, fq, omega, basis):
    """Modal coefficients (N_b, n) of the linear response to Phi^T f cos(omega t)."""
    n = len(omega2)
    Z = np.diag(omega2 - omega * omega) + 1j * omega * np.asarray(Cq)
    a = np.linalg.solve(Z, fq.astype(complex))
    A = np.zeros((len(basis), n))
    A[basis.cos1], A[basis.cos1 + 1] = a.real, -a.imag
    return A


def damped_hill_multipliers(system, basis, A, omega, damping_q, harmonics=None):
    """Floquet multipliers (2n,) of the forced orbit with modal coefficients A (N_b, n) on ``basis`` at
    omega (rad/s), damping_q (n,) modal damping coefficients or (n, n) modal damping matrix: Hill's
    method with damping (module docstring), largest modulus first.  O((2 n (2H + 1))^3)."""
    s, n = system, system.n
    H = int(harmonics or basis.harmonics)
    bp = HBBasis(H, "full", max(4 * H + 4, 2 * basis.harmonics + 2 * H + 2))
    theta = 2 * np.pi * np.arange(bp.samples) / bp.samples
    d = basis.functions(theta) @ (A @ s.Bq.T)
    nb = len(bp)
    Cmat = np.diag(damping_q) if np.ndim(damping_q) == 1 else np.asarray(damping_q)
    C = bp.galerkin(s.tangent(d))
    Kh = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
    Kh[np.diag_indices(nb * n)] += np.tile(s.omega2, nb)
    D = np.kron(derivative_matrix(bp), np.eye(n)) * omega
    Ch = np.kron(np.eye(nb), Cmat)
    m = nb * n
    L = np.zeros((2 * m, 2 * m))
    L[:m, m:] = np.eye(m)
    L[m:, :m] = -(D @ D + Ch @ D + Kh)
    L[m:, m:] = -(2.0 * D + Ch)
    lam, V = sla.eig(L, check_finite=False)
    a = V[:m].reshape(nb, n, -1)
    ac, as_ = a[1::2], a[2::2]
    w_pos = (np.abs(ac - 1j * as_) ** 2).sum(axis=1)
    w_neg = (np.abs(ac + 1j * as_) ** 2).sum(axis=1)
    total = 4 * (np.abs(a[0]) ** 2).sum(axis=0) + (w_pos + w_neg).sum(axis=0)
    centroid = (bp.h[1::2] @ (w_pos - w_neg)) / np.maximum(total, 1e-300)
    keep = np.argsort(np.abs(centroid), kind="stable")[:2 * n]
    mu = np.exp(lam[keep] * 2 * np.pi / omega)
    return mu[np.argsort(-np.abs(mu), kind="stable")]
