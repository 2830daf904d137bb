"""The identification layer's settings: its ranges, sizes and thresholds, written once.

``IDENTIFICATION`` is the instance the code reads (``IDENTIFICATION.min_samples``); ``HIGHPASS_FRACTION`` (rfs)
stays importable as an alias of its field.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["IdentificationSettings", "IDENTIFICATION"]


@dataclass(frozen=True)
class IdentificationSettings:
    """Ranges, sizes and thresholds of the backbone fits and of the restoring-force surface."""

    #: points the backbone curve is resampled to (shape-preserving interpolation between branch points)
    curve_samples: int = 4000
    #: search range of fit_backbone's factor of the nonlinear elements
    factor_range: tuple = (1e-4, 1e4)
    #: bounds of each factor of fit_backbone's groups
    group_range: tuple = (1e-3, 1e3)
    #: default high-pass cut-off of rfs, as a fraction of the relative velocity's dominant frequency
    highpass_fraction: float = 0.2
    #: fewest samples rfs accepts
    min_samples: int = 64
    #: largest number of points drawn on a restoring-force surface (the record is thinned evenly beyond it)
    max_surface_points: int = 20000


#: the identification layer's settings (the defaults above, written once)
IDENTIFICATION = IdentificationSettings()
