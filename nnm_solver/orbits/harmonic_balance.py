r"""Harmonic-balance residual and analytic Jacobian by AFT (alternating frequency/time).

The harmonic-balance periodic-orbit problem (the user-level description is in ``hb.py``).  In mass-normalised
modal coordinates x = Phi q (Phi^T M Phi = I, Phi^T K Phi = Omega^2) the model reads

    q'' + Omega^2 q + Bq^T g(Bq q) = 0,         Bq = B Phi   (n_s, n),

with d = Bq q (m) the n_s spring deformations.  Ansatz, with theta = omega t (omega in rad/s):

    q(t) = sum_j A[j] c_j(theta),     c_j = cos(h_j theta) or sin(h_j theta),   A: (N_b, n).

Because c_j'' = -(h_j omega)^2 c_j, the Galerkin (harmonic-balance) equations are

    R[j] = (Omega^2 - h_j^2 omega^2) A[j] + F[j] = 0          (N/sqrt(kg), per basis function j)
    F    = P g(E A Bq^T) Bq,        g(d): the element force laws   (AFT)

where E[k, j] = c_j(theta_k) at N equispaced samples theta_k = 2 pi k / N and P is the
Galerkin projector (rows (2/N) c_j(theta_k), (1/N) for the constant), so that P E = I.  The
cubic of a series of order h_max has order 3 h_max, so the projection is exact (no aliasing)
when N > 4 h_max.  Only the n_s spring deformations are sampled in time.

Analytic Jacobian (chain rule through E and P):
    dF[j, i] / dA[l, m] = sum_s Bq[s, i] C_s[j, l] Bq[s, m],   C_s = P diag(g_s'(d_s(theta_k))) E
    dR[j] / domega      = -2 h_j^2 omega A[j].

Bases: ``"odd"`` = cos(h theta), h = 1, 3, 5, ... <= h_max.  The symmetric NNMs of odd (cubic)
nonlinearities satisfy q(-t) = q(t) and q(t + T/2) = -q(t), so this basis holds them exactly and
fixes the time origin at an instant of zero velocity: no phase condition is needed.
``"full"`` = 1, cos(h theta), sin(h theta), h = 1..h_max: general periodic orbits; then the phase
condition <q_ref, q'(0)> / omega = sum_j h_j <q_ref, A[j]> (sine terms) = 0, with q_ref the
displacement of the previous point, makes t = 0 an extremum of the motion along q_ref (as in
shooting).  Its rows are then redundant by one (energy balance), which the least-squares
corrector of the continuation tolerates.

Unknowns (scaled): u = [A.ravel() (sqrt(kg) m) ; omega / w_r] with w_r the linear angular
frequency of the continued mode; residuals are divided by w_r^2 (units of A).
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.newton import NOT_FINITE, NewtonSettings, newton_solve
from ..integrators.registry import record_orbit
from ..stability.floquet import without_nearest_to_one
from .hb_basis import BASES, HBBasis, harmonics_in  # noqa: F401
from .hb_error import HBTruncationError
from .hill import hill_multipliers


class HBProblem(HBTruncationError):
    """Harmonic-balance equations of one NNM branch, for ``continuation.pseudo_arclength``; ``frequency_error``
    (hb_error.py) estimates a converged orbit's truncation error."""

    #: the route of Hill's method for the multipliers (hill.HILL_METHODS: "auto", "dense", "structured")
    hill_method = "auto"

    def __init__(self, system, mode_index, basis, max_rel_step=0.4, max_rel_period_step=np.inf):
        self.sys = system
        self.n = system.n
        self.mode_index = int(mode_index)
        self.basis = basis
        self.nb = len(basis)
        self._width = self.n                           # columns of the coefficient block (hb_error.py)
        self.w_r = float(np.sqrt(system.omega2[mode_index]))
        self.h2 = (basis.h.astype(float) ** 2)[:, None]
        self.phase = basis.kind == "full"
        self.q_ref = np.zeros(self.n)
        self.q_ref[mode_index] = 1.0
        self.max_rel_step = max_rel_step
        self.max_rel_period_step = max_rel_period_step

    # --------------------------------------------------------------- packing
    def with_basis(self, basis):
        """The same branch's equations with another HBBasis (the same step limits)."""
        return HBProblem(self.sys, self.mode_index, basis, self.max_rel_step, self.max_rel_period_step)

    def pack(self, A, omega):
        return np.concatenate([np.asarray(A, dtype=float).ravel(), [omega / self.w_r]])

    def unpack(self, u):
        return u[:-1].reshape(self.nb, self.n), u[-1] * self.w_r

    def from_family(self, other, u):
        """u of this problem for the orbit u of a condensed problem ``other`` of the same system
        (condensed_hb.py; the harmonics this basis has)."""
        A, w, _, _ = other.amplitudes(u)
        return self.pack(harmonics_in(self.basis, other.basis, A), w)

    def initial_state(self, u):
        """Modal displacement and velocity at t = 0: (q0, v0)."""
        A, w = self.unpack(u)
        c0, s0 = self.basis.state_at_zero()
        return c0 @ A, w * (s0 @ A)

    # --------------------------------------------------------------- results (driver protocol)
    def state(self, u):
        """(q0, v0, T) of the orbit u: modal initial state and period (s)."""
        q0, v0 = self.initial_state(u)
        return q0, v0, 2 * np.pi / self.unpack(u)[1]

    def multipliers(self, u, tangent=None):
        """Floquet multipliers of the orbit u by Hill's method (hill.py; route: ``hill_method``), the two nearest
        to +1 (the trivial pair) set to exactly 1."""
        return without_nearest_to_one(hill_multipliers(self, u, method=self.hill_method))

    def coefficients(self, u):
        """Fourier coefficients A (N_b, n) of the orbit u, modal (sqrt(kg) m)."""
        return self.unpack(u)[0].copy()

    def modal_orbit(self, u, samples=None):
        """Modal displacements (samples, n) of the orbit u over one period (default: the AFT samples)."""
        samples = samples or max(self.basis.samples, 4 * self.basis.harmonics + 4)
        theta = 2 * np.pi * np.arange(samples) / samples
        return self.basis.functions(theta) @ self.unpack(u)[0]

    def energy_gradient(self, u):
        """dE/du (J per unit of u) of the energy at t = 0, E = |v0|^2 / 2 + q0^T Omega^2 q0 / 2 + V(Bq q0) with
        q0 = sum_j c_j(0) A[j] and v0 = omega sum_j c_j'(0) A[j]: dE/dA[j] = c_j(0) (Omega^2 q0 + Bq^T g(Bq q0)) +
        omega c_j'(0) v0, dE/d(omega / w_r) = w_r |v0|^2 / omega."""
        A, w = self.unpack(u)
        c0, s0 = self.basis.state_at_zero()
        q0, v1 = c0 @ A, s0 @ A                                    # v0 = omega v1
        s = self.sys
        f = s.omega2 * q0 + s.force((s.Bq @ q0)[None])[0] @ s.Bq
        gA = np.outer(c0, f) + (w * w) * np.outer(s0, v1)
        return np.concatenate([gA.ravel(), [self.w_r * w * (v1 @ v1)]])

    def energy_gradient_fd(self, u, h=1e-7):
        """dE/du by central differences (J per unit of u): for problems whose energy has no closed-form gradient
        (CondensedHBProblem), and to check energy_gradient."""
        g = np.zeros(len(u))
        for i in range(len(u)):
            e = np.zeros(len(u))
            e[i] = h * max(abs(u[i]), np.linalg.norm(u[:-1]) / np.sqrt(len(u)), 1e-300)
            g[i] = (self.energy(u + e) - self.energy(u - e)) / (2 * e[i])
        return g

    # --------------------------------------------------------------- problem protocol
    def _parts(self, u):
        A, w = self.unpack(u)
        s = self.sys
        d = self.basis.E @ (A @ s.Bq.T)                       # (N, n_s) spring deformations
        F = self.basis.P @ (s.force(d) @ s.Bq)                # (N_b, n) nonlinear force coefficients
        R = (s.omega2[None, :] - self.h2 * w ** 2) * A + F
        r = R.ravel() / self.w_r ** 2
        if self.phase:
            r = np.concatenate([r, [(self.basis.h * self.basis.sine) @ A @ self.q_ref]])
        return A, w, d, r

    def residual(self, u):
        return self._parts(u)[3]

    def jacobian(self, u):
        A, w, d, r = self._parts(u)
        s, bs, nb, n = self.sys, self.basis, self.nb, self.n
        C = bs.galerkin(s.tangent(d))
        J = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
        if s.elements.coupled:                                 # coupled elements: full tangent blocks (model/coupled.py)
            J += bs.galerkin_matrix(s.coupled_stiffness(d))
        J[np.diag_indices(nb * n)] += (s.omega2[None, :] - self.h2 * w ** 2).ravel()
        J /= self.w_r ** 2
        dw = (-2.0 * self.h2 * w * A).ravel() / self.w_r        # d r / d(omega / w_r)
        J = np.hstack([J, dw[:, None]])
        if self.phase:
            row = np.zeros(nb * n + 1)
            row[:-1] = np.outer(bs.h * bs.sine, self.q_ref).ravel()
            J = np.vstack([J, row])
        return r, J

    def error(self, u, r):
        """Relative residual ||r|| / ||A|| (r: R / w_r^2 and the phase row, both in units of A)."""
        return float(np.linalg.norm(r) / max(np.linalg.norm(u[:-1]), 1e-300))

    def accept(self, u, J):
        q0 = self.initial_state(u)[0]
        nrm = np.linalg.norm(q0)
        if nrm > 0:
            self.q_ref = q0 / nrm

    def scale(self, u):
        """Weights of the balanced step norm: 1 / |A| on the coefficients, w_r / omega on the frequency."""
        x = u[:-1]
        w = np.empty(len(u))
        w.fill(1.0 / max(math.sqrt(float(x.dot(x))), 1e-300))    # (np.linalg.norm's number; np.full's array)
        w[-1] = 1.0 / u[-1]
        return w

    def max_step(self, u, p):
        """Largest step along p (scaled units): coefficients change by at most max_rel_step and the
        frequency by at most max_rel_period_step (relative)."""
        from .shooting import balanced_max_step
        return balanced_max_step(self.scale(u) * p, self.max_rel_step, self.max_rel_period_step)

    def check_step(self, u_old, u_new):
        change = abs(u_old[-1] / u_new[-1] - 1)
        if change > self.max_rel_period_step:
            return f"the period changed by {100 * change:.2f} % in one step"
        return ""

    def energy(self, u):
        """Energy (J) of the orbit u at t = 0 (constant along an HB orbit only to its truncation: energy_spread)."""
        q0, v0 = self.initial_state(u)
        return self.sys.energy(q0, v0)

    def energy_spread(self, u, samples=None):
        """max - min over one period (J) of the energy along the HB orbit u: zero for an exact periodic orbit of the
        conservative system, so a measure of what the truncation leaves of the energy's definition (~1e-9 relative
        on a resolved branch, 1e-3 to 3e-2 inside internal-resonance tongues at H = 5).  Events whose energies
        differ by less than this cannot be told apart by this orbit (stability.events)."""
        # (8H + 8 samples resolve E(t) of a cubic spring's orbit exactly; its max - min from them falls ~2 % short
        # of the true one (2-DOF at 20 J), 4x as many ~0.1 %: short, so never more merging than the truncation says)
        samples = samples or 32 * self.basis.harmonics + 32
        theta = 2 * np.pi * np.arange(samples) / samples
        A, w = self.unpack(u)
        q = self.basis.functions(theta) @ A
        v = w * (self.basis.derivatives(theta) @ A)
        s = self.sys
        E = 0.5 * (v * v).sum(axis=1) + 0.5 * (q * q) @ s.omega2 + s.elements.potential(q @ s.Bq.T).sum(axis=1)
        return float(E.max() - E.min())


def series_orbit(basis, X, period, samples):
    """Orbit of a Fourier series: (x, v) (samples, n) at t = k T / samples, from coefficients X (N_b, n)."""
    theta = 2 * np.pi * np.arange(int(samples)) / int(samples)
    return basis.functions(theta) @ X, (2 * np.pi / period) * (basis.derivatives(theta) @ X)


def recover_coefficients(system, mode_index, basis, x0, v0, period, tol):
    """Fourier coefficients X (N_b, n) (physical, m) of the HB orbit through (x0, v0) with period T.

    For branches stored without their coefficients (files of the first release): the orbit is
    integrated with Newmark at 16 steps per AFT sample and projected on the basis (a close first
    guess), then refined by Gauss-Newton on the HB equations plus the point's initial state.
    Raises RuntimeError if the refined series does not satisfy the HB equations to 10 tol.
    """
    problem = HBProblem(system, mode_index, basis)
    q0, v0 = system.to_modal(x0), system.to_modal(v0)
    problem.q_ref = q0 / max(np.linalg.norm(q0), 1e-300)
    sub = 16
    Q, _, _ = record_orbit(system, q0, v0, period, basis.samples * sub)
    u = problem.pack(basis.P @ Q[:-1:sub], 2 * np.pi / period)
    res = newton_solve(_ThroughState(problem, q0, v0), u, NewtonSettings(tol=0.0, max_iter=30, positive_last=False),
                       stop=_round_off_step)
    u = res.u
    if res.reason == NOT_FINITE or not problem.error(u, problem.residual(u)) < 10 * tol:
        raise RuntimeError("the harmonic-balance coefficients could not be recomputed")
    return system.to_physical(problem.unpack(u)[0])


def _round_off_step(k, u, du, u_new):
    """recover_coefficients' stopping rule: the Gauss-Newton step fell to round-off (1e-13 of the unknowns)."""
    return "the step fell to round-off" if np.linalg.norm(du) <= 1e-13 * np.linalg.norm(u_new) else ""


class _ThroughState:
    """The HB equations of ``problem`` with the rows of the orbit's initial state (q0, v0) appended (an
    over-determined system, solved by Gauss-Newton in continuation/newton.py): r0 = [c(0) A - q0;
    (omega c'(0) A - v0) / w_r]."""

    def __init__(self, problem, q0, v0):
        self.problem, self.q0, self.v0 = problem, q0, v0
        self.c0, self.s0 = problem.basis.functions([0.0])[0], problem.basis.derivatives([0.0])[0]

    def jacobian(self, u):
        p, n = self.problem, self.problem.n
        r, J = p.jacobian(u)
        A, w = p.unpack(u)
        r0 = np.concatenate([self.c0 @ A - self.q0, (w * (self.s0 @ A) - self.v0) / p.w_r])
        J0 = np.vstack([np.hstack([np.kron(self.c0, np.eye(n)), np.zeros((n, 1))]),
                        np.hstack([np.kron(self.s0, np.eye(n)) * w / p.w_r, (self.s0 @ A)[:, None]])])
        return np.concatenate([r, r0]), np.vstack([J, J0])

    def residual(self, u):
        return self.jacobian(u)[0]

    def error(self, u, r):
        return self.problem.error(u, r)
