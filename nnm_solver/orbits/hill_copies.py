r"""The hard classes of the secular route (hill_secular.py; hill.py explains the routes): a Floquet exponent next to
the trivial pair's copies i k (an internal resonance k:1, its tongue), found by its copies.

In the truncated Hill matrix a class's exponent nu = i k0 + d (|d| small) has a zero of the characteristic
polynomial p near the points i k, k0 - H <= k <= k0 + H, and its partner's there too: i k + d and i k - d (and, for
a complex d, their conjugates'), each with its own eigenvector; they are exact copies of one another only without
the truncation.  The candidates are sought at k = 0 .. max(H, |k0|) (the others are their images -conj: the
Hill matrix is real and Hamiltonian).  The dense route keeps, of all of them, those whose eigenvectors have the
smallest |mean harmonic|: below a tongue the copy at i k0 (the class's mode on the fundamental), inside it the
one near 0, where the eigenvector mixes with the continued mode's.  Measured on NLvib's beam (example 09, 5:1
tongue), dense route: below, 4.987 i with mean harmonic -0.02 is kept against +-0.009 i with 0.04; inside, the
real pair +-0.017 with 0 against 4.975 i with -2.8 (the orbit is unstable there).  So here every such zero is
found by Newton on p'/p from i k + {d, -d, conj d, -conj d} and from a ring around 0 and i k0 (near 0 with the
trivial pair's double zero divided out: p'/p - 2 / nu), each checked by its Hill residual, and the kept ones are
chosen as the dense route chooses them (hill_shared.central_pool).

Declined (None; then the structured route decides, as before): a pair within ORBITS.copy_cluster of 0 (colliding with
the trivial pair: next to a fold of the energy or a branch point, a cluster Newton cannot resolve; told by the
count of zeros in that disc, (1 / 2 pi i) \oint p'/p dnu by the trapezoidal rule), a zero found on the orbit's
velocity, a class's own exponent not among the zeros found, a count of zeros near 0 that the zeros found do not
account for, too few central ones, or a near tie of |mean harmonic| at the cut."""
from __future__ import annotations

import numpy as np

from .hill_shared import central_pool, distinct
from .settings import ORBITS

__all__ = ["hard_copies"]


def hard_copies(nu_hard, H, logderiv, vectors, tol, residual_tol, found=None):
    """The 2 len(nu_hard) kept exponents (units of omega) of the hard classes, or None (module docstring).

    nu_hard : the hard classes' secular exponents (each within the secular route's lattice gap of a point i k);
    logderiv(nu) : p'/p at the points nu (S,); vectors(nu) : (mean harmonic, Hill residual, |cos| with the orbit's
    velocity (S,), the eigenvectors (S, N_b, n)) at the zeros nu; tol : Newton's relative step tolerance (at least
    ORBITS.copy_tol: after a step that small the error of a simple zero is its square); residual_tol : the largest
    relative Hill residual of an accepted eigenpair; found : a list that receives (zeros, eigenvectors) of the accepted
    candidates when the answer is not None (for the structured route's warm start)."""
    # a pair colliding with the trivial pair (next to a fold of the energy, or a branch point): more than the
    # trivial pair's two zeros within ORBITS.copy_cluster of 0; Newton is no tool for that cluster: the structured route
    if not abs(_zeros_in(logderiv, ORBITS.copy_cluster) - 2) < 0.05:
        return None
    nu_hard = np.asarray(nu_hard)
    k0 = np.round(nu_hard.imag)
    d = nu_hard - 1j * k0
    offsets = np.concatenate([d, -d, np.conj(d), -np.conj(d)])
    # the lattice points 0 .. max(H, |k0|): a class's own central copy may lie beyond H (e.g. mode 2 of a cantilever
    # at 5.02 i on a branch computed with H = 3); those below 0 are the images (-conj) of these
    lattice = 1j * np.arange(max(H, int(np.abs(k0).max())) + 1, dtype=float)
    start = (lattice[:, None] + offsets[None, :]).ravel()
    home = np.repeat(lattice, len(offsets))
    # and a ring of starts around 0 and the classes' own lattice points (d itself may be the trivial pair's zero)
    ring = ORBITS.copy_ring * np.exp(0.25j * np.pi * np.array([1, 3, 5, 7]))          # off the axes: Newton on a real
    # function from a real start would stay on the real axis
    # (where the secular Newton ended on the trivial pair's zero at 0, the class's own exponent is unknown: a ring
    # around every lattice point)
    at_trivial = np.abs(nu_hard) <= ORBITS.copy_tol ** 0.5
    centres = lattice if np.any(at_trivial) else 1j * np.unique(np.concatenate([[0.0], np.abs(k0)]))
    start = np.concatenate([start, (centres[:, None] + ring[None, :]).ravel()])
    home = np.concatenate([home, np.repeat(centres, len(ring))])
    keep = distinct(start, 1e-10) & (np.abs(start - home) > 1e-12)
    z, home = start[keep].copy(), home[keep]
    at0 = home == 0
    with np.errstate(all="ignore"):
        conv = np.zeros(len(z), dtype=bool)
        for _ in range(ORBITS.copy_iter):
            act = np.flatnonzero(~conv)
            if not len(act):
                break
            L = logderiv(z[act]) - np.where(at0[act], 2.0 / z[act], 0.0)
            step = -1.0 / L
            step[~np.isfinite(step)] = np.nan
            z[act] += step
            conv[act] |= ~(np.abs(step) > max(tol, ORBITS.copy_tol) * np.maximum(1.0, np.abs(z[act])))
            lost = ~(np.abs(z[act] - home[act]) < ORBITS.copy_radius)          # wandered off (or not finite): dropped
            z[act[lost]] = np.nan
            conv[act[lost]] = True
        ok = conv & np.isfinite(z) & (np.abs(z - home) < ORBITS.copy_radius)
        z = z[ok]
        if not len(z):
            return None
        z = z[distinct(z, 1e-8)]
        cent, res, triv0, vecs = vectors(z)
    ok = (res < residual_tol) & np.isfinite(cent)
    # the classes' own exponents (converged zeros, started from themselves) must be among those found, but where
    # the secular Newton converged on the trivial pair's zero at 0 (no start there: the ring looks around it)
    own = ~at_trivial
    if not np.all(np.min(np.abs(nu_hard[own, None] - z[ok][None, :]), axis=1, initial=np.inf)
                  <= 1e-8 * np.maximum(1.0, np.abs(nu_hard[own]))):
        return None
    if np.any(ok & (triv0 > ORBITS.trivial_cos)):
        return None         # a zero on the orbit's velocity: the trivial pair's, or a pair colliding with it
    # every zero near 0 found?  p has there the trivial pair's two and those found (with their images): the count
    # of zeros in |nu| < radius, (1 / 2 pi i) \oint p'/p dnu by the trapezoidal rule, must be that
    for radius in ORBITS.copy_count_radii:
        inner = z[ok & (np.abs(z) < radius)]
        images = np.concatenate([inner, np.conj(inner), -inner, -np.conj(inner)])
        images = images[distinct(images, 1e-8)]
        count = _zeros_in(logderiv, radius)
        if abs(count - np.round(count.real)) < 0.05:
            break                        # an integer: no zero near the circle (else the next radius)
    else:
        return None
    if np.round(count.real) != 2 + len(images):
        return None
    kept = central_pool(z[ok], np.abs(cent[ok]), 2 * len(d), tie=ORBITS.copy_tie)
    if kept is not None and found is not None:
        found.append((z[ok], vecs[ok]))
    return kept


def _zeros_in(logderiv, radius):
    """The number of zeros of p in |nu| < radius, (1 / 2 pi i) \\oint p'/p dnu by the trapezoidal rule on
    ORBITS.copy_count_nodes points (complex: an integer only when no zero lies near the circle)."""
    circle = radius * np.exp(2j * np.pi * (np.arange(ORBITS.copy_count_nodes) + 0.5) / ORBITS.copy_count_nodes)
    with np.errstate(all="ignore"):
        return np.mean(circle * logderiv(circle))
