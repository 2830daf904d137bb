r"""Floquet multipliers of a harmonic-balance orbit from the time-domain monodromy of its variational equation (the
``"monodromy"`` route of hill.py): for models with many modes and few nonlinear elements (the Ritz system of a large
FE model), where every route through the Hill matrix, 2 n (2H + 1) rows, falls back to an eigenproblem of that size.

A perturbation y (modal coordinates, sqrt(kg) m) of the HB orbit q(t) obeys

    y'' + Omega^2 y + Bq^T diag(g'(d(t))) Bq y = 0,        d(t) = Bq q(t)   (the elements' deformations, m),

a linear system whose time-varying part lives on the n_s element coordinates.  It is integrated over the orbit's
period by the Gauss-Legendre collocation of integrators/gauss.py (symplectic and symmetric) with the exact
derivative of the discrete map assembled in low-rank form (integrators/gauss_monodromy.py: only the s n_s stage
deformations are propagated, by a Volterra recursion; the linear modes' part is one 2 x 2 power per mode), the
stage tangents g'(d) read off the HB orbit itself at the stage times (the orbit is the one Hill's method linearises
about: no nonlinear integration, no shooting).  Cost O((N s n_s)^2 n) for N steps, plus the eigenproblem below.

Time-symmetric orbits (q(-t) = q(t): no sine coefficients, every orbit of the 'odd' basis and the NNMs of the
'full' one) need half a period and an n x n eigenproblem: with A = d[y; y'](T/2) / d[y; y'](0) (symplectic) and
R = diag(I, -I), the orbit's symmetry about t = 0 and t = T/2 gives the monodromy M = R A^-1 R A, hence
M^-1 = R M R and (M + M^-1) / 2 = diag(M11, M22) with

    M11 = 2 A22^T A11 - I        (A11 = dy / dy0, A22 = dy' / dy0' over half a period; A22^T A11 - A12^T A21 = I),

so each eigenvalue c of M11 gives a pair of multipliers mu = c +- sqrt(c^2 - 1): on the unit circle for real c in
[-1, 1], a real pair for real |c| > 1, a Krein quadruple for complex c.  The modes that do not see the elements
(stability.floquet.coupled_modes) keep their diagonal entries.  Other orbits: the full period and the 2n x 2n
monodromy's eigenvalues.

Accuracy.  The step is set by the orbit's highest harmonic (ORBITS.monodromy_steps_per_harmonic steps per half
period and harmonic; the tangent g'(d(t)) of a cubic law holds harmonics up to 2H): the method's error is O(h^(2s)),
measured on the aircraft's Ritz system below 1e-9 in the multipliers when the steps are doubled
(tests/test_hill_monodromy.py checks the convergence and the flags against the dense Hill route).  It is not Hill's
truncation: the two routes differ by the Hill matrix's truncation of the perturbation to 2H + 1 harmonics, which is
why a multiplier is compared within that difference and the flags and events exactly.  The trivial pair comes out
near +1 to the HB orbit's residual (the orbit is not an exact orbit of the discrete map); callers set the two
nearest +1 to exactly 1 (stability.floquet.without_nearest_to_one), as for the other routes.
"""
from __future__ import annotations

import math

import numpy as np

from ..integrators.gauss import constants
from ..integrators.gauss_monodromy import _kernel, _linear_parts, _volterra, monodromy
from ..stability.floquet import coupled_modes, eigenvalues
from .settings import ORBITS

__all__ = ["monodromy_multipliers", "monodromy_steps", "time_symmetric"]


def monodromy_steps(harmonics):
    """Gauss steps per half period for an orbit of ``harmonics`` harmonics (at least ORBITS.monodromy_min_steps)."""
    return int(max(ORBITS.monodromy_min_steps, math.ceil(ORBITS.monodromy_steps_per_harmonic * max(int(harmonics), 1))))


def time_symmetric(basis, A):
    """True when the orbit of coefficients A (N_b, n) on ``basis`` is even in time (its sine coefficients below
    ORBITS.reversible_symmetry_tol of the largest coefficient)."""
    A = np.asarray(A, dtype=float)
    scale = float(np.max(np.abs(A))) if A.size else 0.0
    sines = A[np.asarray(basis.sine, dtype=bool)]
    return not sines.size or float(np.max(np.abs(sines))) <= ORBITS.reversible_symmetry_tol * max(scale, 1e-300)


def _pairs(c):
    """The multipliers mu = c +- sqrt(c^2 - 1) of the eigenvalues c (k,) of M11: (2k,)."""
    c = np.asarray(c, dtype=complex)
    root = np.sqrt(c * c - 1.0)
    return np.concatenate([c + root, c - root])


def _diagonal_blocks(k, Bq, N, Dseq):
    """(A11 = dq_N / dq0, A22 = dv_N / dv0) (n, n) each of N Gauss steps: gauss_monodromy.monodromy's Sq[:, :n] and
    Sv[:, n:] from its own parts, without the two off-diagonal blocks' products (half of its final n x N s n_s by
    N s n_s x 2n work)."""
    n = Bq.shape[1]
    PN, Hom, HomV, CAE, Uq, Uv = _linear_parts(k.A_lin, k.C, k.E, Bq, N, True)
    W = _volterra(Hom, HomV, _kernel(CAE, k.BB, k.s, Bq.shape[0]), k.G, Dseq, 2 * n)
    A11, A22 = -(Uq @ W[:, :n]), -(Uv @ W[:, n:])
    A11[np.diag_indices(n)] += PN[:, 0, 0]
    A22[np.diag_indices(n)] += PN[:, 1, 1]
    return A11, A22


def monodromy_multipliers(system, basis, A, w, steps=None, stages=None):
    """Floquet multipliers (2n,) of the HB orbit (modal coefficients A (N_b, n) on ``basis``, frequency w rad/s) of
    the ModalSystem ``system``, largest modulus first, by the time-domain monodromy (module docstring); None for
    coupled elements (their tangent is not diagonal on the deformations) or a non-finite map.  steps : Gauss steps
    per half period (default monodromy_steps(basis.harmonics)); stages : Gauss stages (ORBITS.monodromy_stages)."""
    if system.elements.coupled:
        return None
    s = int(stages or ORBITS.monodromy_stages)
    N = int(steps or monodromy_steps(basis.harmonics))
    n, Bq = system.n, np.ascontiguousarray(system.Bq, dtype=float)
    symmetric = time_symmetric(basis, A)
    span = (np.pi if symmetric else 2 * np.pi) / float(w)        # half a period (s), or the whole one
    N = N if symmetric else 2 * N
    h = span / N
    k = constants(system, h, s)
    t = (np.arange(N)[:, None] + np.asarray(k.c)[None, :]) * h                  # the stage times (N, s)
    d = basis.functions(float(w) * t.ravel()) @ (np.asarray(A, dtype=float) @ Bq.T)     # (N s, n_s)
    Dseq = np.ascontiguousarray(system.tangent(d).reshape(N, s * Bq.shape[0]), dtype=float)
    if symmetric:
        A11, A22 = _diagonal_blocks(k, Bq, N, Dseq)
        if not (np.all(np.isfinite(A11)) and np.all(np.isfinite(A22))):
            return None
        M11 = 2.0 * A22.T @ A11
        M11[np.diag_indices(n)] -= 1.0
        keep = coupled_modes(Bq)
        if keep is None:
            c = eigenvalues(M11)
        else:                      # the decoupled modes' rows and columns are zero off the diagonal
            c = np.concatenate([eigenvalues(M11[np.ix_(keep, keep)]), np.delete(np.diag(M11), keep)])
        mu = _pairs(c)
    else:
        Sq, Sv = monodromy(k, Bq, N, Dseq, 2 * n, velocities=True)
        mu = eigenvalues(np.vstack([Sq, Sv]))
    if not np.all(np.isfinite(mu)):
        return None
    return mu[np.argsort(-np.abs(mu), kind="stable")]
