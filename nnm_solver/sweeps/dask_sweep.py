r"""NNM atlases and parameter sweeps on Dask: many branches (modes x model variants) in parallel.

    branches = nnm.sweep(model, "10-24", energy_max=100.0, out="atlas.h5", max_points=150)
    branches = nnm.sweep(model, [1, 2], 10.0, variants=nnm.variant_grid(spring_factor=[0.5, 1, 2]),
                         client="tcp://host:8786")
    nnm.plot_atlas(branches, path="atlas.png")

Each continuation is sequential, so the parallelism is across branches: every (variant, mode) pair
is one Dask task running ``continue_nnm`` on a worker.  ``client`` is a ``dask.distributed.Client``,
a scheduler address, an int (that many local worker processes) or None (a ``LocalCluster`` with one
worker process per core, one thread per worker and one BLAS thread per process).  Each variant's
model is built on the client, its linear modes computed once, and sent to the workers once
(``scatter``, without the display mesh); each finished branch comes back as plain columns
(``as_completed``) and the client, never a worker, appends it to ``out`` atomically
(``save_branch``), under the name ``<variant>:mode<N>``.  A crash or Ctrl-C keeps every finished
branch in the file, and a rerun with the same ``out`` skips the branches already there.

Dask is imported only when a sweep runs (``pip install "nnm[cluster]"``); importing nnm_solver does
not import it.  Sweep-level keywords, taken out of ``continuation_options``:

* ``progress``: True (a progress bar on stderr), or callable(SweepProgress) called about 5 times a
  second and after each finished branch, in the calling thread (raising KeyboardInterrupt there
  acts as Ctrl-C);
* ``stop``: a threading.Event-like object; once set, the branches not finished are cancelled
  (status 'cancelled', nothing saved for them) and ``sweep`` returns.

A worker that dies while computing a branch (killed, out of memory) has its branch retried on
another worker by Dask (``distributed.scheduler.allowed-failures`` times, 3 by default), then
reported: that branch has status 'failed', a message saying the worker died, and no points.
Scripts that start a local cluster must call ``sweep`` under ``if __name__ == "__main__":`` (the
worker processes are spawned and import the main module).
"""
from __future__ import annotations

import os
import time
import uuid
from pathlib import Path

import numpy as np

from ..results.branch import Branch
from ..driver.api import continue_nnm, from_keywords
from ..errors import NNMInputError
from ..model.model import Model
from .progress import SweepProgress, reporter
from ..files.sweep_groups import branch_name, parse_branch_name  # noqa: F401
from .spec import as_variants, parse_modes
from .sweep_files import load_sweep, prepare_file  # noqa: F401
from .settings import SWEEPS

__all__ = ["sweep", "load_sweep", "SweepProgress", "branch_name", "parse_branch_name", "WORKER_ENV"]

#: environment of local worker processes: one BLAS / OpenMP thread each (the solver also limits
#: BLAS threads itself while it computes points, threads.py), and no worker threads for the multipliers (one
#: process per core keeps every core busy already)
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1", "MALLOC_TRIM_THRESHOLD_": "65536", "NNM_SPECTRUM_WORKERS": "0"}

#: an alias of settings.py's SWEEPS.event_interval (the code reads that)
EVENT_INTERVAL = SWEEPS.event_interval

#: an alias of settings.py's SWEEPS.connect_timeout (the code reads that)
CONNECT_TIMEOUT = SWEEPS.connect_timeout


def _compute(model, variant, mode, energy_max, options, topic):
    """One branch on a worker: continue_nnm, streamed progress, the columns sent back (not the model)."""
    t0, c0 = time.perf_counter(), time.thread_time()
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        worker = None
    name = branch_name(variant, mode)
    info = {"worker": getattr(worker, "address", ""), "pid": os.getpid()}
    count, last = 0, 0.0

    def on_point(point):
        nonlocal count, last
        count += 1
        now = time.perf_counter()
        if worker is not None and topic and (count == 1 or now - last >= SWEEPS.event_interval):
            last = now
            worker.log_event(topic, {"name": name, "points": count, "energy": float(point.energy), **info})

    try:
        b = continue_nnm(model, mode, energy_max, on_point=on_point, **options)
        payload = {k: getattr(b, k) for k in ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable",
                                              "coefficients", "events", "status", "message", "settings",
                                              "freq_error", "steps", "labels", "tongues", "fundamental_share")}
    except Exception as exc:  # reported per branch, never raised on the worker
        payload = {"status": "failed", "message": f"the solver raised {type(exc).__name__}: {exc}"}
    payload.update(info, seconds=time.perf_counter() - t0, cpu_seconds=time.thread_time() - c0)
    return payload


# ---------------------------------------------------------------------- on the client
def _empty(model, mode, name, status, message):
    return Branch(model, mode, [], [], [], [], [], status=status, message=message, name=name)


def _branch_from(model, mode, name, payload):
    cols = {k: payload[k] for k in ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable",
                                    "coefficients", "events", "settings", "freq_error", "steps", "labels", "tongues",
                                    "fundamental_share") if k in payload}
    if "energy" not in cols:
        return _empty(model, mode, name, payload["status"], payload["message"])
    return Branch(model, mode, status=payload["status"], message=payload["message"], name=name, **cols)


def _worker_model(model):
    """The model as sent to the workers: matrices, springs and the linear modes already computed."""
    light = Model(model.M, model.K, model.springs, name=model.name)
    light.__dict__["eigensolution"] = model.eigensolution
    return light


class _AlreadySet:
    @staticmethod
    def is_set():
        return True


def _check_options(model, mode, energy_max, options):
    """Bad continuation options raise NNMInputError here, before anything is sent to a cluster."""
    if "on_point" in options:
        raise NNMInputError("on_point is not available in a sweep (points are computed on the workers); "
                            "use progress=callable(SweepProgress)")
    continue_nnm(model, mode, energy_max, stop=_AlreadySet(), **options)   # checks, then stops at once


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise NNMInputError('nnm.sweep runs on Dask, which is not installed: pip install "nnm[cluster]" '
                            '(or pip install "dask[distributed]")') from None
    return distributed


def _connect(client, n_tasks):
    """(client, owned): the Client to use, and what to close afterwards (None, 'client' or the cluster)."""
    dd = _import_distributed()
    if isinstance(client, dd.Client):
        return client, None
    if isinstance(client, str):
        try:
            return dd.Client(client, timeout=SWEEPS.connect_timeout), "client"
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise NNMInputError(
                f"cannot reach the Dask scheduler at {client!r} ({type(exc).__name__}: {exc}); check the address "
                f"(tcp://host:8786) and that `dask scheduler` runs there with workers (`dask worker {client}`)"
            ) from None
    if client is None or (isinstance(client, (int, np.integer)) and not isinstance(client, bool) and client > 0):
        import dask

        n = int(client) if client else max(1, min(os.cpu_count() or 1, n_tasks))
        try:
            with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
                cluster = dd.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                                          env=dict(WORKER_ENV))
        except Exception as exc:
            raise NNMInputError(
                f"could not start {n} local Dask worker processes ({type(exc).__name__}: {exc}); in a script, "
                f"call nnm.sweep under `if __name__ == \"__main__\":` (workers are spawned processes)") from None
        try:
            return dd.Client(cluster), cluster
        except BaseException:
            cluster.close()
            raise
    raise NNMInputError(f"client must be a dask.distributed.Client, a scheduler address such as 'tcp://host:8786', "
                        f"a number of local workers or None, got {client!r}")


def sweep(model, modes, energy_max, variants=None, client=None, out=None, **continuation_options):
    """Compute the NNM branches of ``modes`` for every model variant, in parallel on Dask.

    Parameters
    ----------
    model : Model.  modes : mode numbers (1-based): an int, a sequence, or a string like "10-24" / "1,3,5-7".
    energy_max : energy (J) where each continuation stops.
    variants : None (the model as it is), a Variant, or a list of Variants (``variant_grid``,
        ``load_sweep_file``); branch names are ``<variant>:mode<N>`` ("base" for the model itself).
    client : a dask.distributed.Client, a scheduler address ("tcp://host:8786"), a number of local
        worker processes, or None (a LocalCluster, one process per core, created and closed here).
    out : nnm HDF5 file each finished branch is appended to (created with ``model`` if absent;
        branches already there are not computed again); None: nothing is saved.
    continuation_options : keywords of ``continue_nnm`` (steps_per_period, tol, max_points, method, ...),
        plus ``progress`` and ``stop`` (module docstring).

    Returns the list of Branches in (variant, mode) order; each has ``branch.model`` = its variant's
    model and ``branch.sweep_info`` (variant, source 'computed' / 'file' / 'cancelled' / 'lost',
    worker, pid, seconds: wall time of the branch on its worker, cpu_seconds: CPU time of its thread).
    Bad input raises NNMInputError before any work is sent.  Ctrl-C cancels the branches not finished
    (the finished ones are in ``out``) and raises KeyboardInterrupt.
    """
    options = dict(continuation_options)
    progress = options.pop("progress", None)
    stop = options.pop("stop", None)
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    variants = as_variants(variants)
    modes = parse_modes(modes)
    models = [v.apply(model) for v in variants]
    for m in models:
        for mode in modes:
            m.check_mode(mode)
    _check_options(models[0], modes[0], energy_max, options)
    tasks = [(vi, mode, branch_name(v, mode)) for vi, v in enumerate(variants) for mode in modes]
    results = [None] * len(tasks)
    state = SweepProgress(total=len(tasks))
    report = reporter(progress)
    if out is not None:
        out = Path(out)
        request = from_keywords(options.get("method"), options.get("continuation"), options.get("tongues"),
                                {k: v for k, v in options.items() if k not in ("method", "continuation", "tongues", "floquet",
                                                                             "locate_events", "energy_min")})[:2]
        found = prepare_file(out, model, variants, energy_max, {t[2] for t in tasks}, request)
        for i, (vi, mode, name) in enumerate(tasks):
            if name in found:
                b = found[name]
                b.model = models[vi]
                b.sweep_info = {"variant": variants[vi].name, "source": "file"}
                results[i] = b
                state.skipped += 1
    todo = [i for i, r in enumerate(results) if r is None]
    if todo:
        _run(client, variants, models, tasks, todo, energy_max, options, out, results, state, report, stop)
    report(state, final=True)
    return results


def _run(client_arg, variants, models, tasks, todo, energy_max, options, out, results, state, report, stop):
    from ..files.branch_io import save_branch

    dd = _import_distributed()
    client, owned = _connect(client_arg, len(todo))
    topic = f"nnm-sweep-{uuid.uuid4().hex[:12]}"
    futures = {}
    pending_names = set()
    scattered = {}
    resubmitted = [0] * len(tasks)
    token = uuid.uuid4().hex[:8]

    def submit(i):
        """Submit task i, its variant's model scattered to every worker (again where the cluster lost it)."""
        vi, mode, name = tasks[i]
        if vi not in scattered or scattered[vi].status != "finished":
            scattered[vi] = client.scatter(_worker_model(models[vi]), broadcast=True, hash=False)
        fut = client.submit(_compute, scattered[vi], variants[vi].name, mode, energy_max, options, topic,
                            key=f"nnm-{name}-{token}-{resubmitted[i]}", pure=False)
        futures[fut] = i
        pending_names.add(name)
        return fut

    def on_event(event):  # in the client's event-loop thread
        msg = event[1]
        name = msg.get("name")
        if name in pending_names:
            state.running[name] = int(msg.get("points", 0))
            state.workers[name] = {"worker": msg.get("worker", ""), "pid": msg.get("pid")}

    def finish(fut):
        i = futures.pop(fut)
        vi, mode, name = tasks[i]
        exc = fut.exception() if fut.status == "error" else None
        killed = exc is not None and type(exc).__name__ == "KilledWorker"
        if fut.status in ("cancelled", "lost") and stop is not None and stop.is_set():
            futures[fut] = i                  # stopped: reported cancelled with the rest (below, finally)
            return
        if fut.status in ("cancelled", "lost") and resubmitted[i] < SWEEPS.lost_retries:
            # the cluster cancelled the branch without an error of its own: the model scattered to the workers was
            # lost (Dask's memory manager drops the copies on workers that no running task needs, keeping one, and
            # the worker holding that one died), so the branch is submitted again with the model scattered anew
            resubmitted[i] += 1
            state.running.pop(name, None)
            try:
                ac.add(submit(i))
                return
            except Exception:                 # no worker to scatter to within the client's timeout: lost
                pass
        pending_names.discard(name)
        state.running.pop(name, None)
        info = {"variant": variants[vi].name, "source": "computed"}
        if fut.status == "finished":
            payload = fut.result()
            b = _branch_from(models[vi], mode, name, payload)
            info.update(worker=payload.get("worker", ""), pid=payload.get("pid"), seconds=payload.get("seconds"),
                        cpu_seconds=payload.get("cpu_seconds"))
        else:
            if killed:
                msg = (f"the worker computing this branch died (killed, out of memory or crashed) and so did its "
                       f"retries ({exc}); nothing was saved for it: run the sweep again with the same out file to "
                       f"retry it")
            else:
                msg = (f"the cluster lost this branch ({type(exc).__name__ + ': ' + str(exc) if exc else fut.status}); "
                       f"nothing was saved for it: run the sweep again with the same out file to retry it")
            b = _empty(models[vi], mode, name, "failed", msg)
            info["source"] = "lost"
        b.sweep_info = info
        results[i] = b
        state.finished += 1
        state.failed += b.status == "failed"
        state.points += len(b)
        if out is not None and len(b):
            save_branch(out, b)

    try:
        client.subscribe_topic(topic, on_event)
        for i in todo:
            submit(i)
        ac = dd.as_completed(list(futures), raise_errors=False)
        last = 0.0
        while not ac.is_empty():
            if stop is not None and stop.is_set():
                break
            got = False
            while ac.has_ready():
                finish(next(ac))
                got = True
            now = time.perf_counter()
            if got or now - last >= 0.2:
                report(state)
                last = now
            if not got:
                time.sleep(0.05)
    finally:
        for fut, i in list(futures.items()):  # stopped, interrupted or failed: cancel what is left
            vi, mode, name = tasks[i]
            b = _empty(models[vi], mode, name, "cancelled",
                       "the sweep was stopped before this branch finished; run it again with the same out file to "
                       "compute it")
            b.sweep_info = {"variant": variants[vi].name, "source": "cancelled"}
            results[i] = b
            state.cancelled += 1
        state.running.clear()
        pending_names.clear()
        try:
            if futures:
                client.cancel(list(futures))
            client.unsubscribe_topic(topic)
        except Exception:  # the connection may be gone already
            pass
        if owned is not None:
            client.close()
            if owned != "client":
                owned.close()
