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
from pathlib import Path

import numpy as np

from ..errors import NNMInputError, run_reporting_errors
from .defaults import TONGUE_CHOICES, solver_defaults
from .report import accuracy_line, report_and_save  # noqa: F401 (accuracy_line: part of the cli's API)
from .modes import list_modes
from .outputs import check_plot_path, output_file


def _load(path):
    from ..files.importers import is_import_path
    from ..files.io import load_extra, load_model

    p = Path(path)
    model = load_model(p)          # nnm HDF5, or an import by suffix (.mat, .toml, .full)
    return model, None if is_import_path(p) else load_extra(p, "reference")


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
        return run_reporting_errors("nnm-solve", _run_sweep, args, parser)
    if args.forced:
        return run_reporting_errors("nnm-solve", _run_forced, args)
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


def _method_arguments(args):
    """The method's keywords of continue_nnm from the command line; NNMInputError for another method's option."""
    given = dict(steps_per_period=args.steps_per_period, integrator=args.integrator)
    given = {k: v for k, v in given.items() if v is not None}      # the solver's defaults for the others
    target = {} if args.freq_tol is None else dict(freq_tol=args.freq_tol)     # both methods have one
    if (args.method or solver_defaults()["method"]) == "shooting":
        if args.condensed:
            raise NNMInputError("--condensed belongs to --method hb (harmonic balance)")
        if args.harmonics is not None:
            raise NNMInputError("--harmonics belongs to --method hb (harmonic balance)")
        return {**given, **target}
    if given:
        flags = ", ".join("--" + k.replace("_", "-") for k in given)
        raise NNMInputError(f"{flags} belong(s) to --method shooting; harmonic balance has no time steps "
                            f"(raise --harmonics instead)")
    return dict(method="hb", condensed=args.condensed, **target,
                **({} if args.harmonics is None else dict(harmonics=args.harmonics)))


def _continuation_options(args):
    """continue_nnm's keywords given on the command line (the solver's defaults for the others)."""
    opts = dict(tol=args.tol, max_points=args.max_points, energy_min=args.energy_min, tongues=args.tongues,
                floquet=True if args.floquet else None)
    return {k: v for k, v in opts.items() if v is not None}


def _check_arguments(model, args):
    """NNMInputError for a mode out of range, a non-positive --energy-max, --tol, --max-points or
    --energy-min (the checks continue_nnm makes, done before anything is printed or written)."""
    from ..driver.api import check_branch_arguments
    from ..model.settings import MODEL

    check_branch_arguments(model, args.mode, args.energy_max, 1e-6 if args.tol is None else args.tol,
                           solver_defaults()["max_points"] if args.max_points is None else args.max_points,
                           args.energy_min, modes_known=model.n <= MODEL.max_dense_dof)


def _forced_unused_flags(args):
    """The flags given on the command line that a forced response does not use (an NNM branch's: its mode, energy,
    method and time integration, tongues, families, exports), in the order of --help."""
    given = {"--list-modes": args.list_modes or None, "--mode": args.mode, "--energy-max": args.energy_max,
             "--energy-min": args.energy_min, "--method": args.method, "--steps-per-period": args.steps_per_period,
             "--integrator": args.integrator, "--freq-tol": args.freq_tol, "--tol": args.tol,
             "--tongues": args.tongues, "--tongue": args.tongue, "--switch": args.switch, "--branch": args.branch,
             "--csv": args.csv, "--uff": args.uff, "--backbone": args.backbone, "--backbone-dof": args.backbone_dof,
             "--floquet": args.floquet or None}
    return [flag for flag, value in given.items() if value is not None]


def _run_forced(args):
    """nnm-solve FILE --forced --force-dof D --force F --f-range A B [--damping Z] [--harmonics H] [--condensed]
    [--max-points N] [--plot FRF.png] [--out OUT.h5]: harmonic balance with modal damping (driver/forced.py)."""
    from ..driver.forced import forced_response
    from ..files.forced_io import check_forced_file, save_forced_response

    unused = _forced_unused_flags(args)
    if unused:
        them = "it" if len(unused) == 1 else "them"
        raise NNMInputError(f"{', '.join(unused)}: not used by --forced (a forced response by harmonic balance: "
                            f"--harmonics, --condensed, --max-points, --damping, --plot and --out apply); "
                            f"leave {them} out")
    model, _ = _load(args.file)
    dofs, values = args.force_dof or [], args.force or []
    if not dofs or not values or args.f_range is None:
        raise NNMInputError("--forced needs --force-dof DOF, --force N and --f-range F_START F_END")
    if len(values) not in (1, len(dofs)):
        raise NNMInputError(f"give one --force for each --force-dof ({len(dofs)}) or a single one, got {len(values)}")
    force = np.zeros(model.n)
    for d, v in zip(dofs, values * len(dofs) if len(values) == 1 else values):
        if not 0 <= d < model.n:
            raise NNMInputError(f"--force-dof {d} is not a DOF of the model (0..{model.n - 1})")
        force[d] += v
    check_plot_path(args.plot)
    out = output_file(args, "the response will be saved to {out} (--out chooses another file)")
    check_forced_file(out, model)           # a file of another model: refused before anything is computed
    options = {k: v for k, v in dict(harmonics=args.harmonics, max_points=args.max_points,
                                     condensed=True if args.condensed else None).items() if v is not None}
    t0 = time.perf_counter()
    r = forced_response(model, force, tuple(args.f_range), args.damping, **options)
    dof = int(dofs[0])
    pk = r.peak(dof) if len(r) else None
    print(f"forced response: {len(r)} points in {time.perf_counter() - t0:.1f} s, {r.status}: {r.message}")
    if pk is not None:
        print(f"  peak at DOF {dof}: {pk['amplitude']:.4e} m at {pk['frequency_hz']:.6g} Hz; folds: {len(r.folds)}")
    if len(r):
        print(f"saved as /forced/{save_forced_response(out, r)} in {out}")
        if args.plot:
            from ..results.forced_plot import plot_forced
            plot_forced([r], dof, path=args.plot)
            print(f"frequency response at DOF {dof} written to {args.plot}")
    return 1 if r.status == "failed" else 0


def _run(args):
    from . import exchange as cli_exchange
    from ..files.branch_io import check_branch_file
    from ..driver.jobs import start_branch

    model, ref = _load(args.file)
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
    job = start_branch(model, args.mode, args.energy_max, **_continuation_options(args), **_method_arguments(args))
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
    model, _ = _load(args.file)
    check_plot_path(args.plot)
    cli_exchange.check_exports(args, model)
    options = {**_continuation_options(args), **_method_arguments(args)}
    options.pop("tongues", None)
    t0 = time.perf_counter()
    parent, family, title = compute_family(args, model, options)
    out = output_file(args, "the branch will be saved to {out} (the model and the branch; --out chooses another file)")
    check_branch_file(out, model)
    return report_and_save(args, model, family, out, title, title, time.perf_counter() - t0)


def _sweep_unused_flags(args, parser):
    """The flags given on the command line that a sweep does not use (a single branch's exports, the forced
    response's, a family started on a saved branch), in the order of --help."""
    given = {"--tongue": args.tongue, "--switch": args.switch, "--branch": args.branch, "--forced": args.forced or None,
             "--force-dof": args.force_dof, "--force": args.force, "--f-range": args.f_range,
             "--damping": args.damping if args.damping != parser.get_default("damping") else None,
             "--csv": args.csv, "--uff": args.uff, "--backbone": args.backbone, "--backbone-dof": args.backbone_dof,
             "--backbone-kind": (args.backbone_kind if args.backbone_kind != parser.get_default("backbone_kind")
                                 else None)}
    return [flag for flag, value in given.items() if value is not None]


def _sweep_options(args, parser, options):
    """continue_nnm's keywords of every branch of a sweep: the sweep file's ``options`` with the branch flags given on
    the command line (--method, --integrator, --steps-per-period, --harmonics, --condensed, --freq-tol, --tongues,
    --tol, --max-points, --energy-min) over them, as a single branch (--mode N) takes them.  The method is the
    command line's where --method is given, else the file's; a flag of the other method is one NNMInputError line."""
    method = args.method or options.get("method") or solver_defaults()["method"]
    flags = _method_arguments(argparse.Namespace(**{**vars(args), "method": method}))
    if not args.condensed:
        flags.pop("condensed", None)            # (a sweep file's condensed = true stays unless the flag is given)
    if args.method is not None:
        flags["method"] = args.method
    return {**options, **flags, **_continuation_options(args)}


def _run_sweep(args, parser):
    """nnm-solve FILE --modes ... : many branches (modes x variants) in parallel on Dask (nnm_solver.sweep)."""
    from ..sweeps.dask_sweep import sweep
    from ..sweeps.spec import load_sweep_file

    if args.mode is not None:
        raise NNMInputError("give --mode N for one branch or --modes for a sweep, not both")
    if args.list_modes:
        raise NNMInputError("--list-modes does not go with --modes / --sweep")
    if args.workers is not None and args.workers < 1:
        raise NNMInputError(f"--workers must be at least 1, got {args.workers}")
    unused = _sweep_unused_flags(args, parser)
    if unused:
        them = "it" if len(unused) == 1 else "them"
        raise NNMInputError(f"{', '.join(unused)}: not used by a sweep (--modes / --sweep computes and saves whole "
                            f"branches; export or continue a saved branch with nnm-solve OUT.h5 afterwards); "
                            f"leave {them} out")
    spec = load_sweep_file(args.sweep) if args.sweep else None
    modes = args.modes if args.modes is not None else (spec.modes if spec else None)
    energy_max = args.energy_max if args.energy_max is not None else (spec.energy_max if spec else None)
    if modes is None or energy_max is None:
        raise NNMInputError("a sweep needs --modes (e.g. 10-24) and --energy-max E, on the command line or as "
                            "modes = ... and energy_max = ... in the sweep file")
    options = _sweep_options(args, parser, dict(spec.options) if spec else {})
    model, _ = _load(args.file)
    out = output_file(args, "the branches will be saved to {out} (--out chooses another file)")
    check_plot_path(args.plot)
    client = args.scheduler or args.workers
    t0 = time.perf_counter()
    try:
        branches = sweep(model, modes, energy_max, variants=spec.variants if spec else None, client=client, out=out,
                         progress=True, **options)
    except KeyboardInterrupt:
        sys.stderr.write(f"\ninterrupted: the finished branches are saved in {out}; run the same command again to "
                         f"compute the others\n")
        return 130
    dt = time.perf_counter() - t0
    print(f"{'branch':<28} {'points':>6}  {'energy (J)':<19}  {'frequency (Hz)':<21}  {'time':>7}  status")
    for b in branches:
        info = getattr(b, "sweep_info", {})
        took = f"{info['seconds']:6.1f}s" if info.get("seconds") is not None else f"{info.get('source', ''):>7}"
        span = (f"{b.energy.min():.2e}..{b.energy.max():.2e}  {b.frequency_hz[0]:9.5f} -> {b.frequency_hz[-1]:9.5f}"
                if len(b) else f"{'-':<19}  {'-':<21}")
        print(f"{b.name:<28} {len(b):>6}  {span}  {took}  {b.status}: {b.message}")
    computed = sum(getattr(b, "sweep_info", {}).get("source") == "computed" for b in branches)
    in_file = sum(getattr(b, "sweep_info", {}).get("source") == "file" for b in branches)
    failed = sum(b.status == "failed" for b in branches)
    print(f"{len(branches)} branches in {dt:.1f} s: {computed} computed, {in_file} already in {out}"
          f"{f', {failed} failed' if failed else ''}; saved as /branches/<variant>:mode<N> in {out}")
    if args.plot and any(len(b) for b in branches):
        from ..results.plotting import plot_atlas
        plot_atlas(branches, path=args.plot, title=f"{model.name or Path(args.file).stem}: NNM atlas")
        print(f"atlas written to {args.plot}")
    return 1 if failed else 0

if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
