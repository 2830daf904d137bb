r"""Scaling law of models whose nonlinear forces are all cubic (homogeneous of degree 3).

If every k3 of  M x'' + K x + f_nl(x) = 0  is multiplied by r > 0, the orbits x(t) of the scaled model
are those of the original divided by sqrt(r): the frequencies (Hz), periods and Floquet multipliers
are unchanged, displacements and velocities are divided by sqrt(r) and energies (J) by r.  The whole
branch of one k3 therefore gives the branch of every other k3 of the same sign, without computing it.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import NNMInputError

__all__ = ["CubicScaling", "cubic_scaling"]


class CubicScaling(NamedTuple):
    """Factors that map an orbit of the original model onto the model with k3 x ratio.

    amplitude : multiplies displacements (m) and velocities (m/s), 1 / sqrt(ratio).
    energy : multiplies energies (J), 1 / ratio.  Frequencies and multipliers are unchanged.
    """

    ratio: float
    amplitude: float
    energy: float


def cubic_scaling(ratio):
    """The CubicScaling of a change of every k3 by the factor ``ratio`` (> 0)."""
    try:
        ratio = float(ratio)
    except (TypeError, ValueError):
        raise NNMInputError(f"k3 scale factor must be a positive number, got {ratio!r}") from None
    if not ratio > 0 or not np.isfinite(ratio):
        raise NNMInputError(f"k3 scale factor must be a positive number, got {ratio}")
    return CubicScaling(ratio, 1.0 / np.sqrt(ratio), 1.0 / ratio)
