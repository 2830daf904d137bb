r"""Harmonic balance condensed exactly onto the nonlinear elements' coordinates.

The uncondensed equations (``harmonic_balance.py``), in mass-normalised modal coordinates, are for
every mode k and basis function j (harmonic h_j, frequency omega in rad/s)

    (w_k^2 - h_j^2 omega^2) A[j, k] + b_k . F[j] = 0,      F = P g(E D),   D[j] = sum_k b_k A[j, k]

with b_k = B phi_k (n_s,) the element deformations of mode k (column k of Bq) and D (N_b, n_s) the
Fourier coefficients of the element deformations d = B x (m).  The force coefficients F (N) depend on
the amplitudes only through D, so every amplitude but the followed mode r's fundamental is

    A[j, k] = -b_k . F[j] / (w_k^2 - h_j^2 omega^2)

and D obeys n_s equations per basis function (the dynamic flexibility of the linear structure at
the elements, G_j, times the element forces):

    R_D[j] = D[j] - delta_{j,cos 1} a b_r + G_j(omega) F[j] = 0,
    G_j(omega) = sum_{k, not (k = r and h_j = 1)} b_k b_k^T / (w_k^2 - h_j^2 omega^2)     (m/N)
    R_a[j]  = (w_r^2 - omega^2) alpha_j + b_r . F[j] = 0,   j with h_j = 1

with alpha_{cos 1} = a (sqrt(kg) m) the followed mode's fundamental amplitude (alpha_{sin 1} = 0 in
the full basis: its time origin, the phase condition).  Unknowns: D, a and omega, N_b n_s + 2 numbers
whatever the number of modes n; the eliminated amplitudes are recovered exactly by the formula above,
so the condensed and the uncondensed equations have the same solutions (the same branch to round-off)
wherever no h_j omega equals a w_k (an exact internal resonance, where the uncondensed amplitude A[j, k]
is free and the condensed equations have a pole).

The linear part (``LinearPart``) is the modes' (w_k^2, b_k, phi_k) and, for a truncated modal basis of a
large model (``LinearPart(omega2, Bq, R0=, R1=)``; the driver's large models take a Ritz basis instead,
model/ritz.py), the residual flexibility of the modes left out,
R0 + Omega^2 R1 with R0 = B (K^-1 - sum phi phi^T / w^2) B^T and R1 = B (K^-1 M K^-1 - sum phi phi^T / w^4) B^T:
exact at Omega = 0, relative error O((Omega / w_cut)^4) for the left-out modes above w_cut.

Coupled elements (model/coupled.py, one force on m deformations) take their m rows of B each; their tangent is an
m x m block instead of a diagonal entry, so their Jacobian is assembled from the full Galerkin blocks
(``coupled_galerkin``): the same equations, n_d = n_s + sum m deformations.

Unknowns (scaled, all in m): u = [D.ravel(); a beta; omega / w_r], beta = |b_r| (1 if mode r does not
deform the elements); residuals [R_D; R_a beta / w_r^2] in m.  Each evaluation costs
O(N_b n_s^2 m + N n_s N_b): nothing of order n^2.  For models of springs (no coupled element) the residual, the
Jacobian, the energy, its gradient and the amplitudes are compiled kernels (condensed_kernels.py: one pass over the
modes each, 10-35 us on the aircraft against 90-570 us for the numpy forms below, which coupled elements and an
installation without numba take); the two agree to round-off (tests/test_per_point_kernels.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.chord import residual_kernel
from ..stability.floquet import without_nearest_to_one
from . import condensed_energy_kernels as energy_kernels
from . import condensed_kernels as kernels
from . import condensed_numpy as numpy_forms
from .condensed_energy import condensed_energy, condensed_energy_gradient
from .condensed_linear import LinearPart, coupled_galerkin
from .harmonic_balance import HBProblem
from .hb_basis import harmonics_in
from .hb_error import HBTruncationError
from .hill import hill_multipliers

__all__ = ["LinearPart", "CondensedHBProblem"]


class CondensedHBProblem(HBTruncationError):
    """Condensed harmonic-balance equations of one NNM branch (module docstring), for the
    pseudo-arclength engine; the same protocol and the same orbits as ``HBProblem``.

    system : the ModalSystem (its elements' force laws; for a complete basis also its modes);
    linear : the LinearPart (default: every mode of ``system``, exact); r : the followed mode's index
    in it; basis : the HBBasis.
    """

    def __init__(self, system, r, basis, linear=None, max_rel_step=0.4, max_rel_period_step=np.inf):
        self.sys = system
        self.lin = linear or LinearPart(system.omega2, system.Bq, system.Phi)
        self.r = int(r)
        self.basis = basis
        self.nb = len(basis)
        self.ns = self.lin.Bq.shape[0]
        self._width = self.ns                          # columns of the coefficient block (hb_error.py)
        self.n = system.n
        self.w_r = float(np.sqrt(self.lin.omega2[self.r]))
        self.b_r = self.lin.Bq[:, self.r].copy()
        nrm = float(np.linalg.norm(self.b_r))
        self.beta = nrm if nrm > 0 else 1.0
        self.h2 = basis.h.astype(float) ** 2
        self.fund = np.flatnonzero(basis.h == 1)                      # cos 1 (and sin 1 in the full basis)
        self.cos1 = int(np.flatnonzero((basis.h == 1) & ~basis.sine)[0])
        self.max_rel_step = max_rel_step
        self.max_rel_period_step = max_rel_period_step
        self.q_ref = None
        self._last_parts = None                        # (u.tobytes(), amplitude_parts(u)) of the last orbit
        self._last_energy = ()                         # (u.tobytes(), energy, gradient or None) of the last 3 orbits
        self._Bq = np.ascontiguousarray(self.lin.Bq, dtype=float)
        self._kernel = kernels.kernel_arguments(self)  # the compiled kernels' constants, or None (numpy forms)
        #: the residual as a compiled kernel for the corrector's chord iterations (continuation/chord.py), or None
        self.residual_kernel = (None if self._kernel is None else
                                residual_kernel(kernels.chord_residual, self._kernel[0]))

    # --------------------------------------------------------------- packing
    def pack(self, D, a, omega):
        return np.concatenate([np.asarray(D, dtype=float).ravel(), [a * self.beta, omega / self.w_r]])

    def unpack(self, u):
        """(D (N_b, n_s) m, a sqrt(kg) m, omega rad/s)."""
        return u[:-2].reshape(self.nb, self.ns), u[-2] / self.beta, u[-1] * self.w_r

    energy_gradient_fd = HBProblem.energy_gradient_fd    # dE/du by central differences (a check of energy_gradient)

    def with_basis(self, basis):
        """The same branch's condensed equations with another HBBasis (the same LinearPart and step limits)."""
        return CondensedHBProblem(self.sys, self.r, basis, self.lin, self.max_rel_step, self.max_rel_period_step)

    def from_state(self, q0, v0, T):
        """u of a first guess from a modal state at rest (q0, v0 = 0) and a period T (s): its fundamental."""
        q0 = np.asarray(q0, dtype=float)
        D = np.zeros((self.nb, self.ns))
        D[self.cos1] = self.lin.Bq @ q0
        return self.pack(D, q0[self.r], 2 * np.pi / T)

    def from_family(self, other, u):
        """u of this problem for the orbit u of another condensed problem ``other`` of the same system (its
        harmonics that this basis has; the others are left out)."""
        A, w, _, _ = other.amplitudes(u)
        mine = harmonics_in(self.basis, other.basis, A)
        return self.pack(mine @ self.lin.Bq.T, mine[self.cos1, self.r], w)

    def start(self, a0):
        """u of the linear mode r at modal amplitude a0, and the direction of growing amplitude."""
        D = np.zeros((self.nb, self.ns))
        D[self.cos1] = a0 * self.b_r
        u0 = self.pack(D, a0, self.w_r)
        p0 = np.zeros_like(u0)
        p0[:-1] = u0[:-1] / a0
        return u0, p0

    # --------------------------------------------------------------- equations
    def residual(self, u):
        if self._kernel is not None:
            return kernels.residual_jacobian(np.asarray(u, dtype=float), False, *self._kernel[0])[0]
        return numpy_forms.residual_parts(self, u)[-1]

    def jacobian(self, u):
        if self._kernel is not None:
            return kernels.residual_jacobian(np.asarray(u, dtype=float), True, *self._kernel[0])
        return numpy_forms.jacobian_of(self, numpy_forms.residual_parts(self, u))

    def residual_parts(self, u):
        """The residual's intermediate results at u, its last item the residual: what ``jacobian_of`` needs (with
        the compiled kernels: u and the residual, the Jacobian's kernel evaluating both again)."""
        if self._kernel is not None:
            u = np.array(u, dtype=float)
            return u, self.residual(u)
        return numpy_forms.residual_parts(self, u)

    def jacobian_of(self, parts):
        """(r, J) from the parts of the residual already computed at u (``residual_parts``: e.g. where a Newton loop
        tested the residual first and needs the Jacobian only when it is not converged)."""
        if self._kernel is not None:
            return self.jacobian(parts[0])
        return numpy_forms.jacobian_of(self, parts)

    def error(self, u, r):
        """Relative residual ||r|| / ||(D, a beta)|| (both in m)."""
        x = u[:-1]
        return math.sqrt(float(r.dot(r))) / max(math.sqrt(float(x.dot(x))), 1e-300)   # np.linalg.norm's

    def accept(self, u, J):
        pass

    # the balanced step norm (1 / |(D, a beta)| on those, w_r / omega on the frequency) and the step limits
    # are harmonic balance's: the unknowns have the same layout, [coefficients; omega / w_r]
    scale = HBProblem.scale
    max_step = HBProblem.max_step
    check_step = HBProblem.check_step

    # --------------------------------------------------------------- the eliminated amplitudes
    def amplitude_parts(self, u):
        """(A, W, F, Omega2, d) of the orbit u: the modal Fourier coefficients A (N_b, m) in the LinearPart's modes
        (the eliminated amplitudes recovered exactly), the weights W (N_b, m; None where the compiled kernels compute
        the energy gradient), the element force coefficients F
        (N_b, n_d), Omega2 = (h_j omega)^2 and the sampled deformations d (N, n_d).  The last orbit's are kept (its
        state, coefficients, orbit, energy and energy gradient all start from them): read-only arrays."""
        key = u.tobytes() if isinstance(u, np.ndarray) else None
        last = self._last_parts
        if key is not None and last is not None and last[0] == key:
            return last[1]
        D, a, w = self.unpack(u)
        Omega2 = self.h2 * w * w
        if self._kernel is not None:              # A and F in one pass over the modes (condensed_kernels.py)
            eq = self._kernel[0]
            A, F = kernels.amplitudes(np.asarray(u, dtype=float), *eq[:6], self._Bq, self.lin.omega2, *eq[-5:])
            d = self.basis.E @ D
            # (W only for the numpy form of the energy gradient, which a truncated basis takes)
            W = self.lin.weights(Omega2, self.r, self.fund) if self._kernel[1] is None else None
        else:
            W = self.lin.weights(Omega2, self.r, self.fund)
            d, F = numpy_forms.forces(self, D)
            A = -W * (F @ self.lin.Bq)
            A[self.cos1, self.r] = a
        parts = (A, W, F, Omega2, d)
        for x in parts:
            if x is not None:
                x.setflags(write=False)
        self._last_parts = (key, parts) if key is not None else last
        return parts

    def amplitudes(self, u):
        """The modal Fourier coefficients A (N_b, m) of the orbit u in the LinearPart's modes (the
        eliminated amplitudes recovered exactly, read-only), the frequency omega (rad/s), the element force
        coefficients F (N_b, n_d) and Omega2 (N_b,) (rad/s)^2."""
        A, W, F, Omega2, d = self.amplitude_parts(u)
        return A, self.unpack(u)[2], F, Omega2

    def coefficients(self, u):
        """Fourier coefficients A (N_b, n) of the orbit u, modal (sqrt(kg) m), for a complete basis."""
        return self.amplitudes(u)[0] if self.lin.complete else None

    def state(self, u):
        """(q0, v0, T): modal initial state (complete basis) and period (s) of the orbit u."""
        A, w, _, _ = self.amplitudes(u)
        c0, s0 = self.basis.state_at_zero()
        return c0 @ A, w * (s0 @ A), 2 * np.pi / w

    def modal_orbit(self, u, samples=None):
        """Modal displacements (samples, m) over one period (default: the AFT samples)."""
        samples = samples or max(self.basis.samples, 4 * self.basis.harmonics + 4)
        if samples == self.basis.samples:          # the basis's own samples: its E (the same numbers)
            return self.basis.E @ self.amplitudes(u)[0]
        theta = 2 * np.pi * np.arange(samples) / samples
        return self.basis.functions(theta) @ self.amplitudes(u)[0]

    def energy(self, u):
        """Energy (J) of the orbit u: the modes' kinetic and linear potential energy at t = 0 plus the
        element potentials (and the left-out modes' share through R0, R1 for a truncated basis;
        condensed_energy.py)."""
        if self._kernel is not None and self._kernel[1] is not None:
            return self._energy_gradient(u, False)[0]
        return condensed_energy(self, u)

    def _energy_gradient(self, u, gradient):
        """(energy, dE/du or None) of u by the compiled kernel (the gradient only when asked), the last three orbits'
        kept: the engine's unseen-turns check asks for the energy of a step's end, then the gradient at its start (the
        iterator's energy slope there a step before, or two steps before when the step from there was refused), the
        truncation estimate and the iterator's energy slope for the end's in turn (the same numbers: one kernel call
        computes both; the energy does not depend on whether the gradient is made)."""
        key = u.tobytes() if isinstance(u, np.ndarray) else None
        kept = self._last_energy
        for last in kept:
            if last[0] == key and (last[2] is not None or not gradient):
                return last[1], last[2]
        E, g = energy_kernels.energy_gradient(np.asarray(u, dtype=float), gradient, *self._kernel[1])
        if not self._kernel[1][0]:
            E = float(E + np.sum(self.sys.elements.potential(self.basis.state_at_zero()[0] @ self.unpack(u)[0])))
        if gradient:
            g.setflags(write=False)
        else:
            g = None
        if key is not None:
            self._last_energy = tuple([x for x in kept[-2:] if x[0] != key]) + ((key, E, g),)
        return E, g

    def energy_and_gradient(self, u):
        """(energy J, dE/du): ``energy`` and ``energy_gradient`` of u, the same numbers, in one pass of the compiled
        kernel where there is one (the truncation estimate's bordered Newton needs both at each step)."""
        if self._kernel is not None and self._kernel[1] is not None:
            E, g = self._energy_gradient(u, True)
            return E, g.copy()
        return self.energy(u), self.energy_gradient(u)

    def galerkin_blocks(self, d):
        return coupled_galerkin(self.basis, self.sys.elements, d)      # (the element tangent's: condensed_energy.py)

    @property
    def gradient_with_energy(self):
        """Does the energy cost about as much with its gradient, both kept for the last three orbits (the compiled
        kernel: one pass makes both)?  Then the engine asks for both at a step's end, whose energy slope the branch
        iterator reads next (continuation.engine._Remembered)."""
        return self._kernel is not None and self._kernel[1] is not None

    #: the energy's slope along a tangent is g . p (continuation.engine.energy_slope): one gradient, about the cost
    #: of one energy with the compiled kernels, instead of two energies by central differences
    slope_from_gradient = True

    def energy_gradient(self, u):
        """dE/du (J per unit of u) in closed form (condensed_energy.py)."""
        if self._kernel is not None and self._kernel[1] is not None:
            return self._energy_gradient(u, True)[1].copy()
        return condensed_energy_gradient(self, u)

    def energy_spread(self, u):
        """max - min of the energy over one period (J), HBProblem.energy_spread of the reconstructed orbit (complete
        basis; None for a truncated one)."""
        if not self.lin.complete:
            return None
        full, uf = self.uncondensed(u)
        return full.energy_spread(uf)

    # --------------------------------------------------------------- stability
    def uncondensed(self, u):
        """(HBProblem, u) of the same orbit in the uncondensed equations (complete basis only)."""
        full = HBProblem(self.sys, self.r, self.basis)
        A, w, _, _ = self.amplitudes(u)
        return full, full.pack(A, w)

    def multipliers(self, u, tangent=None):
        """Floquet multipliers (2n,) by Hill's method on the reconstructed orbit: the uncondensed
        HB orbit's multipliers (hill.py), the trivial pair set to exactly 1."""
        full, uf = self.uncondensed(u)
        return without_nearest_to_one(hill_multipliers(full, uf))
