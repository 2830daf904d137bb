"""nnm-solve FILE --forced ...: a forced response from the command line (driver/forced.py, docs/forced.md)."""
from __future__ import annotations

import time

import numpy as np

from ..errors import NNMInputError
from .branch_options import load_input
from .outputs import check_plot_path, output_file

__all__ = ["run_forced", "forced_unused_flags"]


def forced_unused_flags(args):
    """The flags given on the command line that a forced response does not use (an NNM branch's: its mode, energy,
    method and time integration, tongues, families, exports), in the order of --help."""
    given = {"--list-modes": args.list_modes or None, "--mode": args.mode, "--energy-max": args.energy_max,
             "--energy-min": args.energy_min, "--method": args.method, "--steps-per-period": args.steps_per_period,
             "--integrator": args.integrator, "--freq-tol": args.freq_tol, "--tol": args.tol,
             "--tongues": args.tongues, "--tongue": args.tongue, "--switch": args.switch, "--branch": args.branch,
             "--csv": args.csv, "--uff": args.uff, "--backbone": args.backbone, "--backbone-dof": args.backbone_dof,
             "--floquet": args.floquet or None}
    return [flag for flag, value in given.items() if value is not None]


def run_forced(args):
    """nnm-solve FILE --forced --force-dof D --force F --f-range A B [--damping Z] [--harmonics H] [--condensed]
    [--max-points N] [--plot FRF.png] [--out OUT.h5]: harmonic balance with modal damping (driver/forced.py)."""
    from ..driver.forced import forced_response
    from ..files.forced_io import check_forced_file, save_forced_response

    unused = forced_unused_flags(args)
    if unused:
        them = "it" if len(unused) == 1 else "them"
        raise NNMInputError(f"{', '.join(unused)}: not used by --forced (a forced response by harmonic balance: "
                            f"--harmonics, --condensed, --max-points, --damping, --plot and --out apply); "
                            f"leave {them} out")
    model, _ = load_input(args.file)
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
