"""``nnm-solve import`` / ``nnm-solve export`` and the export options of ``nnm-solve FILE --mode N``.

    nnm-solve import MODEL.toml|.mat|.full --out MODEL.h5     # an imported model as a complete nnm file
    nnm-solve export FILE.h5 [--branch NAME] [--csv T.csv] [--uff S.uff] [--backbone B.csv --backbone-dof DOF]

Exports (also after a computation: ``nnm-solve FILE --mode N --energy-max E --csv ...``): ``--csv``
one row per point (energy, frequency, period, stable, label); ``--uff`` one UFF 55 shape per point;
``--backbone`` the amplitude-frequency backbone at ``--backbone-dof`` (index, label 'node 7 uz',
default: the first spring's DOF), ``--backbone-kind peak|harmonic1``.  Every argument is checked
before anything is computed or written.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import NNMInputError, run_reporting_errors

SUBCOMMANDS = ("import", "export")


def add_export_arguments(parser):
    g = parser.add_argument_group("exports")
    g.add_argument("--csv", metavar="T.csv", help="write the branch as CSV: energy, frequency, period, stable, label")
    g.add_argument("--uff", metavar="S.uff", help="write each point's shape x0 as a UFF 55 data set (needs pyuff)")
    g.add_argument("--backbone", metavar="B.csv", help="write the amplitude-frequency backbone as CSV")
    g.add_argument("--backbone-dof", metavar="DOF", help="DOF of the backbone: 0-based index, a DOF label "
                   "(e.g. 'node 7 uz') or 'NODE DIRECTION' (default: the first spring's DOF)")
    g.add_argument("--backbone-kind", choices=("peak", "harmonic1"), default="peak",
                   help="peak amplitude over the orbit, or the first harmonic's amplitude (default peak)")


def _folder_ok(path, what):
    folder = Path(path).resolve().parent
    if not folder.is_dir():
        raise NNMInputError(f"cannot write the {what}: folder {Path(path).parent} does not exist")


def backbone_dof(args, model):
    """(the backbone's DOF argument (int or label), its description), checked against ``model``."""
    from ..files.exports import _coordinate

    dof = args.backbone_dof
    if dof is None:
        if not model.springs:
            raise NNMInputError("--backbone needs --backbone-dof (the model has no spring to default to)")
        first = model.springs[0]
        dof = first.dof if hasattr(first, "dof") else int((getattr(first, "dofs", None) or (0,))[0])
    elif dof.strip().lstrip("-").isdigit():
        dof = int(dof)
    try:
        _, where = _coordinate(model, dof)
    except NNMInputError as exc:
        raise NNMInputError(f"--backbone-dof {args.backbone_dof}: {exc}") from None
    return dof, where


def check_exports(args, model):
    """One-line NNMInputError for an export that would fail (before anything is computed or written)."""
    if args.backbone_dof is not None and not args.backbone:
        raise NNMInputError("--backbone-dof goes with --backbone OUT.csv")
    for key, what in (("csv", "CSV table"), ("uff", "UFF file"), ("backbone", "backbone")):
        if getattr(args, key):
            _folder_ok(getattr(args, key), what)
    if args.uff:
        from ..files.exports import _pyuff
        _pyuff()
    if args.backbone:
        backbone_dof(args, model)


def write_exports(args, branch, out=None):
    from ..files.exports import export_backbone_csv, export_csv, export_uff

    out = sys.stdout if out is None else out
    if not len(branch):
        return
    if args.csv:
        export_csv(args.csv, branch)
        print(f"CSV table written to {args.csv} ({len(branch)} points)", file=out)
    if args.uff:
        export_uff(args.uff, branch)
        print(f"UFF 55 shapes written to {args.uff} ({len(branch)} data sets)", file=out)
    if args.backbone:
        dof, where = backbone_dof(args, branch.model)
        export_backbone_csv(args.backbone, branch, dof, args.backbone_kind)
        print(f"{args.backbone_kind} backbone at {where} written to {args.backbone}", file=out)


def main_import(argv):
    from ..files.importers import is_import_path
    from ..files.io import load_model, save_model

    p = argparse.ArgumentParser(prog="nnm-solve import", description="Write an imported model (.toml description, "
                                ".mat, ANSYS .full) as a complete nnm HDF5 file (matrices, springs, DOF labels, "
                                "display mesh).")
    p.add_argument("model", help="model file: .toml (description), .mat (MATLAB v5/v7.3), .full (ANSYS)")
    p.add_argument("--out", required=True, help="nnm HDF5 file to write (replaced atomically)")
    p.add_argument("--no-check", action="store_true", help="skip the linear-modes check of M and K")
    args = p.parse_args(argv)
    if not is_import_path(args.model):
        raise NNMInputError(f"{args.model}: nnm-solve import reads .toml, .mat or .full files")
    if is_import_path(args.out):
        raise NNMInputError(f"--out {args.out}: give an HDF5 path (.h5)")
    _folder_ok(args.out, "model")
    model = load_model(args.model)
    from ..model.settings import MODEL
    if not args.no_check and model.n <= MODEL.max_dense_dof:
        freqs, _ = model.linear_modes()       # M positive definite, K positive semi-definite
    else:
        freqs = None
    save_model(args.out, model, extra={"provenance": {"imported_from": str(Path(args.model).resolve()),
                                                      **{k: str(v) for k, v in model.info.items()}}})
    lowest = f"; lowest frequency {freqs[0]:.6g} Hz" if freqs is not None else ""
    print(f"{args.model}: {model.n} DOFs, {len(model.springs)} spring(s), "
          f"{'a display mesh of ' + str(len(model.mesh.vertices)) + ' points' if model.mesh else 'no display mesh'}"
          f"{lowest}; written to {args.out}")
    return 0


def main_export(argv):
    from ..files.branch_io import load_branches
    from .pick import numbered_names, pick_branch
    from ..files.io import load_model

    p = argparse.ArgumentParser(prog="nnm-solve export", description="Export a stored branch (CSV, UFF 55 shapes, "
                                "amplitude-frequency backbone).")
    p.add_argument("file", help="nnm HDF5 file with branches")
    p.add_argument("--branch", help="branch name (as listed) or its 1-based number, as nnm-solve --tongue / --switch "
                   "take it; needed when the file holds several")
    add_export_arguments(p)
    args = p.parse_args(argv)
    if not (args.csv or args.uff or args.backbone):
        raise NNMInputError("nothing to export: give --csv, --uff and/or --backbone")
    model = load_model(args.file)
    branches = load_branches(args.file, model=model)
    if not branches:
        raise NNMInputError(f"{args.file} holds no branch")
    if args.branch is None:
        if len(branches) > 1:
            raise NNMInputError(f"{args.file} holds {len(branches)} branches ({numbered_names(branches)}); "
                                f"choose one with --branch NAME or number")
        branch = branches[0]
    else:
        branch = pick_branch(branches, args.branch, args.file)
    check_exports(args, branch.model)
    write_exports(args, branch)
    return 0


def main(argv):
    """Run ``nnm-solve import|export ...`` (argv without the program name); exit code 2 on bad input."""
    return run_reporting_errors(f"nnm-solve {argv[0]}", main_import if argv[0] == "import" else main_export,
                                argv[1:])
