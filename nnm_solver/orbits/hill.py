r"""Floquet multipliers of a harmonic-balance orbit by Hill's method (harmonic_balance.py).

A perturbation y of the orbit q(t) obeys  y'' + K(t) y = 0,  K(t) = Omega^2 + Bq^T diag(g'(d(t))) Bq
(modal coordinates, d = Bq q the spring deformations).  Floquet form y = e^{lambda t} p(t), p
T-periodic, expanded in the full basis (1, cos h theta, sin h theta, h = 1..H; theta = omega t):

    (D^2 + K_h) a + 2 lambda D a + lambda^2 a = 0,

D = omega (d/dtheta on the coefficients), K_h the Galerkin matrix of K(t) (AFT, as for the HB
Jacobian).  Linearised: lambda [a; b] = [[0, I], [-(D^2 + K_h), -2 D]] [a; b], size 2 n (2H + 1).
Each Floquet exponent appears with copies lambda + i k omega (same multiplier e^{lambda T}); of
the 2 n (2H + 1) eigenvalues the 2 n whose eigenvectors, written in exp(i k theta), k = -H..H, have
the smallest |mean k| are kept (the wave-number ordering of Lazarus & Thomas, 2010): the truncation
spoils the copies centred on high harmonics.  Multipliers mu = exp(lambda T).

Two routes to the same eigenvalues (``method=``):

* ``"dense"``: every eigenpair of the 2 n (2H + 1) matrix (LAPACK geev), then the ordering above;
  O((2 n (2H + 1))^3) a point (0.7 s for a 38-DOF beam at H = 5: 836 rows).  The reference.
* ``"structured"``: only the eigenvalues that the ordering keeps, by shift-invert subspace iteration on
  the same matrix, one small block (BLOCK vectors) per Floquet exponent, all blocks in one vectorised
  sweep.  In exp(i k theta) and modal coordinates the matrix is diagonal up to the springs:

      Q(lambda) = Q0(lambda) + U C U^T,    Q0 = diag((lambda + i k omega)^2 + omega_j^2),

  U = I (x) Bq^T (rank r = (2H + 1) n_s, C the springs' Galerkin blocks), so (L - sigma)^-1 costs a diagonal
  scaling and an r x r solve (Woodbury): O(n (2H + 1) n_s) per vector instead of an LU of the whole matrix.
  The shifts start at the frequencies of the averaged stiffness Omega^2 + Bq^T <g'> Bq (or at the previous
  call's exponents, a warm start), move with the Rayleigh quotient and are recentred by whole harmonics
  when the block's eigenvector is centred on another harmonic (the copies); the kept eigenvalues are then
  chosen as the dense route chooses them (smallest |mean k|, conjugates included), the trivial pair (the two
  exponents nearest 0 among the eigenvectors along the orbit's velocity: next to a fold the pair through +1 lies
  along it too) set to exactly 1.  Should anything not converge or not add up
  (a missing exponent, an eigenvector on the velocity), the dense route is taken: same answers, its cost.
* ``"secular"``: the same elimination taken to the end (the nonlinearity lives on few coordinates): lambda = nu
  omega is an eigenvalue where the r x r matrix I + C~ W(nu) is singular, W(nu) = blockdiag_k Bq Q0_k(nu)^-1 Bq^T;
  one exponent per class by Newton on the characteristic polynomial (batched over the classes, warm-started at
  the previous orbit's), moved to its central copy, checked (Hill residual of the rebuilt eigenvector, mean
  harmonic, no overlap with the velocity's copies, distinct pairs) and kept with its Hamiltonian partner -nu.
  O(classes x N_b x n) a Newton iteration: ~5-15 ms for the 38-DOF beam at H = 5 (0.5-0.7 s dense).  Where an
  exponent comes within ORBITS.secular_lattice_gap of the trivial pair's copies i k (internal resonances: tongues, their
  branch points) its copies at every i k are found by Newton and the kept ones chosen as the dense route chooses
  them (hill_copies.py: ~2 ms); next to a fold or a branch point, where the pair collides with the trivial one,
  the structured route decides (then the dense one).
* ``"reversible"``: the dense route on the symmetry blocks of a time-symmetric orbit (hill_reversible.py: time
  reversal makes the problem linear in lambda^2, half-wave symmetry splits it by the parity of the harmonics): the
  same eigenpairs from matrices of n (2H + 1) / 2 rows, ~1/30 of the dense route's work; the dense route where the
  orbit has no such symmetry.
* ``"monodromy"``: not through the Hill matrix: the time-domain monodromy of the same variational equation along the
  HB orbit (hill_monodromy.py: Gauss collocation in low-rank form, an n x n eigenproblem for a time-symmetric
  orbit), for many modes and few elements: ~0.7 s CPU a point for the unreduced aircraft's Ritz system (670 modes,
  H = 9), whose Hill matrix has 25,460 rows.  It differs from the Hill routes by their truncation of the
  perturbation to 2H + 1 harmonics (the flags and events agree: tests/test_hill_monodromy.py).
* ``"auto"`` (default): reversible up to ORBITS.hill_dense_max_rows rows of the whole matrix, secular above (structured,
then
  reversible, then dense, where it cannot vouch for its answer), monodromy from ORBITS.hill_monodromy_min_rows rows
  (``auto_route``), where those fallbacks would be eigenproblems of thousands of rows.
"""
from __future__ import annotations

import functools

import numpy as np
import scipy.linalg as sla

from .hb_basis import HBBasis
from .hill_monodromy import monodromy_multipliers
from .hill_reversible import reversible_multipliers
from .hill_secular import _secular
from .hill_structured import _structured
from .settings import ORBITS

__all__ = ["hill_multipliers", "auto_route", "derivative_matrix", "central_exponents", "HILL_METHODS", "DENSE_MAX_ROWS"]


#: the routes of hill_multipliers(method=...)
HILL_METHODS = ("auto", "dense", "structured", "secular", "reversible", "monodromy")

#: an alias of settings.py's ORBITS.hill_dense_max_rows (the code reads that)
DENSE_MAX_ROWS = ORBITS.hill_dense_max_rows


def derivative_matrix(basis):
    """Dm (N_b, N_b): coefficients of dp/dtheta from those of p, for a 'full' basis."""
    nb = len(basis)
    Dm = np.zeros((nb, nb))
    for j in range(nb):
        if basis.h[j] == 0:
            continue
        if basis.sine[j]:   # (sin h t)' = h cos h t: the cos of order h sits just before
            Dm[j - 1, j] = basis.h[j]
        else:               # (cos h t)' = -h sin h t: the sin of order h sits just after
            Dm[j + 1, j] = -basis.h[j]
    return Dm


@functools.lru_cache(maxsize=32)
def _hill_basis(H, samples):
    """The Hill basis (full, H harmonics, its sampling): the same for every orbit of a branch, built once (its
    arrays read-only: one object is shared by every caller)."""
    bp = HBBasis(H, "full", samples)
    for a in (bp.h, bp.sine, bp.E, bp.P, bp.at_zero, bp.slope_at_zero):
        a.setflags(write=False)
    return bp


def _galerkin_blocks(problem, u, harmonics):
    """(A, omega, H, bp, C): the orbit's coefficients and frequency, the Hill basis and the springs' Galerkin
    blocks C (n_s, N_b, N_b) of g'(d(t)) in it (real basis 1, cos, sin)."""
    A, w = problem.unpack(u)
    s = problem.sys
    H = int(harmonics or problem.basis.harmonics)
    bp = _hill_basis(H, max(4 * H + 4, 2 * problem.basis.harmonics + 2 * H + 2))
    theta = 2 * np.pi * np.arange(bp.samples) / bp.samples
    d = problem.basis.functions(theta) @ (A @ s.Bq.T)
    C = bp.galerkin(s.tangent(d))
    return A, w, H, bp, C


def auto_route(n, harmonics):
    """The route method="auto" takes for n modes and a Hill basis of ``harmonics`` harmonics (module docstring):
    "reversible", "secular" or "monodromy" by the Hill matrix's rows 2 n (2H + 1)."""
    rows = 2 * int(n) * (2 * int(harmonics) + 1)
    if rows <= ORBITS.hill_dense_max_rows:
        return "reversible"
    return "monodromy" if rows >= ORBITS.hill_monodromy_min_rows else "secular"


def hill_multipliers(problem, u, harmonics=None, method=None):
    """Floquet multipliers (2n,) of the HB orbit u of ``problem`` (an HBProblem), largest modulus first.

    method : "dense", "structured", "secular", "reversible", "monodromy" or "auto" (module docstring); default:
    ``problem.hill_method`` if it has one, else "auto".  The structured route returns the trivial pair as exactly
    1, 1."""
    method = method or getattr(problem, "hill_method", None) or "auto"
    if method not in HILL_METHODS:
        raise ValueError(f"method must be one of {HILL_METHODS}, got {method!r}")
    A, w, H, bp, C = _galerkin_blocks(problem, u, harmonics)
    s = problem.sys
    if s.elements.coupled:             # coupled elements (model/coupled.py): their tangent is not diagonal on the
        theta = 2 * np.pi * np.arange(bp.samples) / bp.samples          # deformations, which the other routes need
        d = problem.basis.functions(theta) @ (A @ s.Bq.T)
        return _dense(problem, w, bp, C, bp.galerkin_matrix(s.coupled_stiffness(d)))
    if method == "auto":
        method = auto_route(problem.n, H)
    if method == "monodromy":
        mu = monodromy_multipliers(s, problem.basis, A, w)
        if mu is not None:
            return mu
        method = "secular"
    if method == "secular":
        mu = _secular(problem, A, w, bp, C)
        if mu is not None:
            return mu
        method = "structured"
    if method == "structured":
        mu = _structured(problem, A, w, bp, C)
        if mu is not None:
            return mu
    if method != "dense":
        mu = reversible_multipliers(problem, w, bp, C)
        if mu is not None:
            return mu
    return _dense(problem, w, bp, C)


def central_exponents(V, bp, n):
    """Indices of the 2n eigenvectors (columns of V: the displacement part, N_b n rows on the full basis bp, basis
    index major) whose mean harmonic in exp(i k theta) is smallest in modulus (the ordering in the module docstring;
    stable sort)."""
    a = V.reshape(len(bp), n, -1)
    ac, as_ = a[1::2], a[2::2]                                    # cos / sin coefficients, h = 1..H
    w_pos = (np.abs(ac - 1j * as_) ** 2).sum(axis=1)               # |c_{+h}|^2 of exp(+i h theta) (x4)
    w_neg = (np.abs(ac + 1j * as_) ** 2).sum(axis=1)               # |c_{-h}|^2
    total = 4 * (np.abs(a[0]) ** 2).sum(axis=0) + (w_pos + w_neg).sum(axis=0)
    centroid = (bp.h[1::2] @ (w_pos - w_neg)) / np.maximum(total, 1e-300)
    return np.argsort(np.abs(centroid), kind="stable")[:2 * n]


def _dense(problem, w, bp, C, extra=None):
    """The dense route; extra: a further Galerkin stiffness (N_b n, N_b n) (the coupled elements')."""
    s, n = problem.sys, problem.n
    nb = len(bp)
    Kh = np.einsum("sjl,si,sm->jilm", C, s.Bq, s.Bq).reshape(nb * n, nb * n)
    if extra is not None:
        Kh += extra
    Kh[np.diag_indices(nb * n)] += np.tile(s.omega2, nb)
    D = np.kron(derivative_matrix(bp), np.eye(n)) * w
    m = nb * n
    L = np.zeros((2 * m, 2 * m))
    L[:m, m:] = np.eye(m)
    L[m:, :m] = -(D @ D + Kh)
    L[m:, m:] = -2.0 * D
    lam, V = sla.eig(L, check_finite=False)
    mu = np.exp(lam[central_exponents(V[:m], bp, n)] * 2 * np.pi / w)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


# --------------------------------------------------------------------------- the structured route
