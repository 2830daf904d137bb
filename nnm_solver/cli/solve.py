"""nnm-solve: list the linear modes of a model file, or compute and save an NNM branch.

    nnm-solve FILE --list-modes
    nnm-solve FILE --mode N --energy-max E [--tongues skip|follow] [--out OUT.h5] [--plot fep.png]
    nnm-solve FILE --tongue K [--branch NAME | --mode N]     nnm-solve FILE --switch K --energy-max E [--branch NAME]
    nnm-solve FILE --modes 10-24 --energy-max E [--sweep SWEEP.toml] [--workers N | --scheduler ADDRESS]

    nnm-solve FILE --mode N --energy-max E [--csv T.csv] [--uff S.uff] [--backbone B.csv --backbone-dof DOF]
    nnm-solve import MODEL.toml --out MODEL.h5      nnm-solve export FILE.h5 [--branch NAME] --csv ...

FILE is an nnm HDF5 file, a MATLAB .mat file (M, K, springs = [dof other k3], 1-based), a model
description .toml (MatrixMarket / Abaqus / ANSYS / MATLAB matrices, springs, units, display mesh)
or an ANSYS .full file (docs/import.md).
Ctrl-C stops the continuation and saves the points computed so far.
"""
from __future__ import annotations

import argparse
import sys
import time

from ..errors import NNMInputError, run_reporting_errors
from .defaults import TONGUE_CHOICES, solver_defaults
from .report import accuracy_line, report_and_save  # noqa: F401 (accuracy_line: part of the cli's API)
from .modes import list_modes
from .branch_options import continuation_options, load_input, method_arguments
from .outputs import check_plot_path, output_file


def _progress(job, stream, interval=0.2):
    """One progress line, rewritten in place until the job is done (the latest point's E and f once
    there is one; before it, the time waited: the first run after installing compiles the solver).  Into a
    file or a pipe (not a terminal): one line per new point, nothing rewritten."""
    width = 30
    t0 = time.perf_counter()
    last = 0
    isatty = getattr(stream, "isatty", None)
    if not (callable(isatty) and isatty()):
        shown = 0
        while True:
            done = job.done                 # (read first: the rows read after it include the last point's)
            for i, (energy, freq) in enumerate(job.rows(shown), start=shown):
                stream.write(f"point {i + 1:4d}  E = {energy:.4e} J  f = {freq:.6f} Hz\n")
                shown = i + 1
            stream.flush()
            if done:
                return
            time.sleep(interval)
    while not job.done:
        f = job.progress
        count, energy, freq = job.latest()
        bar = "#" * int(width * f) + "-" * (width - int(width * f))
        if count:
            text = (f"[{bar}] {100 * f:5.1f}%  {count:4d} points  E = {energy:.3e} J  "
                    f"f = {freq:.5f} Hz")
        else:
            text = (f"[{bar}] waiting for the first point ({time.perf_counter() - t0:.0f} s; the first run "
                    f"compiles the solver)")
        stream.write("\r" + text.ljust(last))
        last = len(text)
        stream.flush()
        time.sleep(interval)
    stream.write("\n")


def main(argv=None):
    from . import exchange as cli_exchange

    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in cli_exchange.SUBCOMMANDS:     # nnm-solve import ... / nnm-solve export ...
        return cli_exchange.main(argv)
    parser = argparse.ArgumentParser(prog="nnm-solve", description=__doc__.split("\n\n")[0],
                                     epilog="nnm-solve import MODEL --out MODEL.h5 / nnm-solve export FILE.h5 ...: "
                                     "see nnm-solve import -h, nnm-solve export -h")
    parser.add_argument("file", help="model file: .h5 nnm file, .mat, .toml model description or ANSYS .full")
    parser.add_argument("--list-modes", action="store_true", help="print the linear natural frequencies")
    parser.add_argument("--count", type=int, default=24, help="number of modes listed (default 24)")
    parser.add_argument("--mode", type=int, help="linear mode to continue (1-based)")
    parser.add_argument("--energy-max", type=float, help="energy (J) where the continuation stops")
    parser.add_argument("--energy-min", type=float, default=None, help="energy (J) of the first point")
    D = solver_defaults()
    parser.add_argument("--method", choices=("shooting", "hb"), default=None, help=f"shooting (Gauss-Legendre or "
                        f"Newmark time integration, the seed paper's method) or hb (harmonic balance); default "
                        f"{D['method']}")
    parser.add_argument("--harmonics", type=int, default=None, help=f"hb: highest harmonic (default {D['harmonics']})")
    parser.add_argument("--condensed", action="store_true", help="hb: solve the harmonic balance condensed onto "
                        "the nonlinear elements (unknowns: their deformations per harmonic; for models of any size "
                        "whose nonlinearity is localized)")
    parser.add_argument("--steps-per-period", type=int, default=None, metavar="STEPS",
                        help=f"shooting: time steps per period of each orbit (default {D['steps_per_period']}; rounded "
                        f"up to a multiple of 4 for the quarter-period shooting of symmetric orbits; the integrator's own "
                        f"default, newmark 200). The frequency error falls as STEPS^-6 with gauss6, STEPS^-2 with "
                        f"newmark: raise it for orbits with strong higher harmonics (high-order tongues), or use "
                        f"--freq-tol")
    parser.add_argument("--integrator", default=None, help=f"time integrator of the shooting: gauss6 or "
                        f"gauss4 (Gauss-Legendre, orders 6 and 4), or newmark (the seed paper's, order 2); default "
                        f"{D['integrator']}")
    parser.add_argument("--freq-tol", type=float, default=None, help="accuracy target: raise the steps per period "
                        "(hb: the harmonics) where a point's estimated relative frequency error exceeds this "
                        f"(default {D['freq_tol']:g}; e.g. 1e-6)")
    parser.add_argument("--tol", type=float, default=None, help="relative periodicity tolerance (default 1e-6; "
                        "hb: relative residual, default 1e-8)")
    parser.add_argument("--floquet", action="store_true", help="compute the Floquet multipliers (stability, "
                        "branch points) at every point also where the default leaves them out (harmonic balance of a "
                        "large model, driver/problems.hb_floquet_default)")
    parser.add_argument("--max-points", type=int, default=None, metavar="N",
                        help=f"largest number of points of the branch (default {D['max_points']}); the continuation "
                        f"stops there if --energy-max is not reached first (status max_points)")
    parser.add_argument("--tongues", choices=TONGUE_CHOICES, default=None,
                        help=f"at an internal-resonance tongue: follow the branch through it (follow: tongues up to "
                        f"3:1, higher orders jumped; follow-all: every tongue), or skip it and return the backbone "
                        f"(the tongues jumped are listed with the branch and saved with it; --tongue K continues "
                        f"one); default {D['tongues']}")
    family = parser.add_mutually_exclusive_group()
    family.add_argument("--tongue", type=int, metavar="K", help="continue the K-th tongue (1-based, as listed after "
                        "a --tongues skip run) of a saved branch of FILE as its own branch (nnm.continue_tongue); "
                        "--energy-max is optional (default 100 x the entry energy)")
    family.add_argument("--switch", type=int, metavar="K", help="continue the family born at the K-th branch point "
                        "or period doubling (1-based, as listed after a run) of a saved branch of FILE "
                        "(nnm.switch_branch); needs --energy-max")
    parser.add_argument("--branch", metavar="NAME", help="--tongue / --switch: the saved branch to start from (its "
                        "name in FILE or its 1-based number; default: the last branch of --mode N that has one)")
    parser.add_argument("--out", help="HDF5 file the branch is appended to (default: FILE, or FILE.h5 for .mat; "
                        "./STEM_branches.h5 if that is a shipped example or not writable)")
    parser.add_argument("--plot", help="save the frequency-energy plot to this image file")
    parser.add_argument("--modes", help="sweep: modes to compute in parallel on Dask, e.g. 10-24 or 1,3,5-7")
    parser.add_argument("--sweep", metavar="SWEEP.toml", help="sweep: model variants (and modes, energy_max, "
                        "options) from a TOML file (docs/sweep.md)")
    forced = parser.add_argument_group("forced response (docs/forced.md)")
    forced.add_argument("--forced", action="store_true", help="compute a forced response (harmonic balance with "
                        "modal damping) instead of an NNM branch; saved under /forced in the output file")
    forced.add_argument("--force-dof", type=int, action="append", metavar="DOF", help="forced DOF (0-based; "
                        "repeat for several)")
    forced.add_argument("--force", type=float, action="append", metavar="N", help="force amplitude (N) at each "
                        "--force-dof, in the same order (one value: the same at every DOF)")
    forced.add_argument("--f-range", type=float, nargs=2, metavar=("F_START", "F_END"), help="frequency range (Hz)")
    forced.add_argument("--damping", type=float, default=0.01, help="modal damping ratio of every mode (default 0.01)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, help="sweep: local worker processes (default: one per core)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="sweep: address of a running Dask scheduler, "
                       "e.g. tcp://host:8786")
    cli_exchange.add_export_arguments(parser)
    args = parser.parse_args(argv)
    stray = _stray_flags(args, parser)
    if stray:
        return run_reporting_errors("nnm-solve", _refuse_stray, stray)
    if args.modes or args.sweep:
        from .sweep_run import run_sweep
        return run_reporting_errors("nnm-solve", run_sweep, args, parser)
    if args.forced:
        from .forced_run import run_forced
        return run_reporting_errors("nnm-solve", run_forced, args)
    if args.tongue is not None or args.switch is not None:
        return run_reporting_errors("nnm-solve", _run_family, args)
    return run_reporting_errors("nnm-solve", _run, args)


def _stray_flags(args, parser):
    """(flags, what they belong to) for the flags of a forced response given without --forced, or a sweep's
    (--workers, --scheduler) without --modes / --sweep (they were silently ignored); None when there are none."""
    if not args.forced:
        forced = {"--force-dof": args.force_dof, "--force": args.force, "--f-range": args.f_range,
                  "--damping": args.damping if args.damping != parser.get_default("damping") else None}
        given = [flag for flag, value in forced.items() if value is not None]
        if given:
            return given, "--forced (a forced response)"
    if not (args.modes or args.sweep):
        given = [flag for flag, value in (("--workers", args.workers), ("--scheduler", args.scheduler))
                 if value is not None]
        if given:
            return given, "--modes / --sweep (a sweep on Dask)"
    return None


def _refuse_stray(stray):
    flags, owner = stray
    raise NNMInputError(f"{', '.join(flags)}: {'go' if len(flags) > 1 else 'goes'} with {owner}; add it or leave "
                        f"{'them' if len(flags) > 1 else 'it'} out")


def _check_arguments(model, args):
    """NNMInputError for a mode out of range, a non-positive --energy-max, --tol, --max-points or
    --energy-min (the checks continue_nnm makes, done before anything is printed or written)."""
    from ..driver.api import check_branch_arguments
    from ..model.settings import MODEL

    check_branch_arguments(model, args.mode, args.energy_max, 1e-6 if args.tol is None else args.tol,
                           solver_defaults()["max_points"] if args.max_points is None else args.max_points,
                           args.energy_min, modes_known=model.n <= MODEL.max_dense_dof)


def _run(args):
    from . import exchange as cli_exchange
    from ..files.branch_io import check_branch_file
    from ..driver.jobs import start_branch

    model, ref = load_input(args.file)
    if args.list_modes:
        if args.count < 1:
            raise NNMInputError(f"--count must be at least 1 (the number of modes listed), got {args.count}")
        list_modes(model, ref, args.count)
        return 0
    if args.mode is None or args.energy_max is None:
        raise NNMInputError("give --list-modes, or --mode N and --energy-max E to compute a branch")
    _check_arguments(model, args)            # bad input: its one line, before any notice about the output file
    out = output_file(args, "the branch will be saved to {out} (the model and the branch; --out chooses another file)")
    check_branch_file(out, model)              # a file of another model: refused before anything is computed
    check_plot_path(args.plot)
    cli_exchange.check_exports(args, model)
    job = start_branch(model, args.mode, args.energy_max, **continuation_options(args), **method_arguments(args))
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
    return report_and_save(args, model, branch, out, f"mode {args.mode}", f"NNM {args.mode}", dt)


def _run_family(args):
    """nnm-solve FILE --tongue K / --switch K: a family started on a saved branch of FILE (families.py)."""
    from . import exchange as cli_exchange
    from ..files.branch_io import check_branch_file
    from .families import compute_family, unused_flags

    if args.list_modes:
        raise NNMInputError("--list-modes does not go with --tongue / --switch")
    flag, unused, why = unused_flags(args)
    if unused:
        them = "it" if len(unused) == 1 else "them"
        raise NNMInputError(f"{', '.join(unused)}: not used by {flag} K ({why}); leave {them} out")
    model, _ = load_input(args.file)
    check_plot_path(args.plot)
    cli_exchange.check_exports(args, model)
    options = {**continuation_options(args), **method_arguments(args)}
    options.pop("tongues", None)
    t0 = time.perf_counter()
    parent, family, title = compute_family(args, model, options)
    out = output_file(args, "the branch will be saved to {out} (the model and the branch; --out chooses another file)")
    check_branch_file(out, model)
    return report_and_save(args, model, family, out, title, title, time.perf_counter() - t0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
