"""nnm-solve FILE --modes ... / --sweep SWEEP.toml: many branches in parallel on Dask (sweeps/, docs/sweep.md)."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..errors import NNMInputError
from .branch_options import continuation_options, load_input, method_arguments
from .defaults import solver_defaults
from .outputs import check_plot_path, output_file

__all__ = ["run_sweep", "sweep_unused_flags", "sweep_options"]


def sweep_unused_flags(args, parser):
    """The flags given on the command line that a sweep does not use (a single branch's exports, the forced
    response's, a family started on a saved branch), in the order of --help."""
    given = {"--tongue": args.tongue, "--switch": args.switch, "--branch": args.branch, "--forced": args.forced or None,
             "--force-dof": args.force_dof, "--force": args.force, "--f-range": args.f_range,
             "--damping": args.damping if args.damping != parser.get_default("damping") else None,
             "--csv": args.csv, "--uff": args.uff, "--backbone": args.backbone, "--backbone-dof": args.backbone_dof,
             "--backbone-kind": (args.backbone_kind if args.backbone_kind != parser.get_default("backbone_kind")
                                 else None)}
    return [flag for flag, value in given.items() if value is not None]


def sweep_options(args, parser, options):
    """continue_nnm's keywords of every branch of a sweep: the sweep file's ``options`` with the branch flags given on
    the command line (--method, --integrator, --steps-per-period, --harmonics, --condensed, --freq-tol, --tongues,
    --tol, --max-points, --energy-min) over them, as a single branch (--mode N) takes them.  The method is the
    command line's where --method is given, else the file's; a flag of the other method is one NNMInputError line."""
    method = args.method or options.get("method") or solver_defaults()["method"]
    flags = method_arguments(argparse.Namespace(**{**vars(args), "method": method}))
    if not args.condensed:
        flags.pop("condensed", None)            # (a sweep file's condensed = true stays unless the flag is given)
    if args.method is not None:
        flags["method"] = args.method
    return {**options, **flags, **continuation_options(args)}


def run_sweep(args, parser):
    """nnm-solve FILE --modes ... : many branches (modes x variants) in parallel on Dask (nnm_solver.sweep)."""
    from ..sweeps.dask_sweep import sweep
    from ..sweeps.spec import load_sweep_file

    if args.mode is not None:
        raise NNMInputError("give --mode N for one branch or --modes for a sweep, not both")
    if args.list_modes:
        raise NNMInputError("--list-modes does not go with --modes / --sweep")
    if args.workers is not None and args.workers < 1:
        raise NNMInputError(f"--workers must be at least 1, got {args.workers}")
    unused = sweep_unused_flags(args, parser)
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
    options = sweep_options(args, parser, dict(spec.options) if spec else {})
    model, _ = load_input(args.file)
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
