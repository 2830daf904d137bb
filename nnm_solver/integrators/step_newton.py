"""The stopping rule of an implicit step's Newton iteration, shared by the general kernels (general.py in modal
coordinates, general_band.py in physical ones).

The limits are compile-time constants of the kernels (settings.py: KERNELS.newton_max, newton_rtol; numba freezes a
module global when it compiles, and keys its disk cache on each kernel's own source file: after changing them, touch
this file, general.py and general_band.py).
"""
from __future__ import annotations

import numpy as np

from ..jit import jit as _jit
from .settings import KERNELS

__all__ = ["NEWTON_MAX", "NEWTON_RTOL", "newton_end", "stage_guess"]

#: the step's Newton limits, compile-time constants of the kernels (settings.py: KERNELS)
NEWTON_MAX = KERNELS.newton_max
NEWTON_RTOL = KERNELS.newton_rtol


@_jit
def newton_end(it, nR, J, scale):
    """(stop, ok) of a step's Newton iteration it with residual norm nR and Newton matrix J: converged (nR within
    NEWTON_RTOL of scale), out of iterations (ok if nR is within 1e-9 of scale), or a NaN/inf (a failed step, not a
    LinAlgError from the solve)."""
    if nR <= NEWTON_RTOL * scale:
        return True, True
    if it == NEWTON_MAX or not _finite(nR, J):
        return True, it == NEWTON_MAX and nR <= 1e-9 * scale
    return False, False


@_jit
def _finite(nR, J):
    """True when the residual norm and the Newton matrix are finite (NaN or inf: the step failed)."""
    if not np.isfinite(nR):
        return False
    for v in J.ravel():
        if not np.isfinite(v):
            return False
    return True


@_jit
def stage_guess(X, q, v, a, c, h):
    """The next step's first guess of its stage values X (s, m), in place: the Taylor polynomial of the state q, v
    with acceleration a at the stage times c h (the collocation polynomial of the step just taken, extrapolated)."""
    for l in range(X.shape[0]):
        tl = c[l] * h
        X[l] = q + tl * v + (0.5 * tl * tl) * a

