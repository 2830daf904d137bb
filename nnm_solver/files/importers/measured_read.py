"""``read_measured``: a measured record from UFF 58, CSV or MATLAB .mat, the reader chosen by suffix."""
from __future__ import annotations

from pathlib import Path

from ...errors import NNMFileError, NNMInputError
from .measured_tables import read_csv_measurement, read_mat_measurement
from .uff58 import read_uff58

__all__ = ["read_measured", "MEASURED_SUFFIXES"]

#: file suffix -> reader
MEASURED_SUFFIXES = {".uff": "uff", ".unv": "uff", ".csv": "csv", ".txt": "csv", ".mat": "mat"}


def read_measured(path, **options):
    """Measurement from a UFF 58 (.uff, .unv), CSV (.csv, .txt) or MATLAB (.mat) file, chosen by suffix.
    options go to the UFF reader (``sets``: which 58 data sets, 0-based among them)."""
    suffix = Path(path).suffix.lower()
    kind = MEASURED_SUFFIXES.get(suffix)
    if kind is None:
        raise NNMFileError(f"{path}: measured data is read from {', '.join(MEASURED_SUFFIXES)} files, not '{suffix}'")
    if kind == "uff":
        return read_uff58(path, **options)
    if options:
        raise NNMInputError(f"{path}: options {', '.join(options)} apply to UFF files only")
    return read_csv_measurement(path) if kind == "csv" else read_mat_measurement(path)
