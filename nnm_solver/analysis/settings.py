"""The analysis layer's settings: every threshold of analysis/, written once.

``ANALYSIS`` is the instance the code reads (``ANALYSIS.resonance_fraction``); ``RESONANCE_FRACTION`` and
``DISTORTION_FRACTION`` (nnm_solver.analysis) stay importable as aliases of its fields.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["AnalysisSettings", "ANALYSIS"]


@dataclass(frozen=True)
class AnalysisSettings:
    """Thresholds of the harmonic content of orbits and of the tongues found along a branch."""

    #: a harmonic k > 1 carrying at least this fraction of the amplitude marks an internal resonance
    resonance_fraction: float = 0.15
    #: below this, the higher harmonics are not mentioned in a description
    distortion_fraction: float = 0.03
    #: relative energy changes below this are flat when walking along a branch (stalled continuations)
    flat: float = 1e-6


#: the analysis layer's settings (the defaults above, written once)
ANALYSIS = AnalysisSettings()
