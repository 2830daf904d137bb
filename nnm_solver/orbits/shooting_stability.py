"""Floquet stability of shooting orbits: the multipliers from the sensitivity maps of the last accepted point.

The sensitivity sweep of a shooting Jacobian gives the map d[q; v](T/2 or T) / d[q0 (; v0)] at no extra cost
(kept as its two blocks, ``_maps``; ``accept`` keeps those of the accepted point).  Quarter-period shooting
(the default, shooting.py) sweeps only to T/4: the half-period block A11 is then made once at the accepted point,
when the multipliers are first asked for (``stability_maps``): from the quarter-period map of the Jacobian there by
the reversibility and symplecticity of the Gauss schemes' discrete map (ORBITS.half_map, gauss.reversible_half_block),
or by a sensitivity sweep over T/2.  Symmetric reversible orbits
(the default: odd forces, v0 = 0) need only its n x n block A11 = dq(T/2)/dq0, whose eigenvalues c give the
multipliers (floquet.reversible_spectrum); other orbits use the full 2n x 2n monodromy.  ``ShootingProblem``
inherits these methods.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, eigs

from ..stability.floquet import (collision_coordinates, coupled_modes, eigenvalues, nontrivial_multipliers,
                       reversible_blocks, reversible_from_eigenvalues, reversible_spectrum)
from .. import threads
from ..stability import settings as _stability_settings
from ..integrators.lowrank import DiagonalPlusLowRank
from ..threads import background
from .settings import ORBITS

__all__ = ["ShootingStability", "PendingSpectrum"]


#: an alias of settings.py's ORBITS.arpack_restarts (the code reads that)
ARPACK_RESTARTS = ORBITS.arpack_restarts


class ShootingStability:
    """Floquet multipliers, monodromy and collision coordinates of a ShootingProblem's last accepted point
    (attributes used: n, symmetric, reversible, all_columns, sys, unpack, _maps, _accepted_maps,
    accepted_u)."""

    @property
    def half_map(self):
        """d[q; v](end) / d[q0 (; v0)] (2n, n or 2n) at the last Jacobian evaluation, end = T/2 (half-period
        shooting) or T, or None (also for quarter-period shooting, whose Jacobian needs no velocity rows)."""
        return None if self._maps is None or self._maps[1] is None else np.vstack(self._maps)

    @property
    def accepted_map(self):
        """d[q; v](T/2 or T) / d[q0 (; v0)] (2n, n or 2n) at the last accepted point, or None (quarter-period
        shooting assembles the velocity rows only with all_columns)."""
        maps = self.stability_maps()
        return None if maps is None or maps[1] is None else np.vstack(maps)

    @property
    def stability_needs_jacobian(self):
        """Do the multipliers of the accepted point come from its latest Jacobian evaluation (so that it must be
        evaluated there)?  Not for quarter-period shooting: stability_maps sweeps them at the accepted point."""
        return not getattr(self, "quarter", False)

    def stability_maps(self):
        """(dq, dv)(T/2 or T) / d[q0 (; v0)] at the last accepted point: the blocks of the half-period (symmetric
        orbits) or full-period map.  Quarter-period shooting makes them here, once per accepted point: A11 from the
        quarter-period Jacobian's sweep at that point where the discrete map's reversibility gives it
        (_reversible_half_block), else one sensitivity sweep over T/2; None if that integration fails or no point was
        accepted."""
        maps = self._accepted_maps
        stale = maps is None or (self.all_columns and maps[0].shape[1] < 2 * self.n)
        if stale and getattr(self, "quarter", False) and hasattr(self, "accepted_u"):
            q0, v0, T = self.unpack(self.accepted_u)
            h, half = T / self.spp, self.spp // 2
            factored = getattr(self.integrator, "sensitivity_factors", None)
            rank = self.sys.Bq.shape[0] * self.integrator.stages * half        # n_s s N: the stages' deformations
            if not self.all_columns and factored and rank <= ORBITS.low_rank_share * self.n:
                out = factored(self.sys, q0, v0, h, half)       # diagonal + low rank (lowrank.py)
            else:
                out = None
            A11 = None if out is not None or self.all_columns else self._reversible_half_block()
            if A11 is not None:
                self._accepted_maps = (A11, None)
            elif out is not None:
                if out[-1]:
                    self._accepted_maps = (out[2].dense(), None)
                    self._accepted_factors = (out[2], self._accepted_maps[0])
            else:
                # the multipliers of reversible orbits need only dq(T/2)/dq0; the monodromy (all_columns): all
                out = self.integrator.sensitivity(self.sys, q0, v0, h, half, self.all_columns, self.all_columns)
                if out[-1]:
                    self._accepted_maps = (out[2], out[3])
        return self._accepted_maps

    def _reversible_half_block(self):
        """A11 of the accepted point from its quarter-period Jacobian's sweep (Integrator.reversible_half_block: the
        discrete map's reversibility and symplecticity, no sweep over the second quarter), or None: not the route
        (ORBITS.half_map), the latest Jacobian not at the accepted point, the scheme keeps no record, or the quarter
        residual |q(T/4)| above ORBITS.reversible_residual |q0| (the formula holds for q(T/4) = 0: its error is of the
        residual's order)."""
        last, stages = getattr(self, "_last_residual", None), getattr(self, "_stages", None)
        if (ORBITS.half_map != "reversible" or stages is None or last is None
                or not np.array_equal(last[0], self.accepted_u)):
            return None
        q0, _, T = self.unpack(self.accepted_u)
        if stages.nsteps != self.nsteps or stages.h != self._h(T):        # (the steps changed since: refinement)
            return None
        if not np.linalg.norm(last[1]) <= ORBITS.reversible_residual * np.linalg.norm(q0):
            return None
        return self.integrator.reversible_half_block(self.sys, stages, self._maps[0])

    def _low_rank_a11(self, maps):
        """The accepted point's A11 as a lowrank.DiagonalPlusLowRank when stability_maps kept that form for
        these maps, else None."""
        kept = getattr(self, "_accepted_factors", None)
        return kept[0] if kept is not None and kept[1] is maps[0] else None

    def multipliers(self, u, tangent=None):
        """Floquet multipliers of the accepted point u (from the exact monodromy of the last sweep),
        the trivial pair identified with the family tangent (u-space, optional) and set to 1."""
        return self.floquet_multipliers(None if tangent is None else self.unpack(tangent))

    def monodromy(self):
        """Monodromy (2n, 2n) of the last accepted point, in modal coordinates [q; v]."""
        if not self.all_columns:
            raise RuntimeError("the monodromy needs all sensitivity columns: set problem.all_columns = True")
        Mh = self.accepted_map
        return Mh @ Mh if self.symmetric else Mh

    def local_collision(self, tangent, shift, k=6):
        """The k collision coordinates (events.py) of the last accepted point nearest ``shift``, or None when
        this formulation has none: for symmetric reversible orbits the eigenvalues c of the deflated A11
        nearest shift, by shift-invert Arnoldi (an LU of the n x n matrix instead of its full eigenproblem,
        ~10x cheaper; with A11 kept as diagonal + low rank, an r x r LU: nearest_eigenvalues); used to follow
        one Krein collision during event location.  A complex shift (a complex pair's coordinate: far from the
        real axis, the pair is not among the k eigenvalues nearest its real part when the spectrum is dense
        there) takes a complex LU; if Arnoldi stalls there, the real part, then the full spectrum."""
        maps = self.stability_maps() if self.symmetric and self.reversible else None
        if maps is None:
            return None
        family = self.unpack(tangent)[0]
        deflated = np.linalg.norm(family) > 0
        low = self._low_rank_a11(maps) if self.n > 8 * k + 1 else None
        C, fixed = None, np.zeros(0)
        if low is not None:
            low = low.deflated(family) if deflated else low
        else:       # the coupled modes only (floquet.reversible_blocks); the others' eigenvalues are `fixed`
            C, _, fixed = reversible_blocks(maps[0][:, :self.n], family if deflated else None, self.coupled_modes)
            if C.shape[0] <= 8 * k:
                return np.concatenate([sla.eigvals(C, check_finite=False), fixed])
        # a complex shift far from a dense real spectrum (the pair has gone back to the axis) can stall Arnoldi:
        # then the shift's real part, and the full spectrum if that fails too
        # (a complex shift that stalled is not tried again: the follower asks with the same shift at every step)
        shifts = ([complex(shift)] if np.imag(shift) != 0 else []) + [float(np.real(shift))]
        for sigma in shifts:
            if isinstance(sigma, complex) and sigma == getattr(self, "_stalled_shift", None):
                continue
            c = nearest_eigenvalues(low if low is not None else C, sigma, k)
            if c is not None:       # with the decoupled modes' eigenvalues as near the shift as these
                return np.concatenate([c, fixed[np.abs(fixed - sigma) <= np.max(np.abs(c - sigma))]])
            if isinstance(sigma, complex):
                self._stalled_shift = sigma
        return np.concatenate([sla.eigvals(C if C is not None else low.dense(), check_finite=False), fixed])

    def local_eigenpairs(self, shift, k=6):
        """(c (k,), X (n, k)): the k eigenvalues of the accepted point's A11 = dq(T/2)/dq0 nearest ``shift`` and their
        right eigenvectors (complex, unit norm), for the Krein signatures of a cluster (krein_form); None unless the
        orbits are symmetric and reversible.  A11 is not deflated (its trivial eigenvalue -1 is among them when the
        shift is near it); only the coupled modes' block is solved (the decoupled modes' eigenvalues are its diagonal
        entries, their eigenvectors unit vectors: they take no part in a collision), by shift-invert Arnoldi where it
        is larger than 8 k (one LU of its size), else densely."""
        maps = self.stability_maps() if self.symmetric and self.reversible else None
        if maps is None:
            return None
        A11 = maps[0][:, :self.n]
        coupled = self.coupled_modes
        idx = np.arange(self.n) if coupled is None else np.asarray(coupled)
        B = A11[np.ix_(idx, idx)]
        k = min(int(k), B.shape[0])
        c = None
        if B.shape[0] > 8 * k:
            try:
                c, Y = eigs(B.astype(complex) if isinstance(shift, complex) else B, k=k, sigma=shift,
                            maxiter=ORBITS.arpack_restarts)
            except (ArpackNoConvergence, ArpackError, RuntimeError):
                c = None
        if c is None:
            c, Y = sla.eig(B, check_finite=False)
            near = np.argsort(np.abs(c - shift), kind="stable")[:k]
            c, Y = c[near], Y[:, near]
        X = np.zeros((self.n, len(c)), dtype=complex)
        X[idx] = Y / np.linalg.norm(Y, axis=0)
        return np.asarray(c, dtype=complex), X

    def krein_form(self, X):
        """F = X^H A21 X (p, p, Hermitian) at the accepted point for directions X (n, p) of q0 (e.g. eigenvectors of
        A11, local_eigenpairs), A21 = dv(T/2)/dq0 of the half-period map, or None (not a symmetric reversible orbit,
        or the sweep failed).

        The half-period map A = [[A11, A12], [A21, A22]] of a symmetric reversible orbit is symplectic (A^T J A = J)
        and reversible (R A R = A^-1, R = diag(I, -I)), so A21 is symmetric and A21 A11 = A11^T A21: A11 is
        self-adjoint in the (indefinite) form x^T A21 x.  For an eigenvalue c = cos(theta) of A11 (|c| < 1) with
        eigenvector x, A's eigenvector at lambda = c + i sqrt(1 - c^2) is z = [x; -i A21 x / sqrt(1 - c^2)] and its
        symplectic form -i z^H J z = -2 x^T A21 x / sqrt(1 - c^2): the Krein signature of the pair is -sign(x^T
        A21 x) (krein_signature.py).  Two real c collide and leave the axis only with opposite signatures.  Cost: one
        state sweep over T/2 and a Volterra solve of 2p columns (Integrator.directional), no n x n block."""
        if not (self.symmetric and self.reversible) or getattr(self, "accepted_u", None) is None:
            return None
        X = np.asarray(X, dtype=complex)
        p = X.shape[1]
        q0, v0, T = self.unpack(self.accepted_u)
        _, SvX, ok = self.integrator.directional(self.sys, q0, v0, T / self.spp, self.spp // 2,
                                                 np.column_stack([X.real, X.imag]))
        if not ok:
            return None
        F = X.conj().T @ (SvX[:, :p] + 1j * SvX[:, p:])
        return 0.5 * (F + F.conj().T)

    @property
    def coupled_modes(self):
        """Indices of the modes that see the nonlinear elements (floquet.coupled_modes), or None when all do: the
        multipliers' eigenproblem is of their size, the others' eigenvalues are their diagonal entries of A11.  All
        modes (None) on the dense reference route (stability.settings: STABILITY.krein_route)."""
        return None if _stability_settings.STABILITY.krein_route == "dense" else coupled_modes(self.sys.Bq)

    @property
    def background_spectrum(self):
        """Does multipliers_later compute the eigenvalues in the worker thread (symmetric reversible orbits of
        ORBITS.background_min_n or more modes; below, the thread's overhead exceeds the eigenproblem), with worker
        threads allowed (threads.WORKERS)?"""
        return bool(self.symmetric and self.reversible and self.n >= ORBITS.background_min_n and threads.WORKERS > 0)

    def multipliers_later(self, u, tangent=None):
        """The Floquet multipliers of the accepted point u (as ``multipliers``) computed in a worker thread
        (threads.background): a PendingSpectrum, called for (multipliers, collision coordinates) when needed.

        The maps are swept, and the matrix deflated, here: they belong to the problem's current state, which the
        continuation's next step changes.  Only the eigenvalue problem, which releases the GIL, runs beside that
        step.  Formulations other than the symmetric reversible one compute the multipliers now."""
        family = None if tangent is None else self.unpack(tangent)
        maps = self.stability_maps()
        if maps is None or not (self.symmetric and self.reversible):
            return PendingSpectrum(result=(self.floquet_multipliers(family), self.collision))
        C, deflated, fixed = reversible_blocks(maps[0][:, :self.n], None if family is None else family[0],
                                               self.coupled_modes)
        self.collision_per_modulus = 0.5
        return PendingSpectrum(job=background(eigenvalues, C), deflated=deflated, fixed=fixed)

    def floquet_multipliers(self, family=None):
        """Floquet multipliers (2n,) of the last accepted point.

        family : optional (dq0, dv0, dT) tangent of the family at that point; with it the trivial
        pair is identified and reported as exactly 1, 1 (floquet.py).  Symmetric reversible orbits
        (the default) need only an n x n eigenproblem (floquet.reversible_multipliers); otherwise the
        full 2n x 2n monodromy is deflated by the velocity and family directions.
        """
        if self.stability_maps() is None:       # the half-period sweep failed (quarter-period shooting)
            self.collision = None
            return np.full(2 * self.n, np.nan, dtype=complex)
        if self.symmetric and self.reversible:
            mu, self.collision = reversible_spectrum(self.stability_maps()[0][:, :self.n],
                                                     None if family is None else family[0], self.coupled_modes)
            self.collision_per_modulus = 0.5     # |mu| = |lambda|^2: c = a + ib gives |mu| - 1 = 2 b / sqrt(1 - a^2)
            return mu
        A = self.accepted_map
        Phi = A @ A if self.symmetric else A
        if family is None:
            mu = sla.eigvals(Phi, check_finite=False)
        else:
            q0, v0, _ = self.unpack(self.accepted_u)
            s = self.sys
            f = np.concatenate([v0, -s.omega2 * q0 - s.Bq.T @ s.force(s.Bq @ q0)])
            mu = nontrivial_multipliers(Phi, f, np.concatenate([family[0], family[1]]))
        # half-period maps square their eigenvalues: mu alone does not tell which pairs can collide
        self.collision = None if self.symmetric else collision_coordinates(mu)
        self.collision_per_modulus = 1.0
        return mu


def nearest_eigenvalues(A, sigma, k):
    """The k eigenvalues of A nearest sigma by shift-invert Arnoldi (at most ORBITS.arpack_restarts restarts), or None
    (the caller tries another shift or the full spectrum) when ARPACK fails or the shift sits on an eigenvalue.
    A is a dense matrix (an n x n LU, complex for a complex sigma) or a lowrank.DiagonalPlusLowRank (the
    Woodbury solve, no n x n LU; its Ritz pairs are checked against A: residuals above ORBITS.arnoldi_residual_tol
    relative to max(1, max |diag A|) give None)."""
    low = isinstance(A, DiagonalPlusLowRank)
    try:
        if not low:
            A = A.astype(complex) if isinstance(sigma, complex) else A
            return eigs(A, k=k, sigma=sigma, maxiter=ORBITS.arpack_restarts, return_eigenvectors=False)
        OPinv = A.shift_invert(sigma)
        if OPinv is None:
            return None
        c, X = eigs(A.operator(OPinv.dtype), k=k, sigma=sigma, OPinv=OPinv, maxiter=ORBITS.arpack_restarts)
    except (ArpackNoConvergence, ArpackError, RuntimeError):      # e.g. a shift on an eigenvalue
        return None
    AX = np.column_stack([A.matvec(x) for x in X.T])
    residual = np.linalg.norm(AX - X * c[None, :], axis=0) / np.linalg.norm(X, axis=0)
    if not np.all(residual <= ORBITS.arnoldi_residual_tol * max(1.0, float(np.max(np.abs(A.d))))):
        return None
    return c


class PendingSpectrum:
    """The multipliers of one point being computed in a worker thread: call it for (multipliers, collision
    coordinates) (it waits); ``cancel()`` drops it if it has not started (a point the continuation discards)."""

    def __init__(self, job=None, deflated=False, result=None, fixed=()):
        """job : a Future of the eigenvalues c of floquet.reversible_blocks' C (deflated: whether C was; fixed: the
        decoupled modes' eigenvalues); or result : the (multipliers, collision coordinates) computed already."""
        self.job, self.deflated, self.result, self.fixed = job, deflated, result, np.asarray(fixed, dtype=complex)

    def __call__(self):
        if self.job is None:
            return self.result
        return reversible_from_eigenvalues(np.concatenate([self.job.result(), self.fixed]), self.deflated)

    def cancel(self):
        if self.job is not None:
            self.job.cancel()
