r"""Hill's multipliers of a time-symmetric orbit by the dense route on its symmetry blocks (hill.py explains the
routes): the same eigenvalues and eigenvectors as every eigenpair of the whole Hill matrix, from matrices a half to
a quarter of its size.

Hill's eigenproblem (hill.py; modal coordinates, lambda in 1/s, D = omega d/dtheta on the real coefficients of
1, cos h theta, sin h theta, h = 1..H):

    (D^2 + K_h) a + 2 lambda D a + lambda^2 a = 0,        K_h: the Galerkin matrix of K(t) = Omega^2 + Bq^T g' Bq.

Two symmetries of the orbit make K_h block-sparse, exactly (up to the round-off of the AFT samples):

* time reversal, q(-t) = q(t) (the 'odd' basis holds cosines only; the 'full' basis with its sines at zero): K(t) is
  even in t, so K_h maps cosines to cosines and sines to sines.  D maps cos h to sin h and back.  With the cosine
  part a_c, the sine part a_s, and b = lambda a_s, the quadratic problem becomes linear in mu = lambda^2:

      [[Kc, 2 Dcs], [0, Ks]] x = -mu [[I, 0], [2 Dsc, I]] x,    x = [a_c; b],

  Kc, Ks the cosine and sine blocks of D^2 + K_h, Dcs, Dsc those of D.  The right-hand matrix is unit lower
  triangular, so  mu x = [[-Kc, -2 Dcs], [2 Dsc Kc, 4 Dsc Dcs - Ks]] x:  a standard eigenproblem of n (2H + 1) rows
  (the whole linearisation has 2 n (2H + 1)).  Each mu gives the pair lambda = +- sqrt(mu) with eigenvectors
  a = [a_c; +- b / lambda], i.e. [lambda a_c; +- b] (no division where lambda -> 0: the trivial pair);
* half-wave symmetry, q(t + T/2) = -q(t) with even g' (odd springs: the 'odd' basis): K(t) has even harmonics only,
  so K_h couples harmonics of equal parity only, and the problem above splits into the even harmonics (0, 2, 4, ..)
  and the odd ones (1, 3, 5, ..): two problems of about n (2H + 1) / 2 rows.

Eigenvalue costs go as the cube of the rows: 1/8 of the dense route's with time reversal, ~1/30 with both (the
2-DOF benchmark at H = 7: 60 rows -> 14 + 16).  The kept 2n exponents are chosen as the dense route chooses them
(hill._dense): the smallest |mean harmonic| of the eigenvectors written in exp(i k theta), computed from the
same eigenvectors; lambda and -lambda have opposite mean harmonics, so each mu is kept or left with both its
exponents (n values of mu).  Multipliers mu_F = exp(lambda T), T = 2 pi / omega (s).

The symmetries are read off the Galerkin blocks C themselves: the entries that must vanish are below SYMMETRY_TOL
of the largest (round-off); otherwise None (then the dense route on the whole matrix)."""
from __future__ import annotations

import functools

import numpy as np

__all__ = ["reversible_multipliers", "SYMMETRY_TOL"]

#: a symmetry holds when the entries of the springs' Galerkin blocks it sets to zero are below this fraction of the
#: largest entry (the AFT round-off is ~1e-16)
SYMMETRY_TOL = 1e-13


@functools.lru_cache(maxsize=32)
def _layout(H):
    """(h, sine, groups) of the real Hill basis 1, cos 1, sin 1, .., cos H, sin H: harmonic orders, the sine
    flags, and for each parity (even, odd) the indices of its cosines and sines (numpy arrays)."""
    h = np.concatenate([[0], np.repeat(np.arange(1, H + 1), 2)])
    sine = np.concatenate([[False], np.tile([False, True], H)])
    groups = []
    for parity in (0, 1):
        par = (h % 2) == parity
        groups.append((np.flatnonzero(par & ~sine), np.flatnonzero(par & sine)))
    return h, sine, tuple(groups)


def _symmetries(C, h, sine):
    """(time_reversal, half_wave) of the Galerkin blocks C (n_s, N_b, N_b) of g'(d(t))."""
    big = np.abs(C).max(initial=0.0)
    if big == 0.0:
        return True, True
    tol = SYMMETRY_TOL * big
    cross = sine[:, None] != sine[None, :]
    odd = ((h[:, None] - h[None, :]) % 2) == 1
    rev = np.abs(C[:, cross]).max(initial=0.0) <= tol
    half = np.abs(C[:, odd]).max(initial=0.0) <= tol
    return bool(rev), bool(half)


def reversible_multipliers(problem, w, bp, C):
    """Multipliers (2n,) of the Hill matrix of the orbit (frequency w rad/s, Hill basis bp, the springs' Galerkin
    blocks C from hill._galerkin_blocks), largest modulus first, as hill._dense returns them; or None when the
    orbit is not time-symmetric (C couples cosines with sines)."""
    s, n = problem.sys, problem.n
    H = bp.harmonics
    h, sine, groups = _layout(H)
    if len(bp) != len(h) or not np.array_equal(bp.h, h) or not np.array_equal(bp.sine, sine):
        return None
    rev, half = _symmetries(C, h, sine)
    if not rev:
        return None
    if not half:                                      # one group: every cosine, every sine
        groups = ((np.flatnonzero(~sine), np.flatnonzero(sine)),)
    lams, cents = [], []
    for ic, is_ in groups:
        lam, cent = _group(s, n, w, h, ic, is_, C)
        lams.append(lam)
        cents.append(cent)
    lam, cent = np.concatenate(lams), np.concatenate(cents)
    keep = np.argsort(np.abs(cent), kind="stable")[:n]
    lam = lam[keep]
    T = 2 * np.pi / w
    mu = np.exp(np.concatenate([lam, -lam]) * T)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


@functools.lru_cache(maxsize=64)
def _group_layout(H, n, ic_t, is_t):
    """Index arrays of one symmetry block (its cosines ic and sines is_ of the real basis, tuples): for the sines,
    the position of the cosine of the same order in the block (kc), their orders hs, the orders of the cosines
    hc; the rows of the block's modal unknowns (cosines first) in the whole basis (N_b, n) (rows, cols)."""
    h, _, _ = _layout(H)
    ic, is_ = np.array(ic_t, dtype=int), np.array(is_t, dtype=int)
    hc, hs = h[ic].astype(float), h[is_].astype(float)
    pos_c = {int(hh): i for i, hh in enumerate(hc)}
    kc = np.array([pos_c[int(hh)] for hh in hs], dtype=int)
    return ic, is_, hc, hs, kc


def _group(s, n, w, h, ic, is_, C):
    """(lambda (R,), |mean harmonic| (R,)) of one symmetry block: the cosines ic and the sines is_ of the basis
    (indices; the sine of order h follows its cosine), R = n (len(ic) + len(is_)); one lambda = sqrt(mu) per mu."""
    ic, is_, hc, hs, kc = _group_layout(int(h[-1]), n, tuple(int(i) for i in ic), tuple(int(i) for i in is_))
    Bq, om2 = s.Bq, s.omega2
    nic, nis = len(ic), len(is_)
    nc, ns_ = nic * n, nis * n
    BB = Bq[:, :, None] * Bq[:, None, :]                                       # (n_s, n, n)

    def K(idx, hr):
        Cs = C[:, idx[:, None], idx[None, :]]                                  # (n_s, r, r)
        Kb = np.einsum("sab,sij->aibj", Cs, BB).reshape(len(idx) * n, len(idx) * n)
        Kb[np.diag_indices_from(Kb)] += np.repeat(-(hr * w) ** 2, n) + np.tile(om2, len(idx))
        return Kb

    Kc, Ks = K(ic, hc), K(is_, hs)
    # D (times omega): (sin h)' = h cos h, (cos h)' = -h sin h; so (Dsc X) takes the rows of X's cosine of each
    # sine's order times -h omega, (Dcs Y) puts h omega times Y's sine rows on the cosine rows, Dsc Dcs = -(h omega)^2
    M = np.zeros((nc + ns_, nc + ns_))
    M[:nc, :nc] = -Kc
    cos_rows = (kc[:, None] * n + np.arange(n)[None, :]).ravel()              # the cosine row of each sine row
    sin_cols = nc + np.arange(ns_)
    M[cos_rows, sin_cols] = -2.0 * np.repeat(hs * w, n)
    M[nc:, :nc] = (-2.0 * np.repeat(hs * w, n))[:, None] * Kc[cos_rows]
    M[nc:, nc:] = -Ks
    M[sin_cols, sin_cols] -= 4.0 * np.repeat((hs * w) ** 2, n)
    mu, X = np.linalg.eig(M)
    lam = np.sqrt(mu.astype(complex))
    # mean harmonic of [a_c; a_s] ~ [lambda a_c; b] in exp(i k theta): c_{+-h} = (a_cos -+ i a_sin) / 2, c_0 = a_0
    Nb = len(h)
    a = np.zeros((Nb, n, len(mu)), dtype=complex)
    a[ic] = (lam[None, :] * X[:nc]).reshape(nic, n, -1)
    a[is_] = X[nc:].reshape(nis, n, -1)
    acos, asin = a[1::2], a[2::2]
    w_pos = (np.abs(acos - 1j * asin) ** 2).sum(axis=1)
    w_neg = (np.abs(acos + 1j * asin) ** 2).sum(axis=1)
    total = 4 * (np.abs(a[0]) ** 2).sum(axis=0) + (w_pos + w_neg).sum(axis=0)
    cent = (h[1::2] @ (w_pos - w_neg)) / np.maximum(total, 1e-300)
    return lam, np.abs(cent)
