"""HDF5 files holding a model and its NNM branches (schema in docs/format.md).

Every write goes to a temporary file in the same folder and is renamed over the target
only when complete, so an interrupted write never damages an existing file.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
import scipy.sparse as sp

from .errors import NNMFileError, NNMInputError
from .model import CubicSpring, DisplayMesh, Model

FORMAT = "nnm"
FORMAT_VERSION = 1
_STR = h5py.string_dtype("utf-8")


# ---------------------------------------------------------------------- helpers
@contextmanager
def atomic_h5(path, copy_existing=False):
    """Open a temporary HDF5 file next to ``path``; rename it over ``path`` on success."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise NNMInputError(f"cannot write {path}: folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    os.close(fd)
    # mkstemp creates the file private (0600): give it the mode of the file it replaces, or the
    # default mode for new files
    if path.exists():
        mode_bits = path.stat().st_mode & 0o777
    else:
        umask = os.umask(0)
        os.umask(umask)
        mode_bits = 0o666 & ~umask
    os.chmod(tmp, mode_bits)
    try:
        if copy_existing and path.exists():
            shutil.copyfile(path, tmp)
            mode = "r+"
        else:
            mode = "w"
        with h5py.File(tmp, mode) as f:
            if mode == "w":
                f.attrs["format"] = FORMAT
                f.attrs["format_version"] = FORMAT_VERSION
            yield f
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


@contextmanager
def open_nnm(path):
    """Open an existing nnm HDF5 file for reading, with one-line errors for bad files."""
    path = Path(path)
    if not path.exists():
        raise NNMFileError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise NNMFileError(f"{path}: not a readable HDF5 file ({exc.__class__.__name__}); "
                           f"is it truncated or of another format?") from None
    try:
        if f.attrs.get("format") != FORMAT:
            raise NNMFileError(f"{path}: not an nnm file (missing attribute format='nnm')")
        version = int(f.attrs.get("format_version", -1))
        if version > FORMAT_VERSION:
            raise NNMFileError(f"{path}: format version {version} is newer than this nnm "
                               f"({FORMAT_VERSION}); upgrade nnm")
        yield f
    finally:
        f.close()


def _write_matrix(g, name, A):
    if sp.issparse(A):
        A = A.tocsr()
        sg = g.create_group(name)
        sg.attrs["sparse"] = "csr"
        sg.attrs["shape"] = A.shape
        sg.create_dataset("data", data=A.data, compression="gzip")
        sg.create_dataset("indices", data=A.indices, compression="gzip")
        sg.create_dataset("indptr", data=A.indptr, compression="gzip")
    else:
        g.create_dataset(name, data=np.asarray(A, dtype=float), compression="gzip")


def _read_matrix(g, name, path):
    if name not in g:
        raise NNMFileError(f"{path}: missing dataset /model/{name}; not a complete nnm model file")
    obj = g[name]
    try:
        if isinstance(obj, h5py.Group):
            shape = tuple(int(s) for s in obj.attrs["shape"])
            return sp.csr_matrix((obj["data"][()], obj["indices"][()], obj["indptr"][()]), shape=shape)
        return obj[()]
    except (KeyError, OSError, ValueError) as exc:
        raise NNMFileError(f"{path}: /model/{name} is unreadable ({exc}); the file is damaged") from None


def _strings(ds):
    return [s.decode() if isinstance(s, bytes) else str(s) for s in ds[()]]


def write_attrs(obj, mapping):
    """Store a dict of numbers / strings / small arrays as HDF5 attributes."""
    for k, v in (mapping or {}).items():
        if v is None:
            continue
        obj.attrs[str(k)] = v if not isinstance(v, (list, tuple)) or not v or not isinstance(v[0], str) \
            else np.array(v, dtype=_STR)


def read_attrs(obj):
    out = {}
    for k, v in obj.attrs.items():
        if isinstance(v, bytes):
            v = v.decode()
        elif isinstance(v, np.ndarray) and v.dtype.kind in "OS":
            v = [s.decode() if isinstance(s, bytes) else str(s) for s in v]
        elif isinstance(v, np.generic):
            v = v.item()
        out[k] = v
    return out


def _write_group_tree(g, content):
    """content: dict name -> array / number / str / dict (sub-group)."""
    for k, v in content.items():
        if isinstance(v, dict):
            _write_group_tree(g.create_group(k), v)
        elif isinstance(v, str):
            g.attrs[k] = v
        elif isinstance(v, (list, tuple)) and v and isinstance(v[0], str):
            g.create_dataset(k, data=np.array(v, dtype=_STR))
        else:
            arr = np.asarray(v)
            g.create_dataset(k, data=arr, compression="gzip" if arr.size > 64 else None)


def _read_group_tree(g):
    out = dict(read_attrs(g))
    for k, v in g.items():
        if isinstance(v, h5py.Group):
            out[k] = _read_group_tree(v)
        elif v.dtype.kind in "OS":
            out[k] = _strings(v)
        else:
            out[k] = v[()]
    return out


# ---------------------------------------------------------------------- model
def write_model_group(f, model, extra=None):
    g = f.create_group("model")
    g.attrs["n_dof"] = model.n
    g.attrs["name"] = model.name
    _write_matrix(g, "M", model.M)
    _write_matrix(g, "K", model.K)
    sg = g.create_group("springs")
    sg.create_dataset("dof", data=np.array([s.dof for s in model.springs], dtype=np.int64))
    sg.create_dataset("other", data=np.array([-1 if s.other is None else s.other for s in model.springs],
                                             dtype=np.int64))
    sg.create_dataset("k3", data=np.array([s.k3 for s in model.springs], dtype=float))
    if model.dof_labels is not None:
        g.create_dataset("dof_labels", data=np.array(model.dof_labels, dtype=_STR))
    if model.mode_labels is not None:
        g.create_dataset("mode_labels", data=np.array(model.mode_labels, dtype=_STR))
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
        mg.create_dataset("part_names", data=np.array(list(m.part_names), dtype=_STR))
    if extra:
        _write_group_tree(f.require_group("extra"), extra)


def save_model(path, model, extra=None):
    """Write ``model`` (with its mesh and labels) to a new nnm HDF5 file at ``path``.

    An existing file at ``path`` is replaced atomically (its branches are not kept).
    extra : optional dict of groups stored under /extra (e.g. reduction validation tables,
    provenance): values are arrays, numbers, strings or nested dicts.
    """
    if not isinstance(model, Model):
        raise NNMInputError(f"save_model needs an nnm_solver.Model, got {type(model).__name__}")
    with atomic_h5(path) as f:
        write_model_group(f, model, extra)


def read_model_group(f, path):
    if "model" not in f:
        raise NNMFileError(f"{path}: no /model group; not an nnm model file")
    g = f["model"]
    M = _read_matrix(g, "M", path)
    K = _read_matrix(g, "K", path)
    try:
        sg = g["springs"]
        dof, other, k3 = sg["dof"][()], sg["other"][()], sg["k3"][()]
    except KeyError:
        raise NNMFileError(f"{path}: missing /model/springs/(dof, other, k3)") from None
    if not (len(dof) == len(other) == len(k3)):
        raise NNMFileError(f"{path}: /model/springs datasets have different lengths")
    springs = [CubicSpring(dof=int(d), other=None if o < 0 else int(o), k3=float(k))
               for d, o, k in zip(dof, other, k3)]
    dof_labels = _strings(g["dof_labels"]) if "dof_labels" in g else None
    mode_labels = _strings(g["mode_labels"]) if "mode_labels" in g else None
    info = read_attrs(g["info"]) if "info" in g else {}
    mesh = None
    if "mesh" in f:
        mg = f["mesh"]
        try:
            mesh = DisplayMesh(
                vertices=mg["vertices"][()].astype(float), faces=mg["faces"][()],
                displacement_map=mg["displacement_map"][()],
                part_ids=mg["part_ids"][()] if "part_ids" in mg else None,
                part_names=_strings(mg["part_names"]) if "part_names" in mg else [])
        except KeyError as exc:
            raise NNMFileError(f"{path}: /mesh is incomplete ({exc})") from None
    try:
        return Model(M, K, springs, dof_labels=dof_labels, mode_labels=mode_labels, mesh=mesh,
                     name=str(g.attrs.get("name", "")), info=info)
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None


def load_model(path):
    """Read the model (matrices, springs, labels, mesh) of an nnm HDF5 file."""
    with open_nnm(path) as f:
        return read_model_group(f, path)


def load_extra(path, name):
    """Read the /extra/<name> group (dict of arrays/attributes), or None if absent."""
    with open_nnm(path) as f:
        if "extra" not in f or name not in f["extra"]:
            return None
        return _read_group_tree(f["extra"][name])


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
    from .branch import Branch
    import json

    if not isinstance(branch, Branch):
        raise NNMInputError(f"save_branch needs an nnm_solver.Branch, got {type(branch).__name__}")
    path = Path(path)
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
        g.attrs["settings_json"] = json.dumps(_jsonable(branch.settings))
        g.attrs["events_json"] = json.dumps(_jsonable(branch.events))
        for key in ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable"):
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

    model : the file's model if already loaded (saves reading it again).
    """
    from .branch import Branch
    import json

    with open_nnm(path) as f:
        if model is None:
            model = read_model_group(f, path)
        out = []
        if "branches" not in f:
            return out
        for gname in sorted(f["branches"], key=lambda s: f["branches"][s].attrs.get("created_order", 0)):
            g = f["branches"][gname]
            try:
                cols = {k: g[k][()] for k in ("energy", "frequency_hz", "period", "x0", "v0", "floquet", "stable")}
                k3 = g["k3"][()] if "k3" in g else model.k3
                settings = json.loads(g.attrs.get("settings_json", "{}"))
                events = json.loads(g.attrs.get("events_json", "[]"))
            except (KeyError, OSError, ValueError) as exc:
                raise NNMFileError(f"{path}: branch {gname} is incomplete or damaged ({exc})") from None
            m = model
            if len(k3) == len(model.springs) and not np.array_equal(k3, model.k3):
                m = model.with_springs([CubicSpring(dof=s.dof, other=s.other, k3=float(k))
                                        for s, k in zip(model.springs, k3)])
            try:
                out.append(Branch(m, int(g.attrs.get("mode", 0)), events=events,
                                  status=str(g.attrs.get("status", "")), message=str(g.attrs.get("message", "")),
                                  settings=settings, name=str(g.attrs.get("name", gname)), **cols))
            except ValueError as exc:
                raise NNMFileError(f"{path}: branch {gname} has inconsistent shapes ({exc})") from None
        return out
