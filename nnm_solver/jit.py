"""numba's njit for the time-stepping kernels, or the plain function when numba is absent.

Compiled kernels are cached on disk (``cache=True``) and release the GIL (``nogil``), so a branch
computed in a background thread does not block a GUI.  Small kernels called from other kernels
(the element force laws) are inlined into their callers.  numba keys its cache on the caller's own
source file only: after editing an inlined kernel during development, touch newmark.py (or delete
the ``*.nbi``/``*.nbc`` files in ``__pycache__``) so its callers are recompiled.
"""
from __future__ import annotations

try:
    import numba

    jit = numba.njit(cache=True, nogil=True)
    #: small kernels called from other kernels: inlined into their callers (also across modules)
    jit_inline = jit
except ImportError:  # pragma: no cover - the same source runs uncompiled
    numba = None

    def jit(f):
        return f

    jit_inline = jit
