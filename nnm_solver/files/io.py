"""nnm HDF5 files, the model: matrices, springs, labels, display mesh, extra groups and the stored Ritz basis
(``save_model``, ``load_model``, ``store_ritz_basis``); the branches are read and written by branch_io.py.

Schema in docs/format.md; the file mechanics (atomic writes, one-line errors) are in h5file.py.
"""
from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import scipy.sparse as sp

from ..model.elements import CubicSpring, PiecewiseLinearSpring, PolynomialSpring
from ..errors import NNMFileError, NNMInputError
from . import coupled_io
from .importers import import_model, is_import_path
from .h5file import (STR, atomic_h5, open_nnm, read_attrs, read_group_tree, read_matrix, strings, write_attrs,
                     write_group_tree, write_matrix)
from ..model.mesh import DisplayMesh
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
    scalar, coupled = coupled_io.split(model.springs)
    marker = [coupled_io.MARKER] if coupled else []         # coupled elements: /model/coupled (coupled_io.py)
    sg = g.create_group("springs")
    sg.create_dataset("dof", data=np.array([s.dof for s in scalar] + [-1] * len(marker), dtype=np.int64))
    sg.create_dataset("other", data=np.array([-1 if s.other is None else s.other for s in scalar] + [-1] * len(marker),
                                             dtype=np.int64))
    sg.create_dataset("k3", data=np.array([s.law().get(3, 0.0) for s in scalar] + [0.0] * len(marker), dtype=float))
    # every element's force law ({power: coefficient}, or a typed object); k3 alone describes cubic springs
    # (first-release files)
    sg.attrs["laws_json"] = json.dumps([spring_law_json(s) for s in scalar] + marker)
    if coupled:
        coupled_io.write_coupled(g, coupled)
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
    coupled = coupled_io.read_coupled(g, path)
    marked = [law == coupled_io.MARKER for law in laws]
    if any(marked) != bool(coupled):
        raise NNMFileError(f"{path}: /model/springs and /model/{coupled_io.GROUP} disagree about coupled elements")
    scalar = [spring_from_json(int(d), None if o < 0 else int(o), law, path)
              for d, o, law, mk in zip(dof, other, laws, marked) if not mk]
    return coupled_io.merge(scalar, coupled, path)


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
