"""nnm HDF5 files: a model (matrices, springs, labels, display mesh) and its NNM branches.

Schema in docs/format.md; the file mechanics (atomic writes, one-line errors) are in h5file.py.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..results.branch import Branch
from ..model.elements import CubicSpring, PiecewiseLinearSpring, PolynomialSpring
from ..errors import NNMFileError, NNMInputError
from .importers import import_model, is_import_path
from .h5file import (STR, atomic_h5, open_nnm, read_attrs, read_group_tree, read_matrix, strings, write_attrs,
                     write_group_tree, write_matrix)
from ..model.mesh import DisplayMesh
from .sweep_groups import with_variant_models
from ..model.model import Model

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
        mg.create_dataset("displacement_map", data=m.displacement_map.astype(np.float32),
                          compression="gzip", compression_opts=9, shuffle=True)
        if m.part_ids is not None:
            mg.create_dataset("part_ids", data=m.part_ids.astype(np.int16), compression="gzip")
        mg.create_dataset("part_names", data=np.array(list(m.part_names), dtype=STR))
    if extra:
        write_group_tree(f.require_group("extra"), extra)


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


def read_model_group(f, path):
    if "model" not in f:
        raise NNMFileError(f"{path}: no /model group; not an nnm model file")
    g = f["model"]
    M = read_matrix(g, "M", path)
    K = read_matrix(g, "K", path)
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
    springs = [spring_from_json(int(d), None if o < 0 else int(o), law, path) for d, o, law in zip(dof, other, laws)]
    dof_labels = strings(g["dof_labels"]) if "dof_labels" in g else None
    mode_labels = strings(g["mode_labels"]) if "mode_labels" in g else None
    info = read_attrs(g["info"]) if "info" in g else {}
    mesh = None
    if "mesh" in f:
        mg = f["mesh"]
        try:
            mesh = DisplayMesh(
                vertices=mg["vertices"][()].astype(float), faces=mg["faces"][()],
                displacement_map=mg["displacement_map"][()],
                part_ids=mg["part_ids"][()] if "part_ids" in mg else None,
                part_names=strings(mg["part_names"]) if "part_names" in mg else [])
        except KeyError as exc:
            raise NNMFileError(f"{path}: /mesh is incomplete ({exc})") from None
    try:
        return Model(M, K, springs, dof_labels=dof_labels, mode_labels=mode_labels, mesh=mesh,
                     name=str(g.attrs.get("name", "")), info=info)
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None


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
    (under /branches).
    """
    if not isinstance(branch, Branch):
        raise NNMInputError(f"save_branch needs an nnm_solver.Branch, got {type(branch).__name__}")
    path = Path(path)
    if is_import_path(path):
        raise NNMInputError(f"{path} is an imported model file, not an nnm HDF5 file: save branches to a .h5 file "
                            f"(nnm-solve import {path.name} --out {path.with_suffix('.h5').name} makes one)")
    if path.exists():
        with open_nnm(path) as f:
            n_file = int(f["model"].attrs["n_dof"]) if "model" in f else None
        if n_file is not None and n_file != branch.model.n:
            raise NNMInputError(f"{path} holds a model with {n_file} DOFs but the branch has {branch.model.n}; "
                                f"save it to another file")
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
        columns = BRANCH_COLUMNS + (("coefficients",) if branch.coefficients is not None else ())
        for key in columns:
            data = getattr(branch, key)
            g.create_dataset(key, data=data, compression="gzip" if data.size > 64 else None)
        g.create_dataset("k3", data=branch.model.k3)
    return gname


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
                for key in ("freq_error", "steps"):
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
