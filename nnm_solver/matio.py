"""Import a reduced model from a MATLAB .mat file, the way reduced models usually leave FE codes.

Expected variables: ``M`` and ``K`` (n x n, dense or sparse) and optionally ``springs``: a table
with one row per cubic spring, columns ``[dof, other, k3]`` where dof/other are 1-based DOF
numbers as in MATLAB (other = 0 for a grounded spring) and k3 in N/m^3.  Optional ``dof_labels``
(cell array of strings).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from .errors import NNMFileError
from .elements import CubicSpring
from .model import Model


def load_mat_model(path, name=None):
    """Model from a .mat file (variables M, K, optional springs = [dof other k3] 1-based, dof_labels)."""
    path = Path(path)
    if not path.exists():
        raise NNMFileError(f"{path}: no such file")
    try:
        data = scipy.io.loadmat(path)
    except Exception as exc:  # scipy raises several types for non-MAT input
        raise NNMFileError(f"{path}: not a readable MATLAB .mat file ({exc.__class__.__name__}: {exc})") from None
    for key in ("M", "K"):
        if key not in data:
            raise NNMFileError(f"{path}: no variable '{key}'; a model file needs M, K and optionally springs")
    springs = []
    if "springs" in data:
        table = np.atleast_2d(np.asarray(data["springs"], dtype=float))
        if table.size and table.shape[1] != 3:
            raise NNMFileError(f"{path}: 'springs' must have 3 columns [dof other k3] (1-based), got {table.shape}")
        for row in table if table.size else []:
            dof, other, k3 = int(round(row[0])), int(round(row[1])), float(row[2])
            springs.append(CubicSpring(dof=dof - 1, other=None if other == 0 else other - 1, k3=k3))
    labels = None
    if "dof_labels" in data:
        labels = [str(np.asarray(s).ravel()[0]) if np.asarray(s).size else "" for s in np.asarray(data["dof_labels"]).ravel()]
    try:
        return Model(data["M"], data["K"], springs, dof_labels=labels, name=name or path.stem,
                     info={"source": str(path.name)})
    except ValueError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
