"""HDF5 mechanics of nnm files: atomic writes, opening with one-line errors, matrices, attributes
and nested groups.  The schema of models and branches is in io.py (and docs/format.md).

Every write goes to a temporary file in the same folder and is renamed over the target only when
complete, so an interrupted write never damages an existing file.
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

from ..errors import NNMFileError, NNMInputError

FORMAT = "nnm"
FORMAT_VERSION = 1
STR = h5py.string_dtype("utf-8")


@contextmanager
def atomic_file(path):
    """A temporary path next to ``path`` (same folder), renamed over ``path`` when the block completes.

    The file gets the permissions of the file it replaces, or the default ones for a new file (mkstemp
    alone would make it private); on any error the temporary file is removed and ``path`` is untouched.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise NNMInputError(f"cannot write {path}: folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    os.close(fd)
    if path.exists():
        mode_bits = path.stat().st_mode & 0o777
    else:
        umask = os.umask(0)
        os.umask(umask)
        mode_bits = 0o666 & ~umask
    os.chmod(tmp, mode_bits)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


@contextmanager
def atomic_h5(path, copy_existing=False):
    """Open a temporary HDF5 file next to ``path``; rename it over ``path`` on success."""
    path = Path(path)
    with atomic_file(path) as tmp:
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


def write_matrix(g, name, A):
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


def read_matrix(g, name, path):
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


def strings(ds):
    return [s.decode() if isinstance(s, bytes) else str(s) for s in ds[()]]


def write_attrs(obj, mapping):
    """Store a dict of numbers / strings / small arrays as HDF5 attributes."""
    for k, v in (mapping or {}).items():
        if v is None:
            continue
        obj.attrs[str(k)] = v if not isinstance(v, (list, tuple)) or not v or not isinstance(v[0], str) \
            else np.array(v, dtype=STR)


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


def write_group_tree(g, content):
    """content: dict name -> array / number / str / dict (sub-group)."""
    for k, v in content.items():
        if isinstance(v, dict):
            write_group_tree(g.create_group(k), v)
        elif isinstance(v, str):
            g.attrs[k] = v
        elif isinstance(v, (list, tuple)) and v and isinstance(v[0], str):
            g.create_dataset(k, data=np.array(v, dtype=STR))
        else:
            arr = np.asarray(v)
            g.create_dataset(k, data=arr, compression="gzip" if arr.size > 64 else None)


def read_group_tree(g):
    out = dict(read_attrs(g))
    for k, v in g.items():
        if isinstance(v, h5py.Group):
            out[k] = read_group_tree(v)
        elif v.dtype.kind in "OS":
            out[k] = strings(v)
        else:
            out[k] = v[()]
    return out
