r"""Forced responses in the nnm HDF5 file: one group ``/forced/<name>`` per ForcedResponse, next to the
model (``/model``) and its NNM branches (``/branches``) in the same file (docs/forced.md, "File").

    /forced/<name>   attrs name, status, message, harmonics, basis, samples (0: default), condensed,
                     stability, created_order, settings_json, folds_json (index, frequency_hz, located)
        force (n,) N; damping (n,) modal damping ratios; damping_matrix (n, n) N s/m (if any);
        frequency_hz (N,); coefficients (N, N_b, n) m, physical Fourier coefficients on the forced basis;
        floquet (N, 2n) complex; stable (N,) bool; fold_sign (N,) int8; fold_coefficients (F, N_b, n) m

Writes are atomic (``h5file.atomic_h5``: a copy of the file, renamed over it when complete).  A response of
another model than the file's (other DOF count, matrices, elements or force laws) is refused with one line
and the file is left unchanged.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from . import coupled_io
from ..errors import NNMFileError, NNMInputError
from ..results.forced import ForcedResponse
from .h5file import atomic_h5, open_nnm, read_matrix
from .importers import is_import_path
from .branch_io import _close, _jsonable      # the same model comparison and JSON as for branches
from .io import read_model_group, spring_law_json, write_model_group
from .settings import FILES

__all__ = ["check_forced_file", "save_forced_response", "load_forced_responses", "FORCED_GROUP"]

FORCED_GROUP = "forced"


def check_forced_file(path, model):
    """NNMInputError (one line) if a forced response of ``model`` may not be saved into the nnm file ``path``: an
    imported model file (not an nnm HDF5 file), or a file of another model; nothing if the file does not exist yet.
    Callers check a target before computing (nnm-solve --forced)."""
    path = Path(path)
    if is_import_path(path):
        raise NNMInputError(f"{path} is an imported model file, not an nnm HDF5 file: save forced responses to a .h5 "
                            f"file")
    if path.exists():
        with open_nnm(path) as f:
            problem = _model_difference(f, path, model)
        if problem:
            raise _refusal(path, problem)


def _refusal(path, problem):
    """The one-line NNMInputError refusing a forced response of another model than the file ``path``'s."""
    return NNMInputError(f"{path} holds another model than this forced response's ({problem}); the file was "
                         f"left unchanged: save it to another file")


def save_forced_response(path, result, name=None):
    """Append the ForcedResponse ``result`` to the nnm file at ``path`` under /forced/<name> (created with the
    result's model if the file does not exist).  Returns the group name used (``name``, the result's name,
    or ``forced``; ``_2``, ``_3``, ... appended when taken).  Everything already in the file is kept."""
    if not isinstance(result, ForcedResponse):
        raise NNMInputError(f"save_forced_response needs an nnm_solver.ForcedResponse, got {type(result).__name__}")
    path = Path(path)
    check_forced_file(path, result.model)
    with atomic_h5(path, copy_existing=True) as f:
        problem = _model_difference(f, path, result.model)   # again under the lock: another process may have
        if problem:                                          # created the file meanwhile
            raise _refusal(path, problem)
        if "model" not in f:
            write_model_group(f, result.model)
        root = f.require_group(FORCED_GROUP)
        base = str(name if name is not None else (result.name or "forced")).replace("/", "_") or "forced"
        gname, k = base, 2
        while gname in root:
            gname, k = f"{base}_{k}", k + 1
        g = root.create_group(gname)
        g.attrs["created_order"] = len(root) - 1
        g.attrs["name"] = result.name or gname
        g.attrs["status"] = result.status
        g.attrs["message"] = result.message
        g.attrs["harmonics"] = result.harmonics
        g.attrs["basis"] = result.basis_kind
        g.attrs["samples"] = 0 if result.samples is None else result.samples
        g.attrs["condensed"] = bool(result.condensed)
        g.attrs["stability"] = result.stability
        g.attrs["settings_json"] = json.dumps(_jsonable(result.settings))
        g.attrs["folds_json"] = json.dumps([{k: _jsonable(v) for k, v in fd.items() if k != "coefficients"}
                                            for fd in result.folds])
        g.create_dataset("force", data=result.force)
        g.create_dataset("damping", data=result.damping)
        if result.damping_matrix is not None:
            g.create_dataset("damping_matrix", data=result.damping_matrix, compression="gzip")
        gz = dict(compression="gzip") if len(result) * result.model.n > 64 else {}
        g.create_dataset("frequency_hz", data=result.frequency_hz)
        g.create_dataset("coefficients", data=result.coefficients, **gz)
        g.create_dataset("floquet", data=result.floquet, **gz)
        g.create_dataset("stable", data=result.stable)
        g.create_dataset("fold_sign", data=result.fold_sign.astype(np.int8))
        fc = np.array([fd["coefficients"] for fd in result.folds]).reshape(len(result.folds), len(result.basis),
                                                                            result.model.n)
        g.create_dataset("fold_coefficients", data=fc)
    return gname


def load_forced_responses(path, model=None):
    """All forced responses stored in the nnm file at ``path`` (list of ForcedResponse, in the order saved; []
    if there are none).  model : the file's model if already loaded."""
    if is_import_path(path):
        return []
    with open_nnm(path) as f:
        if FORCED_GROUP not in f:
            return []
        if model is None:
            model = read_model_group(f, path)
        root = f[FORCED_GROUP]
        out = []
        for gname in sorted(root, key=lambda s: root[s].attrs.get("created_order", 0)):
            g = root[gname]
            try:
                folds = json.loads(g.attrs.get("folds_json", "[]"))
                fc = g["fold_coefficients"][()] if "fold_coefficients" in g else np.zeros((len(folds), 0))
                for fd, c in zip(folds, fc):
                    fd["coefficients"] = c
                samples = int(g.attrs.get("samples", 0)) or None
                out.append(ForcedResponse(
                    model, g["force"][()], g["frequency_hz"][()], g["coefficients"][()],
                    harmonics=int(g.attrs["harmonics"]), basis=str(g.attrs.get("basis", "full")), samples=samples,
                    damping=g["damping"][()], damping_matrix=g["damping_matrix"][()] if "damping_matrix" in g else None,
                    floquet=g["floquet"][()], stable=g["stable"][()], fold_sign=g["fold_sign"][()], folds=folds,
                    status=str(g.attrs.get("status", "")), message=str(g.attrs.get("message", "")),
                    name=str(g.attrs.get("name", gname)), condensed=bool(g.attrs.get("condensed", False)),
                    stability=str(g.attrs.get("stability", "none")),
                    settings=json.loads(g.attrs.get("settings_json", "{}"))))
            except (KeyError, OSError, ValueError, TypeError) as exc:
                raise NNMFileError(f"{path}: forced response {gname} is incomplete or damaged ({exc})") from None
        return out


# ---------------------------------------------------------------------- the file's model
def _model_difference(f, path, model):
    """'' when the file holds no model or ``model`` equals it (matrices to FILES.model_rtol, the same elements and
    force laws), else what differs (one line)."""
    if "model" not in f:
        return ""
    g = f["model"]
    n_file = int(g.attrs["n_dof"]) if "n_dof" in g.attrs else read_matrix(g, "K", path).shape[0]
    if n_file != model.n:
        return f"the file's model has {n_file} DOFs, the response's {model.n}"
    file_model = read_model_group(f, path)
    for label in ("M", "K"):
        d = _matrix_difference(getattr(file_model, label), getattr(model, label))
        if d:
            return f"{label} differs by up to {d:.3g} of its largest entry"
    a, b = file_model.springs, model.springs
    if len(a) != len(b):
        return f"the file's model has {len(a)} nonlinear elements, the response's {len(b)}"
    for i, (s, t) in enumerate(zip(a, b)):
        if coupled_io.is_coupled(s) or coupled_io.is_coupled(t):
            if not coupled_io.same_element(s, t):
                return f"element {i} (a PolynomialStiffness) differs between the file and the response's model"
            continue
        if (s.dof, s.other) != (t.dof, t.other) or type(s) is not type(t) or not _close(spring_law_json(s),
                                                                                        spring_law_json(t)):
            return (f"element {i} differs ({json.dumps(spring_law_json(s))} in the file, "
                    f"{json.dumps(spring_law_json(t))})")
    return ""


def _matrix_difference(A, B):
    """Largest |A - B| relative to the largest entry, or 0 when within FILES.model_rtol (shapes equal)."""
    A = A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)
    B = B.toarray() if sp.issparse(B) else np.asarray(B, dtype=float)
    scale = max(float(np.max(np.abs(A))) if A.size else 0.0, float(np.max(np.abs(B))) if B.size else 0.0, 1e-300)
    d = float(np.max(np.abs(A - B))) / scale if A.size else 0.0
    return 0.0 if d <= FILES.model_rtol else d
