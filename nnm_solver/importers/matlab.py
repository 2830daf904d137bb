"""MATLAB .mat models, the way reduced models usually leave FE codes: v5 (``scipy.io``) and v7.3 (HDF5, ``h5py``).

Expected variables: ``M`` and ``K`` (n x n, dense or sparse) and optionally ``springs``: a table with
one row per cubic spring, columns ``[dof, other, k3]`` where dof/other are 1-based DOF numbers as in
MATLAB (other = 0 for a grounded spring) and k3 in N/m^3.  Optional ``dof_labels`` (cell array of
strings).  MATLAB writes v7.3 (``save -v7.3``) for large matrices: an HDF5 file whose arrays are
stored transposed (column-major) and whose sparse matrices are groups (``data``, ``ir``, ``jc``).
"""
from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import scipy.io
import scipy.sparse as sp

from ..elements import CubicSpring
from ..errors import NNMFileError, NNMInputError
from ..model import Model
from .common import existing


def read_mat(path, names=None):
    """Variables of a .mat file (v5 or v7.3) as a dict: numeric arrays (dense or scipy.sparse),
    strings and lists (cell arrays).  ``names``: read only these (when present)."""
    path = existing(path, "MATLAB file")
    if h5py.is_hdf5(path):
        return _read_v73(path, names)
    try:
        data = scipy.io.loadmat(path, variable_names=names)
    except Exception as exc:  # scipy raises several types for non-MAT input
        raise NNMFileError(f"{path}: not a readable MATLAB .mat file ({exc.__class__.__name__}: {exc})") from None
    return {k: v for k, v in data.items() if not k.startswith("__")}


def _attr(obj, key, default=""):
    v = obj.attrs.get(key, default)
    return v.decode() if isinstance(v, bytes) else v


def _read_v73(path, names):
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise NNMFileError(f"{path}: not a readable MATLAB v7.3 (HDF5) file ({exc})") from None
    out = {}
    with f:
        for key in f:
            if key.startswith("#") or (names is not None and key not in names):
                continue
            try:
                out[key] = _v73_value(f, f[key])
            except (KeyError, ValueError, OSError, TypeError) as exc:
                raise NNMFileError(f"{path}: variable '{key}' is unreadable ({exc})") from None
    return out


def _v73_value(f, obj):
    cls = _attr(obj, "MATLAB_class")
    if isinstance(obj, h5py.Group):
        if "MATLAB_sparse" in obj.attrs:
            nrows = int(obj.attrs["MATLAB_sparse"])
            jc = obj["jc"][()].astype(np.int64)
            ir = obj["ir"][()].astype(np.int64) if "ir" in obj else np.zeros(0, np.int64)
            data = obj["data"][()] if "data" in obj else np.zeros(len(ir))
            if data.dtype.names:  # complex: compound (real, imag)
                data = data["real"] + 1j * data["imag"]
            return sp.csc_matrix((data.astype(float) if cls != "logical" else data.astype(bool).astype(float),
                                  ir, jc), shape=(nrows, len(jc) - 1))
        raise ValueError(f"MATLAB class '{cls or 'struct'}' is not supported (use numeric arrays, strings, cells)")
    if int(obj.attrs.get("MATLAB_empty", 0)):
        return np.zeros((0, 0))
    raw = obj[()]
    if cls == "char":
        a = np.atleast_2d(raw).T   # back to MATLAB's (rows, columns)
        rows = ["".join(chr(c) for c in row) for row in a]
        return rows[0] if len(rows) == 1 else rows
    if cls == "cell":
        return [_v73_value(f, f[ref]) for ref in np.asarray(raw).T.ravel()]
    a = np.asarray(raw)
    if a.dtype.names:
        a = a["real"] + 1j * a["imag"]
    return a.T


def _strings(value):
    if isinstance(value, str):
        return [value]
    if isinstance(value, list):
        return [v if isinstance(v, str) else str(np.asarray(v).ravel()[0]) if np.asarray(v).size else "" for v in value]
    return [str(np.asarray(s).ravel()[0]) if np.asarray(s).size else "" for s in np.asarray(value, dtype=object).ravel()]


def springs_from_table(table, n, where):
    """CubicSprings from rows [dof other k3] with 1-based DOFs (other = 0: grounded)."""
    table = np.atleast_2d(np.asarray(table.toarray() if sp.issparse(table) else table, dtype=float))
    if not table.size:
        return []
    if table.shape[1] != 3:
        raise NNMFileError(f"{where}: 'springs' must have 3 columns [dof other k3] (1-based), got {table.shape}")
    springs = []
    for r, row in enumerate(table, 1):
        dof, other, k3 = int(round(row[0])), int(round(row[1])), float(row[2])
        if not 1 <= dof <= n:
            raise NNMFileError(f"{where}: springs row {r}: dof {dof} is not a DOF of the model (1..{n}, 1-based)")
        if not 0 <= other <= n:
            raise NNMFileError(f"{where}: springs row {r}: other {other} is not a DOF of the model "
                               f"(1..{n}, 1-based; 0 for a grounded spring)")
        springs.append(CubicSpring(dof=dof - 1, other=None if other == 0 else other - 1, k3=k3))
    return springs


def load_mat_model(path, name=None):
    """Model from a .mat file, v5 or v7.3 (variables M, K, optional springs = [dof other k3] 1-based, dof_labels)."""
    path = Path(path)
    data = read_mat(path, ["M", "K", "springs", "dof_labels"])
    for key in ("M", "K"):
        if key not in data:
            raise NNMFileError(f"{path}: no variable '{key}'; a model file needs M, K and optionally springs")
    M, K = data["M"], data["K"]
    if M.shape != K.shape:
        raise NNMFileError(f"{path}: M is {M.shape[0]}x{M.shape[1]} but K is {K.shape[0]}x{K.shape[1]}; "
                           f"they must have the same size")
    n = M.shape[0]
    springs = springs_from_table(data["springs"], n, path) if "springs" in data else []
    labels = _strings(data["dof_labels"]) if "dof_labels" in data else None
    try:
        return Model(M, K, springs, dof_labels=labels, name=name or path.stem,
                     info={"source": str(path.name), "format": "matlab"})
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
