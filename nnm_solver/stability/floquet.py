"""Floquet multipliers and stability of periodic orbits of conservative systems.

For a conservative system the multipliers come in pairs (mu, 1/mu) and two of them equal +1: the
*trivial pair*, whose eigenvectors are the velocity f(z0) (a shift in time along the orbit) and the
tangent of the family (a change of energy, with a Jordan block: Phi w = w + c f).  A discretised
monodromy perturbs that double eigenvalue by O(eps) (eps: the discretisation error), which splits it
by O(sqrt(eps)) -- into a real pair 1 +- 1e-3 where the period changes fast with energy (near a
separatrix), which would flag stable orbits unstable.  So the trivial pair is identified and removed
first: the monodromy is restricted to the quotient by the invariant plane span{f, w}
(``deflate``); its eigenvalues are the 2n - 2 non-trivial multipliers, reported with the pair set
to exactly 1.

Stability is then judged on the non-trivial multipliers: stable when ``max |mu| <= 1 +
STABILITY.stability_tol``.  Newmark's average-acceleration scheme is time-reversible, so the discrete map keeps
every simple multiplier of a stable orbit exactly on the unit circle; the discretisation shifts where
along the branch a multiplier leaves the circle (by O((2 pi / N)^2) in frequency), not the modulus of
the stable ones.  The tolerance therefore covers round-off only, amplified near multiplier
collisions (a double eigenvalue perturbed by delta moves by sqrt(delta)): 1e-5, which resolves
instabilities growing by more than 0.001 % per period.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
from scipy.linalg import lapack

from ..jit import eigvals_nogil
from .settings import STABILITY

#: an alias of settings.py's STABILITY.stability_tol (the code reads that)
STABILITY_TOL = STABILITY.stability_tol


def deflate(Phi, V):
    """The map Phi (m, m) on the quotient by the (nearly) invariant subspace span(V), V (m, k).

    With an orthonormal basis [Q1 Q2] whose Q1 spans V, Q^T Phi Q = [[A, B], [E, C]] where E
    vanishes for an exactly invariant span(V); C = Q2^T Phi Q2 (m-k, m-k) carries the other
    eigenvalues, to first order in E.
    """
    V = np.asarray(V, dtype=float)
    k = V.shape[1]
    m = Phi.shape[0]
    # Q = H_1 ... H_k (Householder reflectors of V's QR), applied on both sides in O(k m^2)
    (h, tau), _ = sla.qr(V, mode="raw", check_finite=False)
    C = lapack.dormqr("L", "T", h, tau, np.array(Phi, dtype=float, order="F"), lwork=32 * m)[0]
    C = lapack.dormqr("R", "N", h, tau, C, lwork=32 * m)[0]
    return C[k:, k:]


def nontrivial_multipliers(monodromy, velocity, family):
    """Multipliers (2n,) of a monodromy (2n, 2n): the 2n - 2 eigenvalues of the quotient by span{f, w}
    (f: the vector field at z0, w: the family tangent dz0), followed by the trivial pair as 1, 1."""
    V = np.column_stack([velocity, family])
    mu = sla.eigvals(deflate(monodromy, V), check_finite=False)
    return np.concatenate([mu, [1.0, 1.0]])


#: an alias of settings.py's STABILITY.decoupled_tol (the code reads that)
DECOUPLED_TOL = STABILITY.decoupled_tol


def coupled_modes(Bq, tol=STABILITY.decoupled_tol):
    """Indices of the modes that see the nonlinear elements (their Bq column above tol x the largest one's norm),
    or None when every mode does (nothing to drop).  Bq : (n_s, n) element deformations per modal coordinate."""
    Bq = np.asarray(Bq, dtype=float)
    if Bq.size == 0:
        return None
    norms = np.linalg.norm(Bq, axis=0)
    keep = np.flatnonzero(norms > tol * np.max(norms))
    return None if len(keep) == Bq.shape[1] else keep


def reversible_blocks(A11, family=None, coupled=None):
    """(C, deflated, fixed): reversible_matrix's C restricted to the coupled modes (indices ``coupled``, from
    coupled_modes; None: all) and the eigenvalues of the others, their diagonal entries of A11 (``fixed``, exact:
    those modes' rows and columns are zero off the diagonal).  The eigenvalues of C followed by ``fixed`` are those
    of reversible_matrix(A11, family)'s C (the family tangent of an NNM has no component in the decoupled modes,
    which the nonlinear forces do not excite), at the cost of an eigenproblem of the coupled modes' size."""
    if coupled is None:
        C, deflated = reversible_matrix(A11, family)
        return C, deflated, np.zeros(0)
    A11 = np.asarray(A11, dtype=float)
    fixed = np.delete(np.diag(A11), coupled)
    C, deflated = reversible_matrix(A11[np.ix_(coupled, coupled)],
                                    None if family is None else np.asarray(family, dtype=float)[coupled])
    return C, deflated, fixed


def reversible_multipliers(A11, family=None):
    """Multipliers (2n,) of a symmetric reversible orbit from A11 = dq(T/2)/dq0 (n, n); see
    reversible_spectrum, which also returns the eigenvalues c of A11 they come from."""
    return reversible_spectrum(A11, family)[0]


def reversible_spectrum(A11, family=None, coupled=None):
    """Multipliers (2n,) of a symmetric reversible orbit from A11 = dq(T/2)/dq0 (n, n).

    Newmark's scheme is time-reversible, so the half-period map A (with z(T/2) = -z0) satisfies
    R A R = A^-1, R = diag(I, -I); hence c = (lam + 1/lam) / 2 for each eigenvalue lam of A are the
    eigenvalues of A11, lam = c +- sqrt(c^2 - 1), and mu = lam^2.  The trivial pair is c = -1 with
    eigenvector the family direction dq0 (A11 dq0 = -dq0 exactly in continuous time): A11 is
    deflated by ``family`` (n,) when given.  Returns (multipliers (2n,), c (n - 1,) without the trivial
    one, or (n,) without ``family``): stable orbits have every c real in [-1, 1]; a Krein collision is
    two real c meeting and leaving the real axis as a complex pair.  coupled : optional indices of the modes
    that see the nonlinear elements (coupled_modes): the eigenproblem is then of their size (reversible_blocks).
    """
    C, deflated, fixed = reversible_blocks(A11, family, coupled)
    return reversible_from_eigenvalues(np.concatenate([eigenvalues(C), fixed]), deflated)


def reversible_matrix(A11, family=None):
    """(C, deflated): the matrix whose eigenvalues c give the multipliers of a symmetric reversible orbit (A11
    deflated by the family direction when given, else a copy of A11), for reversible_from_eigenvalues."""
    if family is not None and np.linalg.norm(family) > 0:
        return deflate(A11, np.asarray(family, dtype=float)[:, None]), True
    return np.array(A11, dtype=float), False


def reversible_from_eigenvalues(c_nontrivial, deflated):
    """(multipliers (2n,), c) of a symmetric reversible orbit from the eigenvalues c of reversible_matrix's C (the
    trivial c = -1 appended when C was deflated)."""
    c_nontrivial = np.asarray(c_nontrivial, dtype=complex)
    c = np.concatenate([c_nontrivial, [-1.0]]) if deflated else c_nontrivial
    root = np.sqrt(c * c - 1.0)
    return np.concatenate([(c + root) ** 2, (c - root) ** 2]), c_nontrivial


def eigenvalues(C):
    """Eigenvalues of a real square matrix by LAPACK dgeev, called from compiled code that releases the GIL
    (jit.eigvals_nogil: the multipliers of one point are computed in a worker thread beside the continuation's next
    step; numpy 1.26's eigvals holds the GIL), else numpy's; NaN if C is not finite or the QR iterations fail."""
    C = np.asarray(C, dtype=float)
    if not np.all(np.isfinite(C)):
        return np.full(C.shape[0], np.nan, dtype=complex)
    c = eigvals_nogil(C)
    if c is not None:
        return c
    try:
        return np.linalg.eigvals(C).astype(complex)
    except np.linalg.LinAlgError:
        return np.full(C.shape[0], np.nan, dtype=complex)


def collision_coordinates(mu):
    """Real-line coordinates rho = (mu + 1/mu) / 2 of the multipliers of a full-period monodromy, one per
    pair: those with Im mu > 0 (on the unit circle rho = cos(theta) maps each pair e^{+-i theta} once)
    and the complex ones off the circle (a Krein quadruple gives rho and its conjugate).  Real
    multipliers (at +-1 or off the circle on the real axis) are left out: they take no part in Krein
    collisions."""
    mu = np.asarray(mu, dtype=complex)
    mu = mu[(mu.imag > 1e-12 * np.abs(mu)) & (np.abs(mu - 1.0) > 0.0)]
    return 0.5 * (mu + 1.0 / mu)


def without_nearest_to_one(mu):
    """The multipliers with the two nearest to +1 replaced by exactly 1 (the trivial pair, for methods
    that give no eigenvectors to identify it, e.g. Hill's method)."""
    mu = np.asarray(mu, dtype=complex).copy()
    if len(mu) >= 2:
        mu[np.argsort(np.abs(mu - 1.0), kind="stable")[:2]] = 1.0
    return mu


def sort_multipliers(mu):
    """Multipliers sorted by decreasing modulus (the most unstable first)."""
    mu = np.asarray(mu, dtype=complex)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


def is_stable(mu, tol=STABILITY.stability_tol):
    return bool(np.max(np.abs(mu)) <= 1.0 + tol)


def instability_kind(mu, tol=STABILITY.stability_tol):
    """How an orbit is unstable, from its largest multiplier: 'branch_point' (real > 1),
    'period_doubling' (real < -1), 'torus' (complex) or '' if stable."""
    mu = sort_multipliers(mu)
    m = mu[0]
    if not abs(m) > 1.0 + tol:                   # stable (or not computed: NaN)
        return ""
    if abs(m.imag) <= 1e-6 * abs(m):
        return "branch_point" if m.real > 0 else "period_doubling"
    return "torus"


def krein_gap(rho, rho_star, per_modulus=1.0, tol=STABILITY.stability_tol, imag_tol=1e-12):
    """Test function of a Krein collision near rho_star, positive while stable.

    For the complex coordinate a + ib nearest rho_star, if there is one: b_tol^2 - b^2, where b_tol is
    the imaginary part at which the multiplier modulus reaches the stability tolerance (|mu| - 1 =
    b / (per_modulus sqrt(1 - a^2)) to first order: per_modulus = 1/2 for the coordinates c of the
    reversible half map, 1 for rho = (mu + 1/mu) / 2); else (d / 2)^2 + b_tol^2 for the two consecutive
    real coordinates around rho_star (d their distance).  Both sides are smooth in the branch parameter
    through a generic collision (the discriminant of the colliding pair) and continuous across it; the
    zero is where the stability flag changes.  None without coordinates."""
    if rho is None or len(rho) < 2:
        return None
    rho = np.asarray(rho, dtype=complex)

    def b_tol(a):
        return per_modulus * tol * np.sqrt(max(1.0 - a * a, 0.0))

    cplx = np.abs(rho.imag) > imag_tol
    if cplx.any():
        r = rho[cplx]
        z = r[np.argmin(np.abs(r.real - rho_star))]
        return float(b_tol(z.real) ** 2 - z.imag ** 2)
    r = np.sort(rho.real)
    i = int(np.clip(np.searchsorted(r, rho_star), 1, len(r) - 1))
    return float((0.5 * (r[i] - r[i - 1])) ** 2 + b_tol(rho_star) ** 2)


def real_crossing(mu):
    """Test function of a real pair leaving the unit circle: max |Re rho| - 1 over the non-trivial
    multipliers, rho = (mu + 1/mu) / 2 (events.Locator.real_crossing)."""
    mu = np.asarray(mu, dtype=complex)
    mu = mu[np.abs(mu - 1.0) > 0.0]                # the trivial pair is reported as exactly 1
    if not len(mu):
        return -1.0
    rho = 0.5 * (mu + 1.0 / mu)
    return float(np.max(np.abs(rho.real)) - 1.0)


def events_of_rows(events, rows):
    """The events of a branch that lie between its rows ``rows`` (original row numbers, in order), each with its
    ``index`` (the first row after it) renumbered among those rows; located events keep their energies and orbits.
    None when the rows are not in increasing order (the caller then brackets the events again, detect_events)."""
    rows = np.asarray(rows)
    if not len(rows) or not np.all(np.diff(rows) > 0):
        return None
    return [dict(e, index=int(np.searchsorted(rows, e["index"]))) for e in events if rows[0] < e["index"] <= rows[-1]]


def detect_events(energy, frequency_hz, floquet, stable):
    """Folds and stability changes bracketed by the points of a branch (for branches whose events
    were not located, e.g. subsets and files of the first release; events.py locates them).

    fold: the energy turns back between points i-1, i, i+1 (recorded at i).  A change of the
    stability flag between i-1 and i is classified by the largest multiplier on the unstable side:
    'branch_point' (through +1), 'period_doubling' (-1) or 'torus' (a complex pair).
    Returns a list of dicts with keys kind, index, energy, frequency_hz, detail (and
    stability_change for the stability events).
    """
    events = []
    E = np.asarray(energy)
    for i in range(1, len(E) - 1):
        a, b = E[i] - E[i - 1], E[i + 1] - E[i]
        if a * b < 0:
            events.append(dict(kind="fold", index=i, energy=float(E[i]), frequency_hz=float(frequency_hz[i]),
                               detail="energy maximum" if a > 0 else "energy minimum"))
    for i in range(1, len(E)):
        if bool(stable[i]) != bool(stable[i - 1]):
            j = i if not stable[i] else i - 1
            kind = instability_kind(floquet[j]) or "branch_point"
            change = "loss" if not stable[i] else "gain"
            through = {"branch_point": "+1", "period_doubling": "-1", "torus": "a complex pair"}[kind]
            events.append(dict(kind=kind, index=i, energy=float(E[i]), frequency_hz=float(frequency_hz[i]),
                               detail=f"{change} of stability, multiplier through {through}",
                               stability_change=change))
    events.sort(key=lambda e: (e["index"], e["kind"]))
    return events
