"""Two backbones of one NNM compared where both have points: the same question asked of two methods (shooting and
harmonic balance, two step counts or truncations) must get the same answer within the errors each one estimates.

``backbone_pieces(branch)`` cuts a branch's backbone where it jumps (a point off the backbone, or a landing past a
tongue: TongueRecord.landings), since no line of the backbone joins the two sides of a jump; ``compare_backbones(a,
b)`` interpolates each branch's frequency inside the other's pieces (a cubic in ln E through the 4 nearest points)
and reports the largest relative difference beyond the two points' estimated errors (branch.freq_error).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BackbonePiece", "BackboneComparison", "backbone_pieces", "compare_backbones"]


@dataclass(frozen=True)
class BackbonePiece:
    """A run of the backbone without a jump: energies (J), frequencies (Hz) and estimated relative frequency errors
    of its points, sorted in energy."""

    energy: np.ndarray
    frequency_hz: np.ndarray
    freq_error: np.ndarray


@dataclass(frozen=True)
class BackboneComparison:
    """excess : the largest |f_a / f_b - 1| minus the two points' estimated errors (negative: every difference
    within the estimates); difference : |f_a / f_b - 1| there; energy : where (J); points : how many points were
    compared (0: the backbones share no energy without a jump; then excess is -inf and the rest NaN)."""

    excess: float
    difference: float
    energy: float
    points: int


def backbone_pieces(branch):
    """The branch's backbone (labels "backbone") as BackbonePieces of at least 2 points: consecutive points (by
    index) not separated by a point off the backbone or a landing past a tongue."""
    landings = {int(i) for t in (branch.tongues or []) for i in (t.landings or ())}
    runs, run = [], []
    for i in np.flatnonzero(np.asarray(branch.labels) == "backbone"):
        if run and (i != run[-1] + 1 or i in landings):
            runs.append(run)
            run = []
        run.append(int(i))
    runs.append(run)
    out = []
    for run in runs:
        if len(run) >= 2:
            idx = np.array(run)[np.argsort(branch.energy[run])]
            out.append(BackbonePiece(branch.energy[idx], branch.frequency_hz[idx], branch.freq_error[idx]))
    return out


def _one_way(a, b):
    worst, count = (-np.inf, np.nan, np.nan), 0
    on = np.asarray(a.labels) == "backbone"
    Ea, fa, ea = a.energy[on], a.frequency_hz[on], a.freq_error[on]
    for piece in backbone_pieces(b):
        Eb, fb, eb = piece.energy, piece.frequency_hz, piece.freq_error
        for E, f, e in zip(Ea, fa, ea):
            j = int(np.searchsorted(Eb, E))
            if j == 0 or j == len(Eb):
                continue
            s = slice(max(j - 2, 0), min(j + 2, len(Eb)))
            fi = np.polyval(np.polyfit(np.log(Eb[s] / E), fb[s], min(3, len(Eb[s]) - 1)), 0.0)
            d = abs(f / fi - 1)
            excess = d - (e + np.max(eb[s]))
            count += 1
            if excess > worst[0]:
                worst = (excess, d, E)
    return worst, count


def compare_backbones(a, b):
    """BackboneComparison of the backbones of branches a and b (each interpolated inside the other's pieces)."""
    (wa, na), (wb, nb) = _one_way(a, b), _one_way(b, a)
    excess, difference, energy = max(wa, wb, key=lambda w: w[0])
    return BackboneComparison(float(excess), float(difference), float(energy), na + nb)
