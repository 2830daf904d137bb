"""Importers: FE models from other codes' files into an ordinary ``nnm_solver.Model`` (docs/import.md).

One module per format: ``matlab`` (.mat v5 and v7.3), ``matrixmarket`` (.mtx pairs), ``abaqus``
(``*MATRIX OUTPUT`` files), ``ansys`` (.full, optional ``ansys-mapdl-reader``), ``nastran`` (.op4,
.op2, optional ``pyNastran``; ``nastran_mesh``: a bulk data file's geometry as the display mesh), ``toml``
(the model description naming matrix files, springs, units and a display mesh; its ``[[springs]]`` in
``toml_springs``, ``polynomial_stiffness`` in ``toml_coupled``), ``meshfile`` (display meshes through the optional
``meshio``); ``common`` holds the DOF map and units.  Measured signals (test data,
not models): ``measured`` (the ``Measurement`` record, CSV and .mat), ``uff58`` (UFF 58 through ``pyuff``),
``measured_units`` (g, mm, lbf ... to SI); ``measured_read.read_measured`` picks the reader by suffix.  ``import_model`` picks
the importer by file suffix; ``nnm_solver.load_model`` uses it for every suffix but HDF5.
"""
from __future__ import annotations

from pathlib import Path

from ...errors import NNMInputError
from .common import DIRECTIONS, DofMap, Units

#: model file suffix -> (module, loader name)
IMPORTERS = {".mat": ("matlab", "load_mat_model"), ".toml": ("toml", "load_toml_model"),
             ".full": ("ansys", "load_full_model"), ".op4": ("nastran", "load_nastran_model"),
             ".op2": ("nastran", "load_nastran_model")}
IMPORT_SUFFIXES = tuple(IMPORTERS)

__all__ = ["IMPORTERS", "IMPORT_SUFFIXES", "DIRECTIONS", "DofMap", "Units", "import_model", "is_import_path"]


def is_import_path(path):
    """True if ``path`` names a model file read by an importer (not an nnm HDF5 file)."""
    return Path(path).suffix.lower() in IMPORTERS


def import_model(path, name=None):
    """Model of an FE file chosen by suffix: .mat (MATLAB v5/v7.3), .toml (description), .full (ANSYS),
    .op4/.op2 (Nastran KAA, MAA)."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMPORTERS:
        raise NNMInputError(f"{path}: no importer for '{suffix}' files; known: {', '.join(IMPORT_SUFFIXES)} "
                            f"(and nnm HDF5 .h5); MatrixMarket and Abaqus matrices are named in a .toml description")
    module, func = IMPORTERS[suffix]
    from importlib import import_module
    return getattr(import_module(f"{__name__}.{module}"), func)(path, name=name)
