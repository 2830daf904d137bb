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

The symmetries are read off the Galerkin blocks C themselves: the entries that must vanish are below
ORBITS.reversible_symmetry_tol of the largest (round-off); otherwise None (then the dense route on the whole matrix)."""
from __future__ import annotations

import functools

import numpy as np

from .settings import ORBITS

__all__ = ["reversible_multipliers", "SYMMETRY_TOL"]

#: an alias of settings.py's ORBITS.reversible_symmetry_tol (the code reads that)
SYMMETRY_TOL = ORBITS.reversible_symmetry_tol


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
    tol = ORBITS.reversible_symmetry_tol * big
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
    h, sine, _ = _layout(H)
    if len(bp) != len(h) or not np.array_equal(bp.h, h) or not np.array_equal(bp.sine, sine):
        return None
    rev, half = _symmetries(C, h, sine)
    if not rev:
        return None
    # the Galerkin matrix of the springs' stiffness, N_b n x N_b n (basis index major), once for every block
    Bq = s.Bq
    Kh = np.einsum("sjl,sim->jilm", C, Bq[:, :, None] * Bq[:, None, :]).ravel()
    lams, cents = [], []
    for blk in _block_layout(H, n, half):
        lam, cent = _group(blk, n, w, s.omega2, Kh)
        lams.append(lam)
        cents.append(cent)
    lam, cent = np.concatenate(lams), np.concatenate(cents)
    keep = np.argsort(cent, kind="stable")[:n]
    lam = lam[keep]
    T = 2 * np.pi / w
    mu = np.exp(np.concatenate([lam, -lam]) * T)
    return mu[np.argsort(-np.abs(mu), kind="stable")]


@functools.lru_cache(maxsize=64)
def _block_layout(H, n, half):
    """Index arrays of the symmetry blocks of the real Hill basis of H harmonics for n modal coordinates (half: split
    by the parity of the harmonics), built once per (H, n, half): a tuple with, for each block, its cosines ic and
    sines is_ (basis indices), their orders hc, hs, the position kc of each sine's cosine among the block's
    cosines, the flat indices of the block's cosine-cosine and sine-sine entries in the whole Galerkin matrix
    (N_b n x N_b n, basis index major), the mode of each row (for Omega^2 on the diagonals), the cosine row of each
    sine row (cos_rows), the position of the constant among the cosines (or -1)."""
    h, sine, groups = _layout(H)
    if not half:
        groups = ((np.flatnonzero(~sine), np.flatnonzero(sine)),)
    N = len(h) * n
    blocks = []
    for ic, is_ in groups:
        hc, hs = h[ic].astype(float), h[is_].astype(float)
        pos_c = {int(hh): i for i, hh in enumerate(hc)}
        kc = np.array([pos_c[int(hh)] for hh in hs], dtype=int)
        rc = (ic[:, None] * n + np.arange(n)[None, :]).ravel()
        rs = (is_[:, None] * n + np.arange(n)[None, :]).ravel()
        cos_rows = (kc[:, None] * n + np.arange(n)[None, :]).ravel()
        zero = np.flatnonzero(hc == 0)
        blocks.append(dict(nic=len(ic), nis=len(is_), hs=hs, kc=kc,
                           cc=(rc[:, None] * N + rc[None, :]).ravel(), ss=(rs[:, None] * N + rs[None, :]).ravel(),
                           hc2=np.repeat(hc ** 2, n), hs_rep=np.repeat(hs, n), mode_c=np.tile(np.arange(n), len(ic)),
                           mode_s=np.tile(np.arange(n), len(is_)), cos_rows=cos_rows,
                           zero=int(zero[0]) if len(zero) else -1))
    return tuple(blocks)


def _group(blk, n, w, om2, Kh):
    """(lambda (R,), |mean harmonic| (R,)) of one symmetry block (_block_layout), R = n (its cosines + its sines);
    Kh: the springs' Galerkin matrix, flattened; one lambda = sqrt(mu) per mu."""
    nic, nis, hs_rep, cos_rows = blk["nic"], blk["nis"], blk["hs_rep"], blk["cos_rows"]
    nc, ns_ = nic * n, nis * n
    R = nc + ns_
    Kc = Kh[blk["cc"]].reshape(nc, nc)
    Kc.flat[::nc + 1] += om2[blk["mode_c"]] - blk["hc2"] * w * w
    # D (times omega): (sin h)' = h cos h, (cos h)' = -h sin h; so (Dsc X) takes the rows of X's cosine of each
    # sine's order times -h omega, (Dcs Y) puts h omega times Y's sine rows on the cosine rows, Dsc Dcs = -(h omega)^2
    two_hw = -2.0 * w * hs_rep
    M = np.zeros((R, R))
    M[:nc, :nc] = -Kc
    M[cos_rows, nc + np.arange(ns_)] = two_hw
    M[nc:, :nc] = two_hw[:, None] * Kc[cos_rows]
    M[nc:, nc:] = -Kh[blk["ss"]].reshape(ns_, ns_)
    # the sine block's diagonal: -Ks's (Omega^2 - (h omega)^2) and 4 Dsc Dcs = -4 (h omega)^2
    M.flat[nc * (R + 1)::R + 1] -= om2[blk["mode_s"]] - (hs_rep * w) ** 2 + 4.0 * (hs_rep * w) ** 2
    mu, X = np.linalg.eig(M)
    lam = np.sqrt(mu.astype(complex))
    # mean harmonic of [a_c; a_s] ~ [lambda a_c; b] in exp(i k theta): c_{+-h} = (a_cos -+ i a_sin) / 2, c_0 = a_0
    ac = (lam[None, :] * X[:nc]).reshape(nic, n, R)
    asin = X[nc:].reshape(nis, n, R)
    acos = ac[blk["kc"]]
    w_pos = (np.abs(acos - 1j * asin) ** 2).sum(axis=1)
    w_neg = (np.abs(acos + 1j * asin) ** 2).sum(axis=1)
    total = (w_pos + w_neg).sum(axis=0)
    if blk["zero"] >= 0:
        total = total + 4 * (np.abs(ac[blk["zero"]]) ** 2).sum(axis=0)
    cent = (blk["hs"] @ (w_pos - w_neg)) / np.maximum(total, 1e-300)
    return lam, np.abs(cent)
