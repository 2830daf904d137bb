"""What nnm-solve reads from its command line for a branch: the input model file, the method's keywords of
continue_nnm and the continuation's (shared by a single branch, a family, a sweep)."""
from __future__ import annotations

from pathlib import Path

from ..errors import NNMInputError
from .defaults import solver_defaults

__all__ = ["load_input", "method_arguments", "continuation_options"]


def load_input(path):
    from ..files.importers import is_import_path
    from ..files.io import load_extra, load_model

    p = Path(path)
    model = load_model(p)          # nnm HDF5, or an import by suffix (.mat, .toml, .full)
    return model, None if is_import_path(p) else load_extra(p, "reference")


def method_arguments(args):
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


def continuation_options(args):
    """continue_nnm's keywords given on the command line (the solver's defaults for the others)."""
    opts = dict(tol=args.tol, max_points=args.max_points, energy_min=args.energy_min, tongues=args.tongues,
                floquet=True if args.floquet else None)
    return {k: v for k, v in opts.items() if v is not None}
