"""ANSYS Mechanical APDL ``.full`` files (stiffness and mass), read by ``ansys-mapdl-reader``.

An optional extra: ``pip install "nnm[ansys]"``.  The reader gives the matrices' upper triangles
and the (node, DOF) of every equation; constrained DOFs (D commands) are dropped from the model, so
springs and mesh nodes are found through the DOF map (direction k of a node = UX, UY, UZ, ROTX,
ROTY, ROTZ in ANSYS's order).  Lumped-mass and unsymmetric files are refused by the reader.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError
from ...model.model import Model
from .common import DIRECTIONS, DofMap, existing

EXTRA = 'pip install "nnm[ansys]" (ansys-mapdl-reader)'


def reader_available():
    """(True, '') if ansys-mapdl-reader imports, else (False, why)."""
    try:
        import ansys.mapdl.reader  # noqa: F401
    except Exception as exc:  # ImportError, or a broken VTK install
        return False, f"{exc.__class__.__name__}: {exc}"
    return True, ""


def read_full(path):
    """(M, K, dof_map) of the free DOFs of an ANSYS .full file (M, K sparse CSR, symmetric)."""
    path = existing(path, "ANSYS .full file")
    ok, why = reader_available()
    if not ok:
        raise NNMInputError(f"{path}: reading ANSYS .full files needs the optional package ansys-mapdl-reader: "
                            f"{EXTRA} ({why})")
    from ansys.mapdl.reader import read_binary
    from ansys.mapdl.reader.full import FullFile

    try:
        full = read_binary(str(path))
        if not isinstance(full, FullFile):
            raise NNMFileError(f"{path}: an ANSYS {type(full).__name__}, not a .full matrix file")
        dof_ref, K, M = full.load_km(as_sparse=True, sort=True)
        const = {tuple(int(v) for v in row) for row in np.asarray(full.const).reshape(-1, 2)}
    except NNMFileError:
        raise
    except NotImplementedError as exc:   # lumped mass, unsymmetric matrices
        raise NNMFileError(f"{path}: {exc}") from None
    except Exception as exc:
        raise NNMFileError(f"{path}: not a readable ANSYS .full file ({exc.__class__.__name__}: {exc})") from None
    if K is None or M is None:
        raise NNMFileError(f"{path}: the file holds no {'stiffness' if K is None else 'mass'} matrix; "
                           f"write both (e.g. a modal analysis with WRFULL)")
    dof_ref = np.asarray(dof_ref)
    free = np.array([(int(n), int(d)) not in const for n, d in dof_ref], dtype=bool)
    idx = np.flatnonzero(free)
    # the reader returns upper triangles: mirror them
    K, M = (_mirror(A.tocsr())[idx][:, idx].tocsr() for A in (K, M))
    dof_map = DofMap([(int(n), DIRECTIONS[d] if 0 <= d < 6 else f"dof{d + 1}") for n, d in dof_ref[idx]])
    return M, K, dof_map


def _mirror(A):
    return (A + sp.triu(A, 1).T).tocsr() if sp.tril(A, -1).nnz == 0 else A


def load_full_model(path, name=None):
    """Linear Model of an ANSYS .full file (no springs; give them in a model description file)."""
    M, K, dof_map = read_full(path)
    try:
        return Model(M, K, [], dof_labels=dof_map.labels(), name=name or existing(path).stem,
                     info={"source": existing(path).name, "format": "ansys"})
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
