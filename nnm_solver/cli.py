"""nnm-solve: list the linear modes of a model file, or compute and save an NNM branch.

    nnm-solve FILE --list-modes
    nnm-solve FILE --mode N --energy-max E [--out OUT.h5] [--plot fep.png]

FILE is an nnm HDF5 file or a MATLAB .mat file (M, K, springs = [dof other k3], 1-based).
Ctrl-C stops the continuation and saves the points computed so far.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from .errors import NNMInputError


def _load(path):
    from .io import load_extra, load_model
    from .matio import load_mat_model

    p = Path(path)
    if p.suffix.lower() == ".mat":
        return load_mat_model(p), None
    model = load_model(p)
    ref = load_extra(p, "reference")
    return model, ref


def list_modes(model, reference=None, count=30, out=sys.stdout):
    freqs, _ = model.linear_modes()
    labels = model.mode_labels or []
    table = None
    if reference and "table2_hz" in reference:
        table = np.asarray(reference["table2_hz"], dtype=float)
    head = f"{'mode':>4}  {'freq (Hz)':>11}"
    if table is not None:
        head += f"  {'reference':>10}  {'diff':>7}"
    print(head + "  label", file=out)
    for k in range(min(count, model.n)):
        line = f"{k + 1:>4}  {freqs[k]:>11.4f}"
        if table is not None:
            if k < len(table):
                line += f"  {table[k]:>10.4f}  {100 * (freqs[k] / table[k] - 1):>+6.2f}%"
            else:
                line += " " * 21
        label = labels[k] if k < len(labels) else ""
        print(line + ("  " + label if label else ""), file=out)


def _progress(job, stream):
    width = 30
    while not job.done:
        f = job.progress
        pts = job.points()
        e = pts.energy[-1] if len(pts) else float("nan")
        fr = pts.frequency_hz[-1] if len(pts) else float("nan")
        bar = "#" * int(width * f) + "-" * (width - int(width * f))
        stream.write(f"\r[{bar}] {100 * f:5.1f}%  {len(pts):4d} points  E = {e:.3e} J  f = {fr:.5f} Hz ")
        stream.flush()
        time.sleep(0.2)
    stream.write("\n")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="nnm-solve", description=__doc__.split("\n\n")[0])
    parser.add_argument("file", help="model file (.h5 nnm file or .mat)")
    parser.add_argument("--list-modes", action="store_true", help="print the linear natural frequencies")
    parser.add_argument("--count", type=int, default=24, help="number of modes listed (default 24)")
    parser.add_argument("--mode", type=int, help="linear mode to continue (1-based)")
    parser.add_argument("--energy-max", type=float, help="energy (J) where the continuation stops")
    parser.add_argument("--energy-min", type=float, default=None, help="energy (J) of the first point")
    parser.add_argument("--steps-per-period", type=int, default=200)
    parser.add_argument("--tol", type=float, default=1e-6, help="relative periodicity tolerance")
    parser.add_argument("--max-points", type=int, default=500)
    parser.add_argument("--out", help="HDF5 file the branch is appended to (default: FILE, or FILE.h5 for .mat)")
    parser.add_argument("--plot", help="save the frequency-energy plot to this image file")
    args = parser.parse_args(argv)
    try:
        return _run(args)
    except NNMInputError as exc:
        print(f"nnm-solve: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"nnm-solve: error: {exc}", file=sys.stderr)
        return 2


def _run(args):
    from .io import save_branch
    from .jobs import start_branch

    model, ref = _load(args.file)
    if args.list_modes:
        list_modes(model, ref, args.count)
        return 0
    if args.mode is None or args.energy_max is None:
        raise NNMInputError("give --list-modes, or --mode N and --energy-max E to compute a branch")
    out = Path(args.out) if args.out else Path(args.file)
    if out.suffix.lower() == ".mat":
        out = out.with_suffix(".h5")
    if args.plot and not Path(args.plot).resolve().parent.is_dir():
        raise NNMInputError(f"cannot write the plot: folder {Path(args.plot).parent} does not exist")
    job = start_branch(model, args.mode, args.energy_max, steps_per_period=args.steps_per_period, tol=args.tol,
                       max_points=args.max_points, energy_min=args.energy_min)
    t0 = time.perf_counter()
    try:
        _progress(job, sys.stderr)
    except KeyboardInterrupt:
        sys.stderr.write("\ninterrupted: stopping after the current point and saving the points computed so far\n")
        job.cancel()
    try:
        branch = job.result()
    except KeyboardInterrupt:
        branch = job.points()
    except NNMInputError:
        raise
    except Exception as exc:  # a solver failure: keep what was computed
        print(f"nnm-solve: the continuation failed: {exc}", file=sys.stderr)
        branch = job.points()
    dt = time.perf_counter() - t0
    print(f"mode {args.mode}: {len(branch)} points in {dt:.1f} s, energy {branch.energy.min():.3e}.."
          f"{branch.energy.max():.3e} J, frequency {branch.frequency_hz[0]:.5f} -> {branch.frequency_hz[-1]:.5f} Hz; "
          f"{branch.status}: {branch.message}" if len(branch) else f"no point converged: {branch.message}")
    for e in branch.events:
        print(f"  {e['kind']:<12} at point {e['index']:>4}: E = {e['energy']:.4e} J, f = {e['frequency_hz']:.5f} Hz"
              f"  ({e['detail']})")
    if len(branch):
        name = save_branch(out, branch)
        print(f"saved as /branches/{name} in {out}")
        if args.plot:
            from .plotting import plot_fep
            plot_fep(branch, path=args.plot, title=f"{model.name or Path(args.file).stem}: NNM {args.mode}")
            print(f"FEP written to {args.plot}")
    return 0 if branch.status in ("done", "max_points", "cancelled") else 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
