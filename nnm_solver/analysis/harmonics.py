"""Harmonic content of the orbits of a branch.

A periodic orbit x(t) of period T is written x(t) = a_0 + sum_k Re(a_k exp(i k 2 pi t / T)), with a_k
complex vectors (n,).  Over all DOFs (``dof=None``) the amplitude of harmonic k is measured with the
mass matrix::

    A_k = sqrt(a_k^H M a_k)      (sqrt(kg) m)

i.e. the length of a_k in mass-normalised modal coordinates q = Phi^T M x: a motion made of one linear
mode q_r(t) = Q cos(w t) has A_1 = |Q|.  This weighting does not depend on the units or the number of
the DOFs (a fine mesh does not count more than a coarse one) and A_k^2 / 2 is the mass-weighted mean
square of the k-th harmonic.  For a single DOF, A_k = |a_k[dof]| (m).  The *fraction* carried by
harmonic k is A_k / sum_{j >= 1} A_j (the mean a_0 is left out; it is zero for the symmetric orbits of
odd nonlinearities).
"""
from __future__ import annotations

from math import gcd
from typing import NamedTuple

import numpy as np

from ..results.branch import Branch
from ..errors import NNMInputError
from ..fourier import fourier_coefficients
from ..model.modal import modal_system
from ..model.reduction import mass_mac
from .settings import ANALYSIS

#: an alias of settings.py's ANALYSIS.resonance_fraction (the code reads that)
RESONANCE_FRACTION = ANALYSIS.resonance_fraction
#: an alias of settings.py's ANALYSIS.distortion_fraction (the code reads that)
DISTORTION_FRACTION = ANALYSIS.distortion_fraction


class HarmonicContent(NamedTuple):
    """Harmonic content of one orbit.

    order : the dominant harmonic k (1 = the orbit's own frequency).
    fraction : the fraction of the amplitude that harmonic carries (0..1).
    fractions : (n+1,) fraction of every harmonic (index k; index 0, the mean, is always 0).
    amplitudes : (n+1,) amplitude A_k of every harmonic (index 0: amplitude of the mean),
        sqrt(kg) m for dof=None, m for one DOF.
    secondary : the strongest harmonic k >= 2 (0 if n < 2).
    secondary_fraction : its fraction.
    """

    order: int
    fraction: float
    fractions: np.ndarray
    amplitudes: np.ndarray
    secondary: int
    secondary_fraction: float


def check_branch(branch, i=None):
    """NNMInputError unless ``branch`` is a Branch (and i one of its points); returns i in 0..N-1."""
    if not isinstance(branch, Branch):
        raise NNMInputError(f"expected an nnm_solver.Branch, got {type(branch).__name__}")
    if i is None:
        return None
    return branch.check_index(i)


def harmonic_coefficients(branch, i, n=15, samples=None):
    """Complex Fourier coefficients (n+1, n_dof) of the orbit of point i (physical coordinates, m).

    Row k is a_k with x(t) = a_0 + sum_k Re(a_k exp(i k w t)), t = 0 at the branch's initial state.
    """
    i = check_branch(branch, i)
    n = int(n)
    if n < 1:
        raise NNMInputError("n (number of harmonics) must be at least 1")
    samples = int(samples or orbit_samples(branch, n))
    _, x = branch.motion(i, samples)
    return fourier_coefficients(x, n)


def orbit_samples(branch, n=15):
    """Samples per period used to look at the orbits of a branch.

    Shooting branches: the branch's own steps per period, so that the orbit is integrated with the
    time step it was computed with (a finer step gives a slightly different, not exactly periodic orbit,
    which near the escape of softening springs may even diverge); harmonics above samples / 2 are then
    reported as 0.  Other branches: max(256, 4 (n + 1)).
    """
    spp = getattr(branch.settings, "steps_per_period", None)
    if spp is not None:
        return max(int(spp), 8)
    return max(256, 4 * (int(n) + 1))


def _amplitudes(branch, coeffs, dof):
    if dof is None:
        q = modal_system(branch.model).to_modal(coeffs)  # linear map, fine for complex rows
        return np.sqrt(np.sum(np.abs(q) ** 2, axis=1))
    if not isinstance(dof, (int, np.integer)) or not 0 <= dof < branch.model.n:
        raise NNMInputError(f"dof={dof!r} is not a DOF of the model (valid: 0..{branch.model.n - 1})")
    return np.abs(coeffs[:, int(dof)])


def _content_from_amplitudes(amps):
    amps = np.asarray(amps, dtype=float)
    tot = float(np.sum(amps[1:]))
    fr = np.zeros_like(amps)
    if tot > 0:
        fr[1:] = amps[1:] / tot
    k = int(np.argmax(fr[1:]) + 1)
    if len(fr) > 2:
        k2 = int(np.argmax(fr[2:]) + 2)
        f2 = float(fr[k2])
    else:
        k2, f2 = 0, 0.0
    return HarmonicContent(k, float(fr[k]), fr, amps, k2, f2)


def dominant_harmonic(branch, i, dof=None, n=15):
    """The dominant harmonic of the orbit of point i: HarmonicContent(order, fraction, fractions, ...).

    dof=None: amplitudes over all DOFs, mass-weighted (A_k = sqrt(a_k^H M a_k), see the module doc);
    dof=j: the harmonics of DOF j alone.  Unpacks as ``k, frac, *_ = dominant_harmonic(b, i)``.
    """
    coeffs = harmonic_coefficients(branch, i, n)
    return _content_from_amplitudes(_amplitudes(branch, coeffs, dof))


def harmonic_fractions(branch, n=15, dof=None, index=None):
    """Fractions (N, n+1) of the amplitude carried by each harmonic, for every point of the branch
    (or for the points ``index``)."""
    check_branch(branch)
    idx = range(len(branch)) if index is None else list(index)
    rows = []
    for j in idx:
        try:
            rows.append(_content_from_amplitudes(_amplitudes(branch, harmonic_coefficients(branch, int(j), n),
                                                             dof)).fractions)
        except RuntimeError:  # the orbit could not be integrated again: unknown content
            rows.append(np.full(int(n) + 1, np.nan))
    return np.array(rows).reshape(len(rows), int(n) + 1)


def harmonic_shape(branch, i, k, n=None):
    """Real shape (n_dof,) of harmonic k of the orbit of point i: its complex coefficient vector turned to
    the phase that makes it as real as possible (the principal direction of [Re a_k, Im a_k]), in m."""
    k = int(k)
    coeffs = harmonic_coefficients(branch, i, max(int(n or 0), k))
    a = coeffs[k]
    A = np.column_stack([a.real, a.imag])
    U, S, _ = np.linalg.svd(A, full_matrices=False)
    shape = U[:, 0] * S[0]
    j = int(np.argmax(np.abs(shape)))
    return shape if shape[j] >= 0 else -shape


def closest_mode(branch, shape):
    _, Phi = branch.model.linear_modes()
    m = mass_mac(branch.model, shape, Phi)[0]
    r = int(np.argmax(m))
    return r + 1, float(m[r])


def _ordinal(k):
    if 10 <= k % 100 <= 20:
        suf = "th"
    else:
        suf = {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suf}"


def _ratio(hc):
    """Resonance ratio (p, q) of an orbit from its harmonic content: (k, 1) for k:1 resonances;
    when the fundamental is nearly absent, the ratio of the two strongest harmonics."""
    fr = hc.fractions
    if fr[1] >= 0.05 or len(fr) < 3:
        return hc.secondary, 1
    order = np.argsort(-fr[1:]) + 1
    if fr[order[1]] < 0.05:   # one harmonic only: its order against the orbit's own frequency
        return int(order[0]), 1
    a, b = sorted(int(x) for x in order[:2])
    g = gcd(a, b)
    return b // g, a // g


def describe_orbit(branch, i, dof=None, n=15, with_mode=True):
    """One-line description of the orbit of point i from its own harmonic content, e.g.
    ``"3:1 internal resonance: the 3rd harmonic carries 45 % of the amplitude (harmonic 1: 52 %)"`` or
    ``"fundamental NNM motion (harmonic 1 carries 98 %)"``.

    with_mode : name the linear mode whose shape is closest (MAC) to the resonant harmonic's shape.
    """
    i = check_branch(branch, i)
    hc = dominant_harmonic(branch, i, dof, n)
    f1 = hc.fractions[1]
    k2, f2 = hc.secondary, hc.secondary_fraction
    if k2 and (f2 >= ANALYSIS.resonance_fraction or hc.order != 1):
        p, q = _ratio(hc)
        kk = hc.order if hc.order != 1 else k2
        ff = hc.fractions[kk]
        if hc.order != 1:
            text = (f"{p}:{q} internal resonance: the {_ordinal(kk)} harmonic dominates with {100 * ff:.0f} % "
                    f"of the amplitude (harmonic 1: {100 * f1:.0f} %)")
        else:
            text = (f"{p}:{q} internal resonance: the {_ordinal(kk)} harmonic carries {100 * ff:.0f} % "
                    f"of the amplitude (harmonic 1: {100 * f1:.0f} %)")
        if with_mode:
            try:
                r, m = closest_mode(branch, harmonic_shape(branch, i, kk, n))
                text += f"; that harmonic's shape is closest to linear mode {r} (MAC {m:.2f})"
            except Exception:  # pragma: no cover - a description never fails on the extra
                pass
        return text
    text = f"fundamental NNM motion (harmonic 1 carries {100 * f1:.0f} %"
    if k2 and f2 >= ANALYSIS.distortion_fraction:
        text += f"; harmonic {k2}: {100 * f2:.0f} %"
    return text + ")"
