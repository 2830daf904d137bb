"""MATLAB .mat models, the way reduced models usually leave FE codes: v5 (``scipy.io``) and v7.3 (HDF5, ``h5py``).

Expected variables: ``M`` and ``K`` (n x n, dense or sparse) and optionally the spring tables, one
row per element, dof/other 1-based DOF numbers as in MATLAB (other = 0 for a grounded spring), SI units:

* ``springs = [dof other k3]``: cubic springs, force k3 d^3 (N/m^3) (spring tables version 1);
* ``polynomial_springs = [dof other p c_p]``: one row per term c_p d^p (integer p >= 2, N/m^p); the
  rows of one (dof, other) pair make one PolynomialSpring (version 2);
* ``piecewise_springs = [dof other k0 d1 k1 d2 k2 ...]``: piecewise-linear springs (N/m, m), slope k0
  about d = 0 and slope k_j past |d| = d_j; rows of different lengths are padded with NaN.  All
  d_j > 0: the odd law.  A negative d_j is a breakpoint of the compression side at d = -|d_j| (the
  pairs with d_j > 0 then describe tension only): an asymmetric law.  Optional scalar
  ``piecewise_eps`` (kink width / d1, default 1e-3) (version 2);
* optional scalar ``springs_version`` (1 or 2; default: 2 when a version-2 table is present): a file
  written for a later version is refused rather than read in part.

Optional ``dof_labels`` (cell array of strings).  MATLAB writes v7.3 (``save -v7.3``) for large matrices: an HDF5 file whose arrays are
stored transposed (column-major) and whose sparse matrices are groups (``data``, ``ir``, ``jc``).
"""
from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import scipy.io
import scipy.sparse as sp

from ...model.elements import CubicSpring, PiecewiseLinearSpring, PolynomialSpring
from ...model.settings import MODEL
from ...errors import NNMFileError, NNMInputError
from ...model.model import Model
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


def strings_of(value):
    if isinstance(value, str):
        return [value]
    if isinstance(value, list):
        return [v if isinstance(v, str) else str(np.asarray(v).ravel()[0]) if np.asarray(v).size else "" for v in value]
    return [str(np.asarray(s).ravel()[0]) if np.asarray(s).size else "" for s in np.asarray(value, dtype=object).ravel()]


def _numeric(value, name, where):
    """The MATLAB variable ``name`` as a float array (sparse ones densified); one-line NNMFileError if it is not
    numeric (a string, a cell array, a struct: numpy's conversion error, a traceback before)."""
    try:
        return np.asarray(value.toarray() if sp.issparse(value) else value, dtype=float)
    except (TypeError, ValueError):
        raise NNMFileError(f"{where}: '{name}' must be a numeric table (rows of numbers), got "
                           f"{type(value).__name__} {np.asarray(value, dtype=object).ravel()[:3].tolist()!r}") from None


def springs_from_table(table, n, where):
    """CubicSprings from rows [dof other k3] with 1-based DOFs (other = 0: grounded)."""
    table = np.atleast_2d(_numeric(table, "springs", where))
    if not table.size:
        return []
    if table.shape[1] != 3:
        raise NNMFileError(f"{where}: 'springs' must have 3 columns [dof other k3] (1-based), got {table.shape}")
    springs = []
    for r, row in enumerate(table, 1):
        dof, other = _ends(row, r, n, "springs", where)     # (whole 1-based numbers: 1.5 was rounded to DOF 2)
        springs.append(CubicSpring(dof=dof, other=other, k3=float(row[2])))
    return springs


#: MATLAB variables holding springs, and the spring-table version that introduced each
SPRING_VARIABLES = {"springs": 1, "polynomial_springs": 2, "piecewise_springs": 2, "piecewise_eps": 2}
#: the newest spring-table version this reader knows
SPRINGS_VERSION = 2


def _table(value, name, ncols, where, exact=True):
    """A numeric (rows, cols) table; one-line NNMFileError if its width is wrong."""
    table = np.atleast_2d(_numeric(value, name, where))
    if table.size and (table.shape[1] != ncols if exact else table.shape[1] < ncols):
        raise NNMFileError(f"{where}: '{name}' must have {'' if exact else 'at least '}{ncols} columns, "
                           f"got {table.shape[0]}x{table.shape[1]}")
    return table if table.size else np.zeros((0, ncols))


def _ends(row, r, n, name, where):
    """0-based (dof, other or None) of a row's first two columns (1-based DOF numbers)."""
    if not np.all(np.isfinite(row[:2])) or np.any(row[:2] != np.round(row[:2])):
        raise NNMFileError(f"{where}: {name} row {r}: dof and other must be whole numbers, got {row[:2].tolist()}")
    dof, other = int(row[0]), int(row[1])
    if not 1 <= dof <= n:
        raise NNMFileError(f"{where}: {name} row {r}: dof {dof} is not a DOF of the model (1..{n}, 1-based)")
    if not 0 <= other <= n:
        raise NNMFileError(f"{where}: {name} row {r}: other {other} is not a DOF of the model "
                           f"(1..{n}, 1-based; 0 for a grounded spring)")
    return dof - 1, None if other == 0 else other - 1


def springs_from_mat(data, n, where):
    """Every spring of the .mat variables ``data`` (see the module docstring), in file order of the tables:
    springs, polynomial_springs, piecewise_springs."""
    version = SPRINGS_VERSION if any(SPRING_VARIABLES[k] > 1 for k in data if k in SPRING_VARIABLES) else 1
    if "springs_version" in data:
        v = _numeric(data["springs_version"], "springs_version", where).ravel()
        if v.size != 1 or v[0] not in (1, 2):
            raise NNMFileError(f"{where}: springs_version = {v.tolist()} is not a spring-table version this nnm reads "
                               f"(1 or {SPRINGS_VERSION}); update nnm")
        if int(v[0]) < version:
            raise NNMFileError(f"{where}: springs_version = {int(v[0])} but the file has version-2 tables "
                               f"(polynomial_springs, piecewise_springs)")
    springs = springs_from_table(data["springs"], n, where) if "springs" in data else []
    if "polynomial_springs" in data:
        terms = {}
        for r, row in enumerate(_table(data["polynomial_springs"], "polynomial_springs", 4, where), 1):
            ends = _ends(row, r, n, "polynomial_springs", where)
            p, c = row[2], row[3]
            if not np.isfinite(p) or p != round(p) or p < 2:
                raise NNMFileError(f"{where}: polynomial_springs row {r}: power {p:g} is not an integer >= 2 "
                                   f"(the linear stiffness belongs in K)")
            if not np.isfinite(c):
                raise NNMFileError(f"{where}: polynomial_springs row {r}: coefficient {c} is not finite")
            law = terms.setdefault(ends, {})
            if int(p) in law:
                raise NNMFileError(f"{where}: polynomial_springs row {r}: a second d^{int(p)} term for the same "
                                   f"dof and other")
            law[int(p)] = float(c)
        springs += [PolynomialSpring(dof=d, other=o, coefficients=law) for (d, o), law in terms.items()]
    if "piecewise_springs" in data:
        eps = MODEL.pwl_eps
        if "piecewise_eps" in data:
            e = _numeric(data["piecewise_eps"], "piecewise_eps", where).ravel()
            if e.size != 1:
                raise NNMFileError(f"{where}: piecewise_eps must be one number (kink width / d1)")
            eps = float(e[0])
        for r, row in enumerate(_table(data["piecewise_springs"], "piecewise_springs", 5, where, exact=False), 1):
            dof, other = _ends(row, r, n, "piecewise_springs", where)
            body = row[2:]
            used = body[:len(body) - np.argmax(~np.isnan(body[::-1]))] if np.any(~np.isnan(body)) else body[:0]
            if np.any(np.isnan(used)) or len(used) < 3 or len(used) % 2 == 0:
                raise NNMFileError(f"{where}: piecewise_springs row {r}: expected k0 followed by pairs d_j k_j "
                                   f"(NaN only as trailing padding), got {used.tolist()}")
            k0, pairs = used[0], used[1:].reshape(-1, 2)
            pos, neg = pairs[pairs[:, 0] >= 0], pairs[pairs[:, 0] < 0]
            law = dict(stiffnesses=[k0, *pos[:, 1]], breakpoints=list(pos[:, 0]), eps=eps)
            if len(neg):
                law.update(stiffnesses_negative=[k0, *neg[:, 1]], breakpoints_negative=list(-neg[:, 0]))
            try:
                springs.append(PiecewiseLinearSpring(dof=dof, other=other, **law))
            except NNMInputError as exc:
                raise NNMFileError(f"{where}: piecewise_springs row {r}: {exc}") from None
    return springs


def load_mat_model(path, name=None):
    """Model from a .mat file, v5 or v7.3 (variables M, K, optional spring tables (module docstring), dof_labels)."""
    path = Path(path)
    data = read_mat(path, ["M", "K", "dof_labels", "springs_version", *SPRING_VARIABLES])
    for key in ("M", "K"):
        if key not in data:
            raise NNMFileError(f"{path}: no variable '{key}'; a model file needs M, K and optionally springs")
    M, K = data["M"], data["K"]
    if M.shape != K.shape:
        raise NNMFileError(f"{path}: M is {M.shape[0]}x{M.shape[1]} but K is {K.shape[0]}x{K.shape[1]}; "
                           f"they must have the same size")
    n = M.shape[0]
    springs = springs_from_mat(data, n, path)
    labels = strings_of(data["dof_labels"]) if "dof_labels" in data else None
    try:
        return Model(M, K, springs, dof_labels=labels, name=name or path.stem,
                     info={"source": str(path.name), "format": "matlab"})
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
