"""Exceptions raised for bad input: one line saying what is wrong and what to do."""


class NNMInputError(ValueError):
    """Invalid user input (matrices, springs, files, parameters).

    The message is one line: what is wrong, and what would fix it.
    """


class NNMFileError(NNMInputError):
    """A model/branch file that is missing, not HDF5, or not in the nnm format."""


def finite_number(value, what):
    """float(value), or NNMInputError "<what> is <value>, not a number / not finite" (one line)."""
    import math

    try:
        v = float(value)
    except (TypeError, ValueError):
        raise NNMInputError(f"{what} is {value!r}, not a number") from None
    if not math.isfinite(v):
        raise NNMInputError(f"{what} is {value!r}, not finite")
    return v


def run_reporting_errors(prog, fn, *args):
    """Run ``fn(*args)`` for a command-line program: bad input (NNMInputError) or an unreadable or
    unwritable file (OSError) prints one line ``<prog>: error: ...`` and returns exit code 2."""
    import sys

    try:
        return fn(*args)
    except (NNMInputError, OSError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
