"""Internal-resonance tongues along an NNM branch.

Along an NNM branch continued in energy, a tongue (an internal resonance k:1 of the continued NNM with
another mode at k times its frequency) is an excursion of the branch: the energy turns back at a fold
(the *entry*, an energy maximum), decreases to the tongue's *tip* (an energy minimum, where the k-th
harmonic carries most of the motion), and increases again past the entry energy (the *exit*).  The
frequency stays almost constant on the excursion.  ``find_tongues`` locates these excursions and names
them by the harmonic that grows along them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import NNMInputError
from .harmonics import check_branch, closest_mode, harmonic_fractions, harmonic_shape
from .settings import ANALYSIS


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
        """One line on the tongue; its points numbered from 1 (rows start..end)."""
        return (f"{self.label} tongue: points {self.start + 1}..{self.end + 1}, energy {self.energy_range[0]:.4g}.."
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


def find_tongues(branch, min_fraction=ANALYSIS.resonance_fraction, n=15, dof=None, fractions=None, with_mode=True):
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
    check_branch(branch)
    N = len(branch)
    if N < 3:
        return []
    F = harmonic_fractions(branch, n, dof) if fractions is None else np.asarray(fractions, dtype=float)
    if F.shape[0] != N:
        raise NNMInputError(f"fractions has {F.shape[0]} rows, the branch has {N} points")
    F = np.nan_to_num(F, nan=0.0)
    sec = F[:, 2:].max(axis=1) if F.shape[1] > 2 else np.zeros(N)
    E = branch.energy
    found = _accepted(_excursions(E, sec), F, sec, min_fraction)
    kept = _strongest_disjoint(found)
    kept = _with_content_runs(kept, F, sec, E, min_fraction)
    kept = _merge_back_and_forth(kept, branch.frequency_hz)
    return [_tongue(branch, d, F, n, with_mode) for d in kept]


def _excursions(E, sec):
    """Candidate excursions between folds: (i0, tip, i1, complete, (E_low, E_high), direction)."""
    N = len(E)
    mins, maxs = _local_extrema(E)
    if E[-1] < E[-2]:
        mins.append(N - 1)  # the branch ends on the way down: its last point is a provisional tip
    cands = []
    for tip in mins:   # tongue towards lower energy
        i0 = tip
        while i0 > 0 and E[i0 - 1] >= E[i0] * (1 - ANALYSIS.flat):
            i0 -= 1
        if i0 == tip:
            continue
        i1 = tip
        while i1 < N - 1 and E[i1] < E[i0]:
            i1 += 1
        cands.append((i0, tip, i1, bool(E[i1] >= E[i0]), (float(E[tip]), float(E[i0])), "lower"))
    for tip in maxs:   # tongue towards higher energy
        i1 = tip
        while i1 < N - 1 and E[i1 + 1] <= E[i1] * (1 + ANALYSIS.flat):
            i1 += 1
        i0 = tip
        while i0 > 0 and E[i0] > E[i1]:
            i0 -= 1
        # traversed when, after the return fold, the branch climbs on with the harmonic's share back down
        # (not when the continuation merely creeps along, stalled inside the tongue)
        after = np.arange(i1 + 1, N)
        back = bool(len(after) and np.any((E[after] > E[i1] * 1.01) & (sec[after] < 0.5 * sec[tip])))
        cands.append((i0, tip, i1, back, (float(E[i1] if back else E[i0]), float(E[tip])), "higher"))
    return cands


def _accepted(cands, F, sec, min_fraction):
    """The candidates whose tip carries a strong enough harmonic k >= 2, as dicts."""
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
    return found


def _strongest_disjoint(found):
    """Overlapping excursions: keep the strongest (e.g. not a small fold pair on a tongue's way out)."""
    kept = []
    for d in sorted(found, key=lambda d: -d["strength"]):
        if any(d["start"] < e["end"] and e["start"] < d["end"] for e in kept):
            continue
        kept.append(d)
    return kept


def _with_content_runs(kept, F, sec, E, min_fraction):
    """Add the runs of high harmonic content outside the excursions (kind "content"), sorted by start."""
    N = len(E)
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
    return kept


def _merge_back_and_forth(kept, fr):
    """A continuation that goes back and forth along the same tongue gives contiguous excursions of the
    same order: one tongue."""
    merged = []
    for d in kept:
        p = merged[-1] if merged else None
        if p is not None and p["kind"] == d["kind"] == "fold" and p["order"] == d["order"] \
                and d["start"] <= p["end"] + 1 and abs(fr[d["tip"]] - fr[p["tip"]]) <= 1e-3 * fr[p["tip"]]:
            strong = d if d["frac"] > p["frac"] else p
            p.update(tip=strong["tip"], frac=strong["frac"], direction=strong["direction"], end=max(p["end"], d["end"]),
                     complete=d["complete"], erange=(min(p["erange"][0], d["erange"][0]),
                                                     max(p["erange"][1], d["erange"][1])))
            continue
        merged.append(d)
    return merged


def _tongue(branch, d, F, n, with_mode):
    """The Tongue of a kept excursion dict."""
    E = branch.energy
    tip = d["tip"]
    ratio = (d["order"], 1)
    mode, m = 0, float("nan")
    if with_mode:
        try:
            mode, m = closest_mode(branch, harmonic_shape(branch, tip, d["order"], n))
        except Exception:  # pragma: no cover
            pass
    return Tongue(ratio=tuple(int(r) for r in ratio), order=d["order"], start=d["start"], tip=tip,
                  end=d["end"], energy_range=d["erange"], direction=d["direction"],
                  tip_energy=float(E[tip]), tip_frequency_hz=float(branch.frequency_hz[tip]),
                  entry_frequency_hz=float(branch.frequency_hz[d["start"]]), tip_fraction=d["frac"],
                  complete=d["complete"], kind=d["kind"], mode=mode, mac=m,
                  fractions=F[d["start"]: d["end"] + 1].copy())
