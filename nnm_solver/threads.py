"""BLAS threads while a branch is computed.

The dense problems here (n ~ 10..5000) gain little from BLAS threads on an idle machine, and
multi-threaded OpenBLAS slows down 5-20x when the cores are shared (measured: a 548 x 548 eigenvalue
problem took 7.6 s with 2 threads and 0.36 s with 1 on a busy 2-core machine).  ``BLAS_THREADS``
(None: leave the process setting alone) applies while each point is computed.

``background`` runs a GIL-free call (a LAPACK eigenvalue problem) in a worker thread (WORKERS of them), so that
the Floquet multipliers of the points are computed beside the continuation's next steps, on both cores.
"""
from __future__ import annotations

import contextlib
import os
import threading

BLAS_THREADS = 1

_controller = None
_lock = threading.Lock()


#: held while the BLAS thread count changes (``blas_limited``) and by a call that may run BLAS in another thread than
#: the branch's (results/point.py: the physical states mapped when a snapshot reads them): OpenBLAS can crash when
#: its thread count changes during a call in another thread
BLAS_CONFIG = threading.RLock()


@contextlib.contextmanager
def blas_limited():
    """Context manager limiting the BLAS threads to BLAS_THREADS (no-op if None); the limit set and restored under
    BLAS_CONFIG."""
    global _controller
    if not BLAS_THREADS:
        yield None
        return
    with _lock:
        if _controller is None:
            from threadpoolctl import ThreadpoolController
            _controller = ThreadpoolController()
    with BLAS_CONFIG:
        limiter = _controller.limit(limits=BLAS_THREADS, user_api="blas")
    try:
        yield limiter
    finally:
        with BLAS_CONFIG:
            limiter.restore_original_limits()


#: worker threads of ``background`` (environment NNM_SPECTRUM_WORKERS; 0: the multipliers are computed in turn,
#: e.g. in a process of a sweep that already has one process per core)
def _workers_from_environment():
    text = os.environ.get("NNM_SPECTRUM_WORKERS", "2").strip() or "0"
    try:
        return max(int(text), 0)
    except ValueError:
        raise ValueError(f"NNM_SPECTRUM_WORKERS must be a whole number of threads (0 turns them off), "
                         f"not {text!r}") from None


WORKERS = _workers_from_environment()

_worker = None


def background(fn, *args):
    """fn(*args) in one of the package's worker threads (started on first use): a concurrent.futures.Future.
    Worth it for calls that release the GIL (numpy's LAPACK routines, numba's nogil kernels)."""
    global _worker
    with _lock:
        if _worker is None:
            from concurrent.futures import ThreadPoolExecutor
            _worker = ThreadPoolExecutor(max_workers=WORKERS, thread_name_prefix="nnm-spectrum")
    return _worker.submit(fn, *args)
