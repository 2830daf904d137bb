"""Tools to read a computed NNM branch: harmonic content of its orbits, internal-resonance tongues,
and MAC between orbit shapes.

Harmonic content
----------------
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

Tongues
-------
Along an NNM branch continued in energy, a tongue (an internal resonance k:1 of the continued NNM with
another mode at k times its frequency) is an excursion of the branch: the energy turns back at a fold
(the *entry*, an energy maximum), decreases to the tongue's *tip* (an energy minimum, where the k-th
harmonic carries most of the motion), and increases again past the entry energy (the *exit*).  The
frequency stays almost constant on the excursion.  ``find_tongues`` locates these excursions and names
them by the harmonic that grows along them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from math import gcd
from typing import NamedTuple

import numpy as np

from .branch import Branch
from .reduction import mac
from .errors import NNMInputError
from .shooting import modal_system

__all__ = ["HarmonicContent", "Tongue", "harmonic_coefficients", "dominant_harmonic", "harmonic_fractions",
           "harmonic_shape", "orbit_samples", "describe_orbit", "find_tongues", "orbit_shape", "mac_orbits",
           "RESONANCE_FRACTION", "DISTORTION_FRACTION"]

#: a harmonic k > 1 carrying at least this fraction of the amplitude marks an internal resonance
RESONANCE_FRACTION = 0.15
#: below this, the higher harmonics are not mentioned in a description
DISTORTION_FRACTION = 0.03
#: relative energy changes below this are flat when walking along a branch (stalled continuations)
FLAT = 1e-6


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


def _check_branch(branch, i=None):
    if not isinstance(branch, Branch):
        raise NNMInputError(f"expected an nnm_solver.Branch, got {type(branch).__name__}")
    if i is None:
        return None
    return branch._check_index(i)


def harmonic_coefficients(branch, i, n=15, samples=None):
    """Complex Fourier coefficients (n+1, n_dof) of the orbit of point i (physical coordinates, m).

    Row k is a_k with x(t) = a_0 + sum_k Re(a_k exp(i k w t)), t = 0 at the branch's initial state.
    """
    i = _check_branch(branch, i)
    n = int(n)
    if n < 1:
        raise NNMInputError("n (number of harmonics) must be at least 1")
    samples = int(samples or orbit_samples(branch, n))
    _, x = branch.motion(i, samples)
    X = np.fft.rfft(np.asarray(x, dtype=float), axis=0) / samples
    X[1:] *= 2.0
    if X.shape[0] < n + 1:
        X = np.vstack([X, np.zeros((n + 1 - X.shape[0], X.shape[1]), dtype=complex)])
    return X[: n + 1]


def orbit_samples(branch, n=15):
    """Samples per period used to look at the orbits of a branch.

    Shooting branches: the branch's own steps per period, so that the orbit is integrated with the
    time step it was computed with (a finer step gives a slightly different, not exactly periodic orbit,
    which near the escape of softening springs may even diverge); harmonics above samples / 2 are then
    reported as 0.  Other branches: max(256, 4 (n + 1)).
    """
    if branch.settings.get("method", "shooting") == "shooting" and "steps_per_period" in branch.settings:
        return max(int(branch.settings["steps_per_period"]), 8)
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
    _check_branch(branch)
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


def _closest_mode(branch, shape):
    _, Phi = branch.model.linear_modes()
    m = mac(shape, Phi)[0]
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
    i = _check_branch(branch, i)
    hc = dominant_harmonic(branch, i, dof, n)
    f1 = hc.fractions[1]
    k2, f2 = hc.secondary, hc.secondary_fraction
    if k2 and (f2 >= RESONANCE_FRACTION or hc.order != 1):
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
                r, m = _closest_mode(branch, harmonic_shape(branch, i, kk, n))
                text += f"; that harmonic's shape is closest to linear mode {r} (MAC {m:.2f})"
            except Exception:  # pragma: no cover - a description never fails on the extra
                pass
        return text
    text = f"fundamental NNM motion (harmonic 1 carries {100 * f1:.0f} %"
    if k2 and f2 >= DISTORTION_FRACTION:
        text += f"; harmonic {k2}: {100 * f2:.0f} %"
    return text + ")"


# ---------------------------------------------------------------------- tongues
@dataclass
class Tongue:
    """An internal-resonance tongue along a branch.

    ratio : (p, q), e.g. (3, 1); ``label`` gives "3:1".  order : the harmonic that grows along it.
    start, tip, end : point indices of the entry, of the tip (the far end, an energy minimum or
    maximum) and of the exit (see ``find_tongues``).
    energy_range : (lowest, highest) energy of the tongue, J: (tip, entry fold) for a tongue towards
    lower energy, (return fold, tip) for one towards higher energy.  direction : "lower" / "higher".  tip_energy, tip_frequency_hz : at the tip.
    entry_frequency_hz : at the entry.  tip_fraction : fraction of the amplitude carried by the
    resonant harmonic at the tip.  complete : the branch came back above the entry energy.
    kind : "fold" (an excursion between folds) or "content" (high harmonic content without folds,
    e.g. when the continuation stepped across the tongue).  mode, mac : the linear mode closest to
    the shape of the resonant harmonic at the tip.
    """

    ratio: tuple
    order: int
    start: int
    tip: int
    end: int
    energy_range: tuple
    tip_energy: float
    tip_frequency_hz: float
    entry_frequency_hz: float
    tip_fraction: float
    complete: bool
    kind: str = "fold"
    direction: str = "lower"
    mode: int = 0
    mac: float = float("nan")
    fractions: np.ndarray = field(default=None, repr=False)

    @property
    def label(self):
        return f"{self.ratio[0]}:{self.ratio[1]}"

    @property
    def indices(self):
        return np.arange(self.start, self.end + 1)

    def middle(self, branch=None):
        """Index on the way in (start..tip) where the resonant harmonic carries half of its share at the
        tip: the orbit has two dominant frequency components (seed paper, Fig. 12 (b)).  Without the
        fractions (or if ``branch`` is given and they are missing): the point halfway in log-energy."""
        if self.fractions is not None and self.order < self.fractions.shape[1]:
            share = self.fractions[: self.tip - self.start + 1, self.order]
            return int(self.start + np.argmin(np.abs(share - 0.5 * share[-1])))
        E = np.log10(np.maximum(branch.energy[self.start:self.tip + 1], 1e-300))
        target = 0.5 * (E[0] + E[-1])
        return int(self.start + np.argmin(np.abs(E - target)))

    def summary(self):
        return (f"{self.label} tongue: points {self.start}..{self.end}, energy {self.energy_range[0]:.4g}.."
                f"{self.energy_range[1]:.4g} J, tip at {self.tip_frequency_hz:.6g} Hz where harmonic "
                f"{self.order} carries {100 * self.tip_fraction:.0f} %"
                + (f" (closest linear mode {self.mode}, MAC {self.mac:.2f})" if self.mode else "")
                + ("" if self.complete else " [not traversed to its end]"))


def _local_extrema(E):
    mins, maxs = [], []
    for j in range(1, len(E) - 1):
        a, b = E[j] - E[j - 1], E[j + 1] - E[j]
        if a < 0 < b:
            mins.append(j)
        elif a > 0 > b:
            maxs.append(j)
    return mins, maxs


def find_tongues(branch, min_fraction=RESONANCE_FRACTION, n=15, dof=None, fractions=None, with_mode=True):
    """Internal-resonance tongues along a branch: a list of Tongue, in the order met along the branch.

    A tongue is an excursion of the branch between folds, with a *tip* where a harmonic k >= 2 carries a
    large share of the amplitude.  Two orientations occur on a FEP:

    * towards lower energy (tip = energy minimum): the entry is the fold (energy maximum) before the tip,
      the exit the first point after the tip back above the entry energy;
    * towards higher energy (tip = energy maximum, typical of softening structures): the exit is the fold
      (energy minimum) after the tip, the entry the last point before the tip below the exit energy.

    A candidate is accepted when, at its tip, the strongest harmonic k >= 2 carries more than at the
    entry and the exit, and at least ``min_fraction`` of the amplitude (or at least 5 % and twice its
    share at the entry and exit).  Overlapping candidates keep the strongest; small fold pairs inside a
    tongue are part of it.  A branch that ends inside a tongue gives a provisional tip at its last point
    (``complete`` False).  Runs of points where a harmonic k >= 2 carries at least ``min_fraction``
    outside all excursions are reported too (kind "content", e.g. a tongue stepped across).  Contiguous
    excursions of the same order whose tips have the same frequency (within 0.1 %: a continuation going back
    and forth along one tongue) are merged.

    fractions : optional precomputed ``harmonic_fractions(branch, n, dof)`` (N, n+1), to save time.
    """
    _check_branch(branch)
    N = len(branch)
    if N < 3:
        return []
    F = harmonic_fractions(branch, n, dof) if fractions is None else np.asarray(fractions, dtype=float)
    if F.shape[0] != N:
        raise NNMInputError(f"fractions has {F.shape[0]} rows, the branch has {N} points")
    F = np.nan_to_num(F, nan=0.0)
    sec = F[:, 2:].max(axis=1) if F.shape[1] > 2 else np.zeros(N)
    E = branch.energy
    mins, maxs = _local_extrema(E)
    if E[-1] < E[-2]:
        mins.append(N - 1)  # the branch ends on the way down: its last point is a provisional tip
    cands = []
    for tip in mins:   # tongue towards lower energy
        i0 = tip
        while i0 > 0 and E[i0 - 1] >= E[i0] * (1 - FLAT):
            i0 -= 1
        if i0 == tip:
            continue
        i1 = tip
        while i1 < N - 1 and E[i1] < E[i0]:
            i1 += 1
        cands.append((i0, tip, i1, bool(E[i1] >= E[i0]), (float(E[tip]), float(E[i0])), "lower"))
    for tip in maxs:   # tongue towards higher energy
        i1 = tip
        while i1 < N - 1 and E[i1 + 1] <= E[i1] * (1 + FLAT):
            i1 += 1
        i0 = tip
        while i0 > 0 and E[i0] > E[i1]:
            i0 -= 1
        # traversed when, after the return fold, the branch climbs on with the harmonic's share back down
        # (not when the continuation merely creeps along, stalled inside the tongue)
        after = np.arange(i1 + 1, N)
        back = bool(len(after) and np.any((E[after] > E[i1] * 1.01) & (sec[after] < 0.5 * sec[tip])))
        cands.append((i0, tip, i1, back, (float(E[i1] if back else E[i0]), float(E[tip])), "higher"))
    found = []
    for i0, tip, i1, complete, erange, direction in cands:
        near = np.arange(max(i0, tip - 2), min(i1, tip + 2) + 1)
        jpk = int(near[np.argmax(sec[near])])  # strongest higher harmonic at (or next to) the tip
        s_tip = float(sec[jpk])
        s_ends = max(sec[i0], sec[i1] if complete else 0.0)
        if s_tip <= s_ends or not (s_tip >= min_fraction or (s_tip >= 0.05 and s_tip >= 2.0 * s_ends)):
            continue
        k = int(np.argmax(F[jpk, 2:]) + 2)
        found.append(dict(start=i0, tip=tip, end=i1, complete=complete, order=k, frac=float(F[jpk, k]),
                          kind="fold", strength=s_tip, erange=erange, direction=direction))
    # overlapping excursions: keep the strongest (e.g. not a small fold pair on a tongue's way out)
    kept = []
    for d in sorted(found, key=lambda d: -d["strength"]):
        if any(d["start"] < e["end"] and e["start"] < d["end"] for e in kept):
            continue
        kept.append(d)
    # high harmonic content outside the excursions
    covered = np.zeros(N, dtype=bool)
    for d in kept:
        covered[d["start"]: d["end"] + 1] = True
    tongues = list(kept)
    j = 0
    while j < N:
        if sec[j] >= min_fraction and not covered[j]:
            a = j
            while j + 1 < N and sec[j + 1] >= min_fraction and not covered[j + 1]:
                j += 1
            p = int(a + np.argmax(sec[a: j + 1]))
            k = int(np.argmax(F[p, 2:]) + 2)
            # a run that leads into (or out of) a tongue of the same order is part of it
            touching = [d for d in tongues if d["order"] == k and (j + 1 == d["start"] or a - 1 == d["end"])]
            if touching:
                d = touching[0]
                d["start"], d["end"] = min(d["start"], a), max(d["end"], j)
                j += 1
                continue
            kept.append(dict(start=a, tip=p, end=j, complete=False, order=k, frac=float(F[p, k]), kind="content",
                             erange=(float(E[a: j + 1].min()), float(E[a: j + 1].max())), direction=""))
        j += 1
    kept.sort(key=lambda d: d["start"])
    # a continuation that goes back and forth along the same tongue gives contiguous excursions of the
    # same order: one tongue
    merged = []
    for d in kept:
        p = merged[-1] if merged else None
        fr = branch.frequency_hz
        if p is not None and p["kind"] == d["kind"] == "fold" and p["order"] == d["order"] \
                and d["start"] <= p["end"] + 1 and abs(fr[d["tip"]] - fr[p["tip"]]) <= 1e-3 * fr[p["tip"]]:
            strong = d if d["frac"] > p["frac"] else p
            p.update(tip=strong["tip"], frac=strong["frac"], direction=strong["direction"], end=max(p["end"], d["end"]),
                     complete=d["complete"], erange=(min(p["erange"][0], d["erange"][0]),
                                                     max(p["erange"][1], d["erange"][1])))
            continue
        merged.append(d)
    kept = merged
    out = []
    for d in kept:
        tip = d["tip"]
        ratio = (d["order"], 1)
        mode, m = 0, float("nan")
        if with_mode:
            try:
                mode, m = _closest_mode(branch, harmonic_shape(branch, tip, d["order"], n))
            except Exception:  # pragma: no cover
                pass
        out.append(Tongue(ratio=tuple(int(r) for r in ratio), order=d["order"], start=d["start"], tip=tip,
                          end=d["end"], energy_range=d["erange"], direction=d["direction"],
                          tip_energy=float(E[tip]), tip_frequency_hz=float(branch.frequency_hz[tip]),
                          entry_frequency_hz=float(branch.frequency_hz[d["start"]]), tip_fraction=d["frac"],
                          complete=d["complete"], kind=d["kind"], mode=mode, mac=m,
                          fractions=F[d["start"]: d["end"] + 1].copy()))
    return out


# ---------------------------------------------------------------------- shapes and MAC
def orbit_shape(branch, i, kind="peak", samples=None):
    """Shape (n_dof,) of the orbit of point i.

    kind : "x0" the initial displacement (the paper's convention: at zero velocity for synchronous
    orbits); "peak" the configuration of largest mass-weighted norm over the period (equal to x0
    for the synchronous orbits that start at rest, robust when the continuation's phase condition put
    t = 0 elsewhere); "harmonic1" the real shape of the fundamental harmonic.
    """
    i = _check_branch(branch, i)
    if kind == "x0":
        return branch.x0[i].copy()
    if kind == "harmonic1":
        return harmonic_shape(branch, i, 1)
    if kind == "peak":
        try:
            _, x = branch.motion(i, samples or orbit_samples(branch))
        except RuntimeError:  # the orbit cannot be integrated again (strongly unstable): its x0
            return branch.x0[i].copy()
        q = modal_system(branch.model).to_modal(np.asarray(x, dtype=float))
        return np.asarray(x[int(np.argmax(np.sum(q * q, axis=1)))], dtype=float)
    raise NNMInputError(f"kind must be 'x0', 'peak' or 'harmonic1', got {kind!r}")


def mac_orbits(branch_a, i, branch_b=None, j=None, kind="peak"):
    """MAC between the shapes of orbit i of branch_a and orbit j of branch_b (default: the same
    branch).  kind: see ``orbit_shape``.  Returns a float in 0..1."""
    if branch_b is None:
        branch_b = branch_a
    if j is None:
        raise NNMInputError("give the index j of the second orbit")
    if branch_a.model.n != branch_b.model.n:
        raise NNMInputError(f"the branches have {branch_a.model.n} and {branch_b.model.n} DOFs; "
                            f"MAC needs shapes of the same size")
    return mac(orbit_shape(branch_a, i, kind), orbit_shape(branch_b, j, kind))
