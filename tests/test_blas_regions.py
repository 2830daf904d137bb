"""threads.blas_limited: BLAS-limited regions counted over all threads, so that the process's BLAS thread count
changes only when no region is open (issue 52: OpenBLAS's thread pool is one per process; a lazy Point's physical
state, mapped in whichever thread reads it, and the multipliers computed in the worker threads are the package's BLAS
calls outside the branch's own thread), and a region opened in any thread limits the BLAS threads (threadpoolctl 3.8
lets one thread at a time change OpenBLAS's count and silently ignores the others)."""
import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from nnm_solver import threads
from nnm_solver.results.point import ModalState, Point, resolve_points

pytestmark = pytest.mark.skipif(not threads.BLAS_THREADS, reason="BLAS_THREADS is None: no limit is set")


def blas_threads():
    """The thread counts of the loaded BLAS libraries (numpy's and scipy's OpenBLAS)."""
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def no_region_open(timeout=120.0):
    """Wait until no region is open (a worker call of an earlier test may still hold one); True if none is."""
    ready = threading.Event()
    for _ in range(int(timeout / 0.01)):
        if threads._open == 0:
            return True
        ready.wait(0.01)
    return threads._open == 0


@pytest.fixture
def two_threads():
    """The BLAS libraries at 2 threads outside any region (so that the limit to 1 is seen), restored after."""
    from threadpoolctl import threadpool_limits
    assert no_region_open()
    with threadpool_limits(limits=2, user_api="blas"):
        yield [2] * len(blas_threads())
    assert no_region_open()


def test_regions_in_two_threads_keep_the_limit_until_the_last_one_closes(two_threads):
    opened, close_a, closed_a = threading.Event(), threading.Event(), threading.Event()

    def a():
        with threads.blas_limited():
            opened.set()
            close_a.wait(10)
        closed_a.set()

    t = threading.Thread(target=a)
    t.start()
    assert opened.wait(10)
    assert blas_threads() == [threads.BLAS_THREADS] * len(two_threads)
    with threads.blas_limited():                 # a second region, in this thread
        with threads.blas_limited():             # re-entrant
            close_a.set()
            assert closed_a.wait(10)             # the first region closed: the limit stays, this one is open
            assert blas_threads() == [threads.BLAS_THREADS] * len(two_threads) and threads._open == 2
    t.join()
    assert blas_threads() == two_threads         # the last one closed: the limits it found are back


def test_a_background_call_holds_the_limit_until_it_ends(two_threads):
    started, release = threading.Event(), threading.Event()
    seen = []

    def call():
        started.set()
        release.wait(10)
        seen.append(blas_threads())
        return 1

    with threads.blas_limited():                 # submitted from a region (as the driver does) that then closes
        job = threads.background(call)
        assert started.wait(10)
    assert blas_threads() == [threads.BLAS_THREADS] * len(two_threads)    # no change while the call runs
    release.set()
    assert job.result(10) == 1 and seen == [[threads.BLAS_THREADS] * len(two_threads)]
    assert no_region_open()                      # the done callback runs just after the result is set
    assert blas_threads() == two_threads


def test_a_cancelled_background_call_closes_its_region(two_threads):
    if threads.WORKERS < 1:
        pytest.skip("no worker threads")
    gate = threading.Event()
    busy = [threads.background(gate.wait, 10) for _ in range(threads.WORKERS)]   # the workers occupied
    queued = threads.background(np.linalg.eigvals, np.eye(3))
    assert queued.cancel() and threads._open == len(busy)
    gate.set()
    for job in busy:
        job.result(10)
    assert no_region_open() and blas_threads() == two_threads


class Watched(np.ndarray):
    """An array that records whether a BLAS-limited region is open when a product uses it."""
    regions = []

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if ufunc is np.matmul:
            Watched.regions.append((threads._open, blas_threads()))
        inputs = tuple(np.asarray(x) if isinstance(x, Watched) else x for x in inputs)
        return getattr(ufunc, method)(*inputs, **kwargs)


def test_a_lazy_point_is_mapped_inside_a_region_in_any_thread(two_threads):
    rng = np.random.default_rng(1)
    phi = rng.standard_normal((7, 3))
    q0, v0, A = rng.standard_normal(3), rng.standard_normal(3), rng.standard_normal((5, 3))
    Watched.regions = []
    point = Point(1.0, 1.0, 1.0, None, None, np.zeros(14, complex), True, modal=ModalState(phi.view(Watched), q0, v0, A))
    out = []
    t = threading.Thread(target=lambda: out.append(point.x0.copy()))     # read in a thread of its own
    t.start()
    t.join()
    assert Watched.regions == [(1, [threads.BLAS_THREADS] * len(two_threads))]
    assert np.allclose(out[0], phi @ q0, rtol=0, atol=1e-14) and np.allclose(point.v0, phi @ v0, rtol=0, atol=1e-14)
    assert np.allclose(point.coefficients, A @ phi.T, rtol=0, atol=1e-14)
    assert blas_threads() == two_threads and resolve_points([point]) == [point]


def test_a_region_limits_a_job_thread_after_the_main_thread_had_one(two_threads):
    """threadpoolctl 3.8 keeps the control of OpenBLAS's thread count with the thread that set it until it leaves a
    ``with`` block: a limit set and restored without one (issue 52's first try) left the main thread in control and
    the job thread's limit was silently ignored (the job then ran multi-threaded beside the main thread's BLAS)."""
    with threads.blas_limited():
        assert blas_threads() == [threads.BLAS_THREADS] * len(two_threads)
    assert blas_threads() == two_threads
    seen = []

    def job():
        with threads.blas_limited():
            seen.append(blas_threads())
        seen.append(blas_threads())

    t = threading.Thread(target=job)
    t.start()
    t.join()
    assert seen == [[threads.BLAS_THREADS] * len(two_threads), two_threads]
