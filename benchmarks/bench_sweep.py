"""Sweep benchmark: the same NNM branches serially in one process and with ``nnm.sweep`` on local Dask workers.

Usage (from the repository root; needs ``pip install -e ".[cluster]"``)::

    python benchmarks/bench_sweep.py                          # paris modes 10-24, 12 points each, 2 workers
    python benchmarks/bench_sweep.py --max-points 30 --workers 2 --modes 10-24 --energy-max 100
    python benchmarks/bench_sweep.py --no-serial              # the parallel run only

In one run it measures

1. serial: ``continue_nnm`` for every mode, one after the other, in this process (after a warm-up
   branch, so numba's compiled kernels are loaded);
2. the engine's per-branch overhead: a sweep of many trivial branches (2-DOF model, 2 points each)
   on the workers; overhead per branch = wall x workers / branches - compute time per branch (this
   also warms the workers up, as the serial warm-up does for this process);
3. parallel: ``nnm.sweep(model, modes, energy_max, client=<LocalCluster of --workers processes, one
   thread each>)``: wall time, the workers' compute time, speed-up = serial wall / parallel wall
   (cluster start-up shown apart), worker memory (RSS) after the sweep, and whether every branch
   equals its serial twin point for point.

The 1-minute load average (``os.getloadavg``) is printed before and after each run: on a shared
machine, other jobs take cores from the workers and the speed-up drops accordingly.  The CPU
seconds of the serial process and of the workers' solver threads (``time.thread_time`` per branch)
show whether the work itself differs: equal CPU and longer wall time means the cores were busy
with something else.  The last line gives the CPU-bound speed-up, serial CPU time / the busiest
worker's CPU time: the speed-up on cores that nothing else uses (it includes the imbalance of the
last branches, not the cluster start-up).
"""
from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def load():
    return os.getloadavg()[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--file", default=str(ROOT / "assets" / "paris.h5"))
    ap.add_argument("--modes", default="10-24")
    ap.add_argument("--energy-max", type=float, default=100.0)
    ap.add_argument("--max-points", type=int, default=12)
    ap.add_argument("--steps-per-period", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--overhead-branches", type=int, default=40)
    ap.add_argument("--no-serial", action="store_true")
    args = ap.parse_args()

    import dask
    import distributed

    import nnm_solver as nnm
    sweeps = sys.modules["nnm_solver.sweeps.dask_sweep"]

    model = nnm.load_model(args.file)
    from nnm_solver.sweeps.spec import parse_modes

    modes = parse_modes(args.modes)
    opts = dict(max_points=args.max_points, steps_per_period=args.steps_per_period)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, dask {dask.__version__}, distributed {distributed.__version__}")
    print(f"model: {args.file} ({model.n} DOFs, {len(model.springs)} springs), modes {args.modes}, energy_max "
          f"{args.energy_max:g} J, {opts}")
    model.eigensolution  # noqa: B018  (computed once; the sweep sends it to the workers)
    two = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), [nnm.CubicSpring(dof=0, k3=0.5)])

    serial, t_serial = {}, None
    if not args.no_serial:
        nnm.continue_nnm(two, 1, 1.0, max_points=3)   # warm-up: numba kernels loaded
        l0 = load()
        t0, c0 = time.perf_counter(), time.process_time()
        for mode in modes:
            t1 = time.perf_counter()
            serial[mode] = nnm.continue_nnm(model, mode, args.energy_max, **opts)
            b = serial[mode]
            print(f"  serial mode {mode:2d}: {len(b):3d} points, {time.perf_counter() - t1:6.1f} s, {b.status}",
                  flush=True)
        t_serial, cpu_serial = time.perf_counter() - t0, time.process_time() - c0
        ls = load()
        print(f"serial: {t_serial:.1f} s, load {l0:.2f} -> {ls:.2f}", flush=True)

    l0 = load()
    t0 = time.perf_counter()
    with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
        cluster = distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                           dashboard_address=None, env=dict(sweeps.WORKER_ENV))
    client = distributed.Client(cluster)
    t_start = time.perf_counter() - t0
    print(f"cluster of {args.workers} workers started in {t_start:.1f} s", flush=True)
    try:
        # per-branch overhead of the engine: many trivial branches
        n_over = args.overhead_branches
        variants = [nnm.Variant(name=f"v{i}", spring_factor=1.0 + 1e-3 * i) for i in range(n_over // 2)]
        nnm.sweep(two, [1, 2], 1.0, variants=variants[:2], client=client, max_points=2)   # workers warm
        t1 = time.perf_counter()
        tiny = nnm.sweep(two, [1, 2], 1.0, variants=variants, client=client, max_points=2)
        t_tiny = time.perf_counter() - t1
        c_tiny = float(np.mean([b.sweep_info["seconds"] for b in tiny]))
        over = t_tiny * args.workers / len(tiny) - c_tiny
        print(f"overhead: {len(tiny)} trivial branches in {t_tiny:.2f} s on {args.workers} workers; compute "
              f"{1e3 * c_tiny:.1f} ms/branch; engine overhead {1e3 * over:.1f} ms/branch", flush=True)

        l1 = load()
        t1 = time.perf_counter()
        par = nnm.sweep(model, modes, args.energy_max, client=client, **opts)
        t_par = time.perf_counter() - t1
        l2 = load()
        busy = sum(b.sweep_info["seconds"] for b in par)
        cpu_par = sum(b.sweep_info["cpu_seconds"] for b in par)
        rss = client.run(lambda: __import__("psutil").Process().memory_info().rss)
        for b in par:
            print(f"  sweep mode {b.mode:2d}: {len(b):3d} points, {b.sweep_info['seconds']:6.1f} s on "
                  f"{b.sweep_info['worker']}, {b.status}")
        print(f"parallel: {t_par:.1f} s (+ {t_start:.1f} s cluster start-up), workers busy {busy:.1f} s "
              f"({100 * busy / (args.workers * t_par):.0f} % of {args.workers} x wall), load {l1:.2f} -> {l2:.2f}; "
              f"worker RSS {', '.join(f'{r / 2**20:.0f} MB' for r in rss.values())}")
    finally:
        client.close()
        cluster.close()

    same = None
    if serial:
        diffs = [len(serial[b.mode]) == len(b) and np.array_equal(serial[b.mode].frequency_hz, b.frequency_hz)
                 and np.array_equal(serial[b.mode].x0, b.x0) for b in par]
        same = all(diffs)
    n_points = sum(len(b) for b in par)
    print()
    print("| run | wall (s) | speed-up | CPU s (solver threads) | load avg 1 min (before -> after) |")
    print("|---|---|---|---|---|")
    if t_serial is not None:
        print(f"| serial, 1 process | {t_serial:.1f} | 1.00 | {cpu_serial:.1f} | {l0:.2f} -> {ls:.2f} |")
        print(f"| sweep, {args.workers} workers (sweep only) | {t_par:.1f} | {t_serial / t_par:.2f} | {cpu_par:.1f} | "
              f"{l1:.2f} -> {l2:.2f} |")
        print(f"| sweep, {args.workers} workers (+ cluster start-up) | {t_par + t_start:.1f} | "
              f"{t_serial / (t_par + t_start):.2f} | | |")
    print()
    per_worker = {}
    for b in par:
        per_worker[b.sweep_info["worker"]] = per_worker.get(b.sweep_info["worker"], 0.0) + b.sweep_info["cpu_seconds"]
    print(f"{len(par)} branches, {n_points} points; engine overhead {1e3 * over:.1f} ms per branch; "
          f"parallel == serial point for point: {same}")
    print(f"CPU s per worker: {', '.join(f'{c:.1f}' for c in per_worker.values())}", end="")
    if t_serial is not None:
        print(f"; with a free core per worker the sweep would take about max = {max(per_worker.values()):.1f} s: "
              f"CPU-bound speed-up {cpu_serial / max(per_worker.values()):.2f} (serial CPU / busiest worker's CPU)")
    else:
        print()


if __name__ == "__main__":
    main()
