"""Backbone points from frequency responses measured at several force levels: the peak of each.

A stepped-sine test at force levels F_1 < F_2 < ... gives one response curve per level; for light damping the
peak of each lies near the NNM backbone (the resonance of a forced, lightly damped system sits on the backbone
to first order in the damping: energy balance), so the peaks are (amplitude, frequency) points for
``fit_backbone``.  Each record is a frequency record (``nnm.read_measured``) whose channel is the response
amplitude (displacement, velocity or acceleration: converted to displacement by 1/(2 pi f)^k) or an FRF
(receptance, mobility, accelerance: times the level F (N) first).  The peak: the largest sample refined by the
parabola through it and its two neighbours (when they bracket it in frequency).
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError

__all__ = ["frf_peaks"]

#: powers of (2 pi f) dividing each quantity into a displacement; FRFs are multiplied by the force level first
_TO_DISPLACEMENT = {"displacement": 0, "velocity": 1, "acceleration": 2, "receptance": 0, "mobility": 1,
                    "accelerance": 2}
_FRF = ("receptance", "mobility", "accelerance")


def _peak(f, x):
    j = int(np.argmax(x))
    if 0 < j < len(x) - 1 and (f[j - 1] - f[j]) * (f[j + 1] - f[j]) < 0:
        A = np.array([[f[k] ** 2, f[k], 1.0] for k in (j - 1, j, j + 1)])
        try:
            a, b, c = np.linalg.solve(A, x[j - 1:j + 2])
        except np.linalg.LinAlgError:
            return x[j], f[j]
        if a < 0:
            fp = -b / (2 * a)
            return a * fp * fp + b * fp + c, fp
    return x[j], f[j]


def frf_peaks(records, channel=0, levels=None):
    """(amplitude (m), frequency (Hz)) of the peak of each frequency record (module doc), sorted by amplitude.

    records : Measurements of kind "frequency", one per force level.  channel : the response channel of each
    (index, label, 'node 14 uz' or (node, direction)).  levels : force amplitude (N) of each record, needed for
    FRFs (receptance, mobility, accelerance)."""
    from ..files.importers.measured import Measurement

    records = list(records)
    if not records or not all(isinstance(r, Measurement) and r.kind == "frequency" for r in records):
        raise NNMInputError("frf_peaks: give a list of frequency records (nnm.read_measured), one per force level")
    if levels is not None and len(levels) != len(records):
        raise NNMInputError(f"frf_peaks: {len(levels)} force levels for {len(records)} records")
    amp, freq = [], []
    for k, r in enumerate(records):
        j = r.index(channel)
        q = r.quantities[j]
        if q not in _TO_DISPLACEMENT:
            raise NNMInputError(f"frf_peaks: channel {r.labels[j]!r} of {r.source} is a {q}; give a response "
                                f"(displacement, velocity, acceleration) or an FRF")
        x = np.abs(r.data[:, j]).astype(float)
        if q in _FRF:
            if levels is None:
                raise NNMInputError(f"frf_peaks: {r.source} holds an FRF ({q}); give the force levels (N)")
            x = x * float(levels[k])
        f = np.asarray(r.frequency_hz, dtype=float)
        if np.any(f <= 0):
            raise NNMInputError(f"frf_peaks: {r.source} has frequencies <= 0 Hz")
        x = x / (2 * np.pi * f) ** _TO_DISPLACEMENT[q]
        a, fp = _peak(f, x)
        amp.append(a)
        freq.append(fp)
    order = np.argsort(amp)
    return np.asarray(amp)[order], np.asarray(freq)[order]
