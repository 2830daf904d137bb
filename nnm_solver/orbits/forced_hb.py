r"""Forced, damped periodic responses by harmonic balance: the model, the bases, the uncondensed problem.

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

The same responses condensed onto the elements: ``forced_hb_condensed.py``; their stability by Hill's method
with damping and the fold test: ``forced_hill.py``.
"""
from __future__ import annotations

import numpy as np

from ..continuation.newton import NewtonSettings, newton_solve
from .hb_basis import HBBasis
from .hill import derivative_matrix

__all__ = ["FORCED_BASES", "ForcedBasis", "ForcedHBProblem"]

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

    def pack(self, X, omega):
        """u of the coefficients X (N_b, n or n_s) and omega (rad/s)."""
        return np.concatenate([np.asarray(X, dtype=float).ravel(), [omega / self.w_ref]])

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
        """Newton at the fixed frequency of u from u (continuation/newton.py, on the coefficients): (u, converged)."""
        res = newton_solve(self, u, NewtonSettings(tol, max_iter, positive_last=False), free=slice(0, -1))
        return res.u, res.converged

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
        if s.elements.coupled:                                 # coupled elements: full tangent blocks (model/coupled.py)
            J += bs.galerkin_matrix(s.coupled_stiffness(d))
        J[np.diag_indices(nb * n)] += (s.omega2[None, :] - self.h2 * w * w).ravel()
        J += w * np.kron(self.Dm, self.Cq)
        J /= self.w_ref ** 2
        dw = (-2.0 * self.h2 * w * A + self._damp(V)).ravel() / self.w_ref
        return r, np.hstack([J, dw[:, None]])


def _linear_modal_response(omega2, Cq, fq, omega, basis):
    """Modal coefficients (N_b, n) of the linear response to Phi^T f cos(omega t)."""
    n = len(omega2)
    Z = np.diag(omega2 - omega * omega) + 1j * omega * np.asarray(Cq)
    a = np.linalg.solve(Z, fq.astype(complex))
    A = np.zeros((len(basis), n))
    A[basis.cos1], A[basis.cos1 + 1] = a.real, -a.imag
    return A
