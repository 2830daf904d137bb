"""nnm HDF5 files: a model (matrices, springs, labels, display mesh) and its NNM branches.

Schema in docs/format.md; the file mechanics (atomic writes, one-line errors) are in h5file.py.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import scipy.sparse as sp

from ..results.branch import Branch
from ..model.elements import CubicSpring, PiecewiseLinearSpring, PolynomialSpring
from ..errors import NNMFileError, NNMInputError
from .importers import import_model, is_import_path
from .h5file import (STR, atomic_h5, open_nnm, read_attrs, read_group_tree, read_matrix, strings, write_attrs,
                     write_group_tree, write_matrix)
from ..model.mesh import DisplayMesh
from .sweep_groups import parse_branch_name, recorded_variants, with_variant_models
from ..model.model import Model
from ..model.ritz import linear_fingerprint, ritz_system
from .ritz_store import GROUP as RITZ_GROUP
from .ritz_store import register_basis_of_file, store_basis_in_file

BRANCH_COLUMNS = ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable")


PWL_KEYS = {"type", "stiffnesses", "breakpoints", "eps"}
PWL_NEGATIVE_KEYS = {"stiffnesses_negative", "breakpoints_negative"}


def spring_law_json(spring):
    """One entry of /model/springs laws_json: {power: coefficient} for polynomial laws (first form),
    {"type": "piecewise_linear", "stiffnesses": [...], "breakpoints": [...], "eps": eps} for an odd
    piecewise-linear law, or {"type": "piecewise_linear_asymmetric", ... the same keys,
    "stiffnesses_negative": [...], "breakpoints_negative": [...]} for one whose compression side has its
    own law (a type of its own, so that readers which do not know it refuse the file instead of reading
    an odd law)."""
    if isinstance(spring, PiecewiseLinearSpring):
        out = {"type": "piecewise_linear", "stiffnesses": list(spring.stiffnesses),
               "breakpoints": list(spring.breakpoints), "eps": spring.eps}
        if not spring.symmetric:
            out.update(type="piecewise_linear_asymmetric", stiffnesses_negative=list(spring.stiffnesses_negative),
                       breakpoints_negative=list(spring.breakpoints_negative))
        return out
    return {str(p): c for p, c in spring.law().items()}


def spring_from_json(dof, other, law, path="file"):
    """The element of one laws_json entry (see spring_law_json)."""
    if not isinstance(law, dict):
        raise NNMFileError(f"{path}: /model/springs/laws_json entry {law!r} is not an object")
    kind = law.get("type", "polynomial")
    if kind in ("piecewise_linear", "piecewise_linear_asymmetric"):
        allowed = PWL_KEYS | (PWL_NEGATIVE_KEYS if kind == "piecewise_linear_asymmetric" else set())
        extra = sorted(set(law) - allowed)
        if extra:
            raise NNMFileError(f"{path}: {kind} spring with unknown key(s) {', '.join(extra)}")
        try:
            neg = {k: law[k] for k in PWL_NEGATIVE_KEYS} if kind == "piecewise_linear_asymmetric" else {}
            return PiecewiseLinearSpring(dof=dof, other=other, stiffnesses=law["stiffnesses"],
                                         breakpoints=law["breakpoints"], **({"eps": law["eps"]} if "eps" in law else {}),
                                         **neg)
        except KeyError as exc:
            raise NNMFileError(f"{path}: {kind} spring without {exc}") from None
    if kind != "polynomial":
        raise NNMFileError(f"{path}: unknown spring type {kind!r} in /model/springs/laws_json "
                           f"(this nnm reads 'polynomial', 'piecewise_linear' and 'piecewise_linear_asymmetric')")
    return spring_from_law(dof, other, {int(p): c for p, c in law.items() if p != "type"})


def spring_from_law(dof, other, law):
    """The element for a force law {power: coefficient}: a CubicSpring for {3: k3}, else a PolynomialSpring."""
    if set(law) == {3}:
        return CubicSpring(dof=dof, other=other, k3=float(law[3]))
    return PolynomialSpring(dof=dof, other=other, coefficients=law)


# ---------------------------------------------------------------------- model
def write_model_group(f, model, extra=None):
    g = f.create_group("model")
    g.attrs["n_dof"] = model.n
    g.attrs["name"] = model.name
    write_matrix(g, "M", model.M)
    write_matrix(g, "K", model.K)
    sg = g.create_group("springs")
    sg.create_dataset("dof", data=np.array([s.dof for s in model.springs], dtype=np.int64))
    sg.create_dataset("other", data=np.array([-1 if s.other is None else s.other for s in model.springs],
                                             dtype=np.int64))
    sg.create_dataset("k3", data=model.k3)
    # every element's force law ({power: coefficient}, or a typed object); k3 alone describes cubic springs
    # (first-release files)
    sg.attrs["laws_json"] = json.dumps([spring_law_json(s) for s in model.springs])
    if model.dof_labels is not None:
        g.create_dataset("dof_labels", data=np.array(model.dof_labels, dtype=STR))
    if model.mode_labels is not None:
        g.create_dataset("mode_labels", data=np.array(model.mode_labels, dtype=STR))
    write_attrs(g.create_group("info"), model.info)
    if model.mesh is not None:
        m = model.mesh
        mg = f.create_group("mesh")
        mg.create_dataset("vertices", data=m.vertices.astype(np.float32), compression="gzip")
        mg.create_dataset("faces", data=m.faces.astype(np.int32), compression="gzip")
        if sp.issparse(m.displacement_map):
            write_sparse_map(mg, m.displacement_map)
        else:
            mg.create_dataset("displacement_map", data=m.displacement_map.astype(np.float32),
                              compression="gzip", compression_opts=9, shuffle=True)
        if m.part_ids is not None:
            mg.create_dataset("part_ids", data=m.part_ids.astype(np.int16), compression="gzip")
        mg.create_dataset("part_names", data=np.array(list(m.part_names), dtype=STR))
    if extra:
        write_group_tree(f.require_group("extra"), extra)


def write_sparse_map(mg, D):
    """A sparse display map as the group /mesh/displacement_map: attrs sparse="csr" and shape, datasets
    data (float32), indices and indptr (int32 where they fit)."""
    D = sp.csr_matrix(D)
    g = mg.create_group("displacement_map")
    g.attrs["sparse"] = "csr"
    g.attrs["shape"] = np.asarray(D.shape, dtype=np.int64)
    index = np.int32 if max(D.shape[1], D.nnz) < 2 ** 31 else np.int64
    g.create_dataset("data", data=D.data.astype(np.float32), compression="gzip", shuffle=True)
    g.create_dataset("indices", data=D.indices.astype(index), compression="gzip", shuffle=True)
    g.create_dataset("indptr", data=D.indptr.astype(index), compression="gzip", shuffle=True)


def read_displacement_map(mg, path):
    """/mesh/displacement_map: a dense float32 dataset, or a CSR group (write_sparse_map), kept sparse."""
    obj = mg["displacement_map"]
    if not isinstance(obj, h5py.Group):
        return obj[()]
    if obj.attrs.get("sparse") != "csr":
        raise NNMFileError(f"{path}: /mesh/displacement_map is a group without the attribute sparse='csr'")
    try:
        shape = tuple(int(s) for s in obj.attrs["shape"])
        return sp.csr_matrix((obj["data"][()], obj["indices"][()], obj["indptr"][()]), shape=shape)
    except (KeyError, OSError, ValueError) as exc:
        raise NNMFileError(f"{path}: /mesh/displacement_map is unreadable ({exc}); the file is damaged") from None


def save_model(path, model, extra=None):
    """Write ``model`` (with its mesh and labels) to a new nnm HDF5 file at ``path``.

    An existing file at ``path`` is replaced atomically (its branches are not kept).
    extra : optional dict of groups stored under /extra (e.g. reduction validation tables,
    provenance): values are arrays, numbers, strings or nested dicts.
    """
    if not isinstance(model, Model):
        raise NNMInputError(f"save_model needs an nnm_solver.Model, got {type(model).__name__}")
    if is_import_path(path):
        raise NNMInputError(f"{path}: nnm writes HDF5 model files; give a .h5 path (this suffix is an import format)")
    with atomic_h5(path) as f:
        write_model_group(f, model, extra)


def read_springs(g, path):
    """The nonlinear elements of the /model group ``g``."""
    try:
        sg = g["springs"]
        dof, other, k3 = sg["dof"][()], sg["other"][()], sg["k3"][()]
    except KeyError:
        raise NNMFileError(f"{path}: missing /model/springs/(dof, other, k3)") from None
    if not (len(dof) == len(other) == len(k3)):
        raise NNMFileError(f"{path}: /model/springs datasets have different lengths")
    laws = json.loads(sg.attrs["laws_json"]) if "laws_json" in sg.attrs else [{"3": float(k)} for k in k3]
    if len(laws) != len(dof):
        raise NNMFileError(f"{path}: /model/springs/laws_json has {len(laws)} entries for {len(dof)} springs")
    return [spring_from_json(int(d), None if o < 0 else int(o), law, path) for d, o, law in zip(dof, other, laws)]


def store_ritz_basis(path, model, mode, harmonics, f_cut_hz=None):
    """Store the Ritz basis (model/ritz.py) of a condensed-HB branch of the 1-based ``mode`` with ``harmonics`` (or
    of the cutoff ``f_cut_hz``) as /ritz_basis in the nnm file ``path`` (files/ritz_store.py), whose model must be
    ``model`` up to its force laws' coefficients (NNMInputError otherwise, the file untouched).  The basis is
    computed here unless this process has it; one stored before is replaced; the write is atomic.  A branch of a
    model read from the file then starts from it (no Lanczos).  Returns dict(exact_modes, cutoff_hz, columns)."""
    path = Path(path)
    if not isinstance(model, Model):
        raise NNMInputError(f"store_ritz_basis needs an nnm_solver.Model, got {type(model).__name__}")
    if is_import_path(path) or not path.exists():
        raise NNMInputError(f"{path}: no nnm model file there; write the model first (nnm_solver.save_model)")
    fingerprint = linear_fingerprint(model)
    with open_nnm(path) as f:
        file_model = read_model_group(f, path, register_basis=False)
    if linear_fingerprint(file_model) != fingerprint:
        raise NNMInputError(f"{path} holds another model than this one (M, K or the elements' places differ); the "
                            f"basis was not stored: store it in the model's own file")
    system = ritz_system(model, mode, harmonics, f_cut_hz)
    store_basis_in_file(path, system, fingerprint, mode, harmonics)
    return dict(exact_modes=int(system.exact_modes), cutoff_hz=float(system.cutoff_hz), columns=len(system.omega2))


def read_model_group(f, path, register_basis=True):
    if "model" not in f:
        raise NNMFileError(f"{path}: no /model group; not an nnm model file")
    g = f["model"]
    M = read_matrix(g, "M", path)
    K = read_matrix(g, "K", path)
    springs = read_springs(g, path)
    dof_labels = strings(g["dof_labels"]) if "dof_labels" in g else None
    mode_labels = strings(g["mode_labels"]) if "mode_labels" in g else None
    info = read_attrs(g["info"]) if "info" in g else {}
    mesh = None
    if "mesh" in f:
        mg = f["mesh"]
        try:
            mesh = DisplayMesh(
                vertices=mg["vertices"][()].astype(float), faces=mg["faces"][()],
                displacement_map=read_displacement_map(mg, path),
                part_ids=mg["part_ids"][()] if "part_ids" in mg else None,
                part_names=strings(mg["part_names"]) if "part_names" in mg else [])
        except KeyError as exc:
            raise NNMFileError(f"{path}: /mesh is incomplete ({exc})") from None
    try:
        model = Model(M, K, springs, dof_labels=dof_labels, mode_labels=mode_labels, mesh=mesh,
                      name=str(g.attrs.get("name", "")), info=info)
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
    if register_basis and RITZ_GROUP in f:         # a stored Ritz basis: its shapes are read when a branch needs them
        register_basis_of_file(path, linear_fingerprint(model), f)
    return model


def load_model(path):
    """Read a model (matrices, springs, labels, mesh): an nnm HDF5 file, or by suffix an FE model import,
    .mat (MATLAB v5/v7.3), .toml (model description naming MatrixMarket / Abaqus / ANSYS / MATLAB matrix
    files, springs, units, display mesh) or .full (ANSYS); see nnm_solver.importers and docs/import.md."""
    if is_import_path(path):
        return import_model(path)
    with open_nnm(path) as f:
        return read_model_group(f, path)


def load_extra(path, name):
    """Read the /extra/<name> group (dict of arrays/attributes), or None if absent."""
    with open_nnm(path) as f:
        if "extra" not in f or name not in f["extra"]:
            return None
        return read_group_tree(f["extra"][name])


# ---------------------------------------------------------------------- branches
def _branch_group_name(f, branch):
    g = f.require_group("branches")
    base = branch.name or f"mode{branch.mode}"
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
    check_branch_file(path, branch.model, branch.name if name is None else str(name))
    with atomic_h5(path, copy_existing=True) as f:
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
#: relative tolerance of the model comparison (a model read back from a file is bit-identical; a model
#: built again from the same description is too, up to rounding)
MODEL_RTOL = 1e-10


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
        alt = _free_name(path)
        raise NNMInputError(f"{path} holds another model than this branch's ({problem}); the file was left "
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
    """Equal force-law descriptions (spring_law_json), numbers to MODEL_RTOL."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=MODEL_RTOL, abs_tol=0.0)
    return a == b


def _spring_difference(file_springs, springs, free_k3=True, where=""):
    """What differs between the file's springs and the branch's ('' if nothing).  free_k3: a cubic spring's
    k3 may differ (the branch's own k3 is stored with it and read back)."""
    if len(file_springs) != len(springs):
        return f"the file's model{where} has {len(file_springs)} springs, the branch's {len(springs)}"
    for i, (a, b) in enumerate(zip(file_springs, springs)):
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
    """'' when the matrices are equal to MODEL_RTOL (relative to their largest entry), else what differs."""
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
    if diff <= MODEL_RTOL * scale:
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
