"""nnm HDF5 files, the branches: append a branch to a file of its model (``save_branch``, refused with one line
for another model's file: ``check_branch_file``) and read them back (``load_branches``).

Schema in docs/format.md; the model's own group is read and written by io.py, the file mechanics (atomic writes,
one-line errors) are in h5file.py.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..results.branch import Branch
from ..model.elements import CubicSpring
from ..model.model import Model
from ..errors import NNMFileError, NNMInputError
from .importers import is_import_path
from .h5file import STR, atomic_h5, open_nnm, read_matrix, strings
from .sweep_groups import parse_branch_name, recorded_variants, with_variant_models
from . import coupled_io
from .io import BRANCH_COLUMNS, read_model_group, read_springs, spring_law_json, write_model_group
from .settings import FILES

__all__ = ["save_branch", "check_branch_file", "load_branches", "MODEL_RTOL"]


# ---------------------------------------------------------------------- branches
def _branch_group_name(f, branch):
    g = f.require_group("branches")
    base = (branch.name or f"mode{branch.mode}").replace("/", "∕")   # '/' separates HDF5 groups; the
    # name itself is kept in the group's attribute "name"
    name, k = base, 2
    while name in g:
        name, k = f"{base}_{k}", k + 1
    return name


def save_branch(path, branch, name=None):
    """Append ``branch`` to the nnm file at ``path`` (created with the branch's model if absent).

    Everything already in the file is kept; the write is atomic. Returns the group name used
    (under /branches).  A branch of another model than the file's is refused (NNMInputError, the
    file untouched; see check_branch_file): a branch may differ from it only by its cubic springs' k3,
    or be a sweep branch of a variant recorded in /sweeps.
    """
    if not isinstance(branch, Branch):
        raise NNMInputError(f"save_branch needs an nnm_solver.Branch, got {type(branch).__name__}")
    path = Path(path)
    if is_import_path(path):
        raise NNMInputError(f"{path} is an imported model file, not an nnm HDF5 file: save branches to a .h5 file "
                            f"(nnm-solve import {path.name} --out {path.with_suffix('.h5').name} makes one)")
    check_name = branch.name if name is None else str(name)
    check_branch_file(path, branch.model, check_name)
    with atomic_h5(path, copy_existing=True) as f:
        problem = _model_mismatch(f, path, branch.model, check_name)    # again under the lock: another process
        if problem:                                                    # may have created the file meanwhile
            raise _refusal(path, problem)
        if "model" not in f:
            write_model_group(f, branch.model)
        if name is not None:
            branch = branch.subset(slice(None))
            branch.name = str(name)
        gname = _branch_group_name(f, branch)
        g = f["branches"].create_group(gname)
        g.attrs["created_order"] = len(f["branches"]) - 1
        g.attrs["mode"] = branch.mode
        g.attrs["status"] = branch.status
        g.attrs["message"] = branch.message
        g.attrs["name"] = branch.name or gname
        g.attrs["settings_json"] = json.dumps(_jsonable(branch.settings.as_dict()))
        g.attrs["events_json"] = json.dumps(_jsonable(branch.events))
        g.attrs["tongues_json"] = json.dumps(_jsonable(branch.tongues))
        g.create_dataset("labels", data=np.array([str(x) for x in branch.labels], dtype=STR))
        g.create_dataset("freq_error", data=branch.freq_error)
        if np.any(branch.steps):
            g.create_dataset("steps", data=branch.steps)
        if not np.all(np.isnan(branch.fundamental_share)):
            g.create_dataset("fundamental_share", data=branch.fundamental_share)
        columns = BRANCH_COLUMNS + (("coefficients",) if branch.coefficients is not None else ())
        for key in columns:
            data = getattr(branch, key)
            g.create_dataset(key, data=data, compression="gzip" if data.size > 64 else None)
        g.create_dataset("k3", data=branch.model.k3)
    return gname


# ---------------------------------------------------------------------- the model a branch is appended to
#: an alias of settings.py's FILES.model_rtol (the code reads that)
MODEL_RTOL = FILES.model_rtol


def check_branch_file(path, model, name=None):
    """NNMInputError (one line: the file, what differs, the remedy) if a branch of ``model`` saved under
    ``name`` into the nnm file ``path`` would not be read back with ``model`` (see save_branch); nothing if
    the file does not exist yet or holds no model.  Callers can check a target before computing a branch."""
    path = Path(path)
    if not path.exists():
        return
    with open_nnm(path) as f:
        problem = _model_mismatch(f, path, model, name)
    if problem:
        raise _refusal(path, problem)


def _refusal(path, problem):
    """The one-line NNMInputError refusing a branch of another model than the file ``path``'s (``problem``: what
    differs)."""
    alt = _free_name(path)
    return NNMInputError(f"{path} holds another model than this branch's ({problem}); the file was left "
                         f"unchanged: save the branch to another file name, e.g. {alt} (nnm-solve: --out {alt})")


def _model_mismatch(f, path, model, name):
    """Why a branch of ``model`` (saved under ``name``) may not go into the open nnm file ``f``: '' when
    ``model`` is the file's model as ``load_branches`` will give it back, else what differs (one line).

    Accepted: the file's model up to the cubic springs' k3 (each branch stores its own k3 and gets it back),
    and for a sweep branch (``<variant>:mode<N>``) whose variant is recorded in /sweeps, the model of that
    variant (which is what it is read back with; its k3 then has to match the variant's).
    """
    if "model" not in f:
        return ""
    g = f["model"]
    n_file = int(g.attrs["n_dof"]) if "n_dof" in g.attrs else read_matrix(g, "K", path).shape[0]
    if n_file != model.n:
        return f"the file's model has {n_file} DOFs but the branch has {model.n}"
    M, K, springs = read_matrix(g, "M", path), read_matrix(g, "K", path), read_springs(g, path)
    where = ""
    parsed = parse_branch_name(name) if name else None
    variant = None
    if parsed is not None:
        vname = parsed[0]
        variant = recorded_variants(f).get(vname)
        if variant is None and vname == "base":
            variant = False                       # the base model itself, read back without its own k3
    if variant:                                   # a recorded sweep variant: compare with the varied model
        try:
            varied = variant.apply(Model(M, K, springs))
        except NNMInputError as exc:
            return f"sweep variant {variant.name!r} does not apply to the file's model ({exc})"
        M, K, springs = varied.M, varied.K, varied.springs
        where = f" with sweep variant {variant.name!r}"
    problems = [p for p in (_spring_difference(springs, model.springs, free_k3=variant is None, where=where),
                            _matrix_difference("M", M, model.M, where),
                            _matrix_difference("K", K, model.K, where)) if p]
    return "; ".join(problems)


def _joint(s):
    return f"{s.dof}-{'ground' if s.other is None else s.other}"


def _close(a, b):
    """Equal force-law descriptions (spring_law_json), numbers to FILES.model_rtol."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=FILES.model_rtol, abs_tol=0.0)
    return a == b


def _spring_difference(file_springs, springs, free_k3=True, where=""):
    """What differs between the file's springs and the branch's ('' if nothing).  free_k3: a cubic spring's
    k3 may differ (the branch's own k3 is stored with it and read back)."""
    if len(file_springs) != len(springs):
        return f"the file's model{where} has {len(file_springs)} springs, the branch's {len(springs)}"
    for i, (a, b) in enumerate(zip(file_springs, springs)):
        if coupled_io.is_coupled(a) or coupled_io.is_coupled(b):
            if not coupled_io.same_element(a, b):
                return f"element {i} (a PolynomialStiffness) differs between the file{where} and the branch's model"
            continue
        if (a.dof, a.other) != (b.dof, b.other):
            return f"spring {i} joins DOFs {_joint(a)} in the file{where}, {_joint(b)} in the branch's model"
        if type(a) is not type(b):
            return f"spring {i} is a {type(a).__name__} in the file{where}, a {type(b).__name__} in the branch's model"
        if free_k3 and isinstance(a, CubicSpring):
            continue
        la, lb = spring_law_json(a), spring_law_json(b)
        if not _close(la, lb):
            return (f"spring {i} ({_joint(a)}) has the force law {json.dumps(la)} in the file{where}, "
                    f"{json.dumps(lb)} in the branch's model")
    return ""


def _matrix_difference(label, A, B, where=""):
    """'' when the matrices are equal to FILES.model_rtol (relative to their largest entry), else what differs."""
    if A.shape != B.shape:
        return (f"{label} is {A.shape[0]}x{A.shape[1]} in the file{where}, {B.shape[0]}x{B.shape[1]} in the "
                f"branch's model")
    if sp.issparse(A) or sp.issparse(B):
        A, B = sp.csr_matrix(A), sp.csr_matrix(B)
        D = abs(A - B)
        diff = float(D.max()) if D.nnz else 0.0
        scale = max(float(abs(A).max()) if A.nnz else 0.0, float(abs(B).max()) if B.nnz else 0.0)
    else:
        A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
        diff = float(np.max(np.abs(A - B))) if A.size else 0.0
        scale = float(max(np.max(np.abs(A)), np.max(np.abs(B)))) if A.size else 0.0
    if not math.isfinite(diff):
        return f"{label} differs (non-finite entries)"
    if diff <= FILES.model_rtol * scale:
        return ""
    against = " from the file" + where if where else ""
    return f"{label} differs{against} by up to {100 * diff / scale:.3g} % of its largest entry"


def _free_name(path):
    """A file name next to ``path`` that does not exist yet: <stem>_2.h5, <stem>_3.h5, ..."""
    k = 2
    while True:
        cand = path.with_name(f"{path.stem}_{k}{path.suffix or '.h5'}")
        if not cand.exists():
            return cand
        k += 1


def _jsonable(obj):
    if hasattr(obj, "as_dict"):              # typed records (results/tongues.py)
        obj = obj.as_dict()
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def load_branches(path, model=None):
    """All branches stored in the nnm file at ``path`` (list of Branch, in file order).

    Branches of a sweep (``<variant>:mode<N>``, docs/sweep.md) come with their variant's model.

    model : the file's model if already loaded (saves reading it again).  Imported model files
    (.mat, .toml, .full) hold no branches: [].
    """
    if is_import_path(path):
        return []
    with open_nnm(path) as f:
        if model is None:
            model = read_model_group(f, path)
        out = []
        if "branches" not in f:
            return out
        for gname in sorted(f["branches"], key=lambda s: f["branches"][s].attrs.get("created_order", 0)):
            g = f["branches"][gname]
            try:
                cols = {k: g[k][()] for k in BRANCH_COLUMNS}
                if "coefficients" in g:
                    cols["coefficients"] = g["coefficients"][()]
                k3 = g["k3"][()] if "k3" in g else model.k3
                if "labels" in g:
                    cols["labels"] = strings(g["labels"])
                for key in ("freq_error", "steps", "fundamental_share"):
                    if key in g:
                        cols[key] = g[key][()]
                settings = json.loads(g.attrs.get("settings_json", "{}"))
                events = json.loads(g.attrs.get("events_json", "[]"))
                cols["tongues"] = json.loads(g.attrs.get("tongues_json", "[]"))
            except (KeyError, OSError, ValueError) as exc:
                raise NNMFileError(f"{path}: branch {gname} is incomplete or damaged ({exc})") from None
            m = model
            if len(k3) == len(model.springs) and not np.array_equal(k3, model.k3):   # the branch's own k3
                m = model.with_springs([CubicSpring(dof=s.dof, other=s.other, k3=float(k))
                                        if isinstance(s, CubicSpring) else s for s, k in zip(model.springs, k3)])
            try:
                out.append(Branch(m, int(g.attrs.get("mode", 0)), events=events,
                                  status=str(g.attrs.get("status", "")), message=str(g.attrs.get("message", "")),
                                  settings=settings, name=str(g.attrs.get("name", gname)), **cols))
            except (ValueError, TypeError) as exc:
                raise NNMFileError(f"{path}: branch {gname} has inconsistent shapes or settings ({exc})") from None
        if "sweeps" in f:                       # branches of a sweep get their variant's model
            with_variant_models(out, model, f)
        return out
