"""BLAS threads while a branch is computed.

The dense problems here (n ~ 10..5000) gain little from BLAS threads on an idle machine, and
multi-threaded OpenBLAS slows down 5-20x when the cores are shared (measured: a 548 x 548 eigenvalue
problem took 7.6 s with 2 threads and 0.36 s with 1 on a busy 2-core machine).  ``BLAS_THREADS``
(None: leave the process setting alone) applies while a branch's points are computed, in BLAS-limited regions
counted over all threads (``blas_limited``).

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


#: held while the count of open BLAS-limited regions and the BLAS thread limit change (``blas_limited``)
BLAS_CONFIG = threading.RLock()

_open = 0          # BLAS-limited regions open now, in all threads (worker jobs included)
_limiter = None    # the threadpoolctl limiter set when the first region opened (restores the limits of that moment)


def _release_control():
    """threadpoolctl 3.8 lets one thread at a time change OpenBLAS's process-wide thread count (the first to set
    it, until it leaves a ``with`` block) and silently ignores the others' changes.  The limit here is set and
    restored outside ``with`` blocks, in whichever thread opens the first region or closes the last, always under
    BLAS_CONFIG: that thread takes the control for the change and gives it back at once (earlier versions have no
    such control: nothing to do).  Without this, a thread that had set the limit once kept the control for good and
    a Job's thread ran unlimited, beside the main thread's BLAS calls (issue 52)."""
    import threadpoolctl
    clear = getattr(getattr(threadpoolctl, "OpenBLASController", None), "clear_controlling_thread", None)
    if clear is not None:
        clear(force=True)


def _open_region():
    """One more BLAS-limited region; the first one sets the limit (under BLAS_CONFIG)."""
    global _controller, _limiter, _open
    with BLAS_CONFIG:
        if _open == 0:
            with _lock:
                if _controller is None:
                    from threadpoolctl import ThreadpoolController
                    _controller = ThreadpoolController()
            _release_control()
            _limiter = _controller.limit(limits=BLAS_THREADS, user_api="blas")
            _release_control()
        _open += 1


def _close_region(*_):
    """One BLAS-limited region fewer; the last one restores the limits it found (under BLAS_CONFIG)."""
    global _limiter, _open
    with BLAS_CONFIG:
        if _open == 1:               # the limits are restored before the count reads 0 (read without the lock)
            _release_control()
            _limiter.restore_original_limits()
            _release_control()
            _limiter = None
        _open -= 1


@contextlib.contextmanager
def blas_limited():
    """Context manager limiting the BLAS threads to BLAS_THREADS (no-op if None).

    The regions are counted over all threads (re-entrant): the limit is set when the first one opens and restored
    when the last one closes, so the process's BLAS thread count never changes while a BLAS call of the package
    runs in any thread, as long as every such call runs inside a region.  The package's are: a branch's points
    (driver/iterator.py), a Job's whole run (driver/jobs.py), the multipliers computed in the worker threads
    (``background``: the region is held from the submission to the end of the call) and a Point's physical state
    mapped from its modal one (results/point.py, in whichever thread reads it).  (OpenBLAS's pthreads pool is one
    per process: a count changed per point by one thread under another thread's running call is what this avoids;
    a limit set per point and restored out of order by two threads left the count wrong.)"""
    if not BLAS_THREADS:
        yield None
        return
    _open_region()
    try:
        yield None
    finally:
        _close_region()


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
    Worth it for calls that release the GIL (numpy's LAPACK routines, numba's nogil kernels).  The call runs inside
    a BLAS-limited region (``blas_limited``) opened here and closed when it ends or is cancelled."""
    global _worker
    with _lock:
        if _worker is None:
            from concurrent.futures import ThreadPoolExecutor
            _worker = ThreadPoolExecutor(max_workers=WORKERS, thread_name_prefix="nnm-spectrum")
    if not BLAS_THREADS:
        return _worker.submit(fn, *args)
    _open_region()              # held until the call ends (or is cancelled): no limit change while it runs
    try:
        job = _worker.submit(fn, *args)
    except BaseException:
        _close_region()
        raise
    job.add_done_callback(_close_region)
    return job
