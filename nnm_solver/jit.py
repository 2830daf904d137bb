"""numba's njit for the time-stepping kernels, or the plain function when numba is absent.

Compiled kernels are cached on disk (``cache=True``) and release the GIL (``nogil``), so a branch
computed in a background thread does not block a GUI.
"""
from __future__ import annotations

try:
    import numba

    jit = numba.njit(cache=True, nogil=True)
except ImportError:  # pragma: no cover - the same source runs uncompiled
    numba = None

    def jit(f):
        return f
