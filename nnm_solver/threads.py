"""BLAS threads while a branch is computed.

The dense problems here (n ~ 10..5000) gain little from BLAS threads on an idle machine, and
multi-threaded OpenBLAS slows down 5-20x when the cores are shared (measured: a 548 x 548 eigenvalue
problem took 7.6 s with 2 threads and 0.36 s with 1 on a busy 2-core machine).  ``BLAS_THREADS``
(None: leave the process setting alone) applies while each point is computed.
"""
from __future__ import annotations

import contextlib
import threading

BLAS_THREADS = 1

_controller = None
_lock = threading.Lock()


def blas_limited():
    """Context manager limiting the BLAS threads to BLAS_THREADS (no-op if None)."""
    global _controller
    if not BLAS_THREADS:
        return contextlib.nullcontext()
    with _lock:
        if _controller is None:
            from threadpoolctl import ThreadpoolController
            _controller = ThreadpoolController()
    return _controller.limit(limits=BLAS_THREADS, user_api="blas")
