"""HDF5 mechanics of nnm files: atomic writes, opening with one-line errors, matrices, attributes
and nested groups.  The schema of models and branches is in io.py (and docs/format.md).

Every write goes to a temporary file in the folder of the real file (symbolic links resolved) and is renamed
over it only when complete, so an interrupted write never damages an existing file and a link stays a link.
An update of an existing file (copy, append, rename) holds an inter-process lock on ``<file>.lock``
(file_lock), so concurrent appends from several processes all end up in the file.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
import scipy.sparse as sp

from ..errors import NNMFileError, NNMInputError
from .settings import FILES

try:                        # POSIX: flock locks (file_lock)
    import fcntl
except ImportError:         # Windows
    fcntl = None
try:
    import msvcrt
except ImportError:         # not Windows
    msvcrt = None

FORMAT = "nnm"
FORMAT_VERSION = 1
STR = h5py.string_dtype("utf-8")


def real_target(path):
    """The file a write to ``path`` has to replace: ``path`` with its symbolic links resolved (os.path.realpath),
    so that saving through a link updates the linked file and keeps the link.  NNMInputError (one line) if the
    folder of that file does not exist."""
    real = Path(os.path.realpath(path))
    if not real.parent.is_dir():
        shown = f"{path} (a link to {real})" if real != Path(os.path.abspath(path)) else f"{path}"
        raise NNMInputError(f"cannot write {shown}: folder {real.parent} does not exist")
    return real


def lock_path(path):
    """The lock file of the nnm file ``path``: ``<real file>.lock`` beside the file the links of ``path`` lead to."""
    real = Path(os.path.realpath(path))
    return real.with_name(real.name + ".lock")


def _try_lock(fd):
    """Take the exclusive lock of the open lock file ``fd`` without waiting: True if taken, False if another
    process (or another open of the lock file in this process) holds it."""
    if fcntl is not None:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:     # flock's only way of answering "held by another"
            return False
        return True
    os.lseek(fd, 0, os.SEEK_SET)
    try:
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError:                 # msvcrt's way of answering "held by another"
        return False
    return True


def _unlock(fd):
    if fcntl is not None:
        fcntl.flock(fd, fcntl.LOCK_UN)
    else:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)


def _still_at(fd, lock):
    """True if the open file ``fd`` is still the file at the path ``lock`` (not removed by its previous holder)."""
    try:
        return os.path.samestat(os.fstat(fd), os.stat(lock))
    except FileNotFoundError:   # removed between our open and our lock: a race with its holder, not an error
        return False


@contextmanager
def file_lock(path):
    """Hold the inter-process lock of the nnm file ``path`` for the block (exclusive; one writer at a time).

    Held by every write of an nnm file (atomic_h5; ritz_store.store_basis_in_file), from before it reads the
    existing file until after the rename, so two processes appending to one file both keep their data; readers need
    no lock (the rename that publishes a write is atomic).  The lock is ``fcntl.flock`` on ``<file>.lock``
    beside the real file (lock_path; links resolved, so a link and its target share one lock), created when
    needed.  The holder removes it while still holding it, and a process that gets the lock of a lock file
    already removed (it opened it before the removal) opens the new one and tries again, so two processes
    never both hold a lock.  On Windows (no fcntl) ``msvcrt.locking`` of its first byte is used and the lock
    file is left in place (an open file cannot be removed there); without either module there is no lock.
    A lock is released by the OS if its holder dies, so a leftover lock file never blocks a later save.
    Waiting is bounded by FILES.lock_timeout seconds: after that, NNMFileError (one line naming the file).
    The lock is not re-entrant: a block holding it must not take it again for the same file.
    """
    if fcntl is None and msvcrt is None:
        yield
        return
    lock = lock_path(real_target(path))
    deadline = time.monotonic() + FILES.lock_timeout
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        taken = _try_lock(fd)
        while not taken and time.monotonic() < deadline:
            time.sleep(FILES.lock_poll)
            taken = _try_lock(fd)
        if not taken:
            os.close(fd)
            raise NNMFileError(f"cannot write {path}: another process has been updating it for more than "
                               f"{FILES.lock_timeout:g} s (it holds the lock {lock}); the file is unchanged, "
                               f"save again when that process has finished")
        if fcntl is None or _still_at(fd, lock):
            break
        _unlock(fd)             # the lock of a removed lock file: take the new one
        os.close(fd)
    try:
        yield
    finally:
        if fcntl is not None and _still_at(fd, lock):
            os.unlink(lock)     # while holding it: whoever waits on this file sees it removed and retries
        _unlock(fd)
        os.close(fd)


@contextmanager
def atomic_file(path):
    """A temporary path next to the file ``path`` leads to, renamed over that file when the block completes.

    Symbolic links are resolved (real_target): the temporary file is written in the real file's folder and
    renamed over the real file, so a link stays a link and the file it points to gets the new content.
    The file gets the permissions of the file it replaces, or the default ones for a new file (mkstemp
    alone would make it private); on any error the temporary file is removed and the file is untouched.
    This does not lock: the writes of nnm files hold file_lock around it (atomic_h5); exports need none.
    """
    real = real_target(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{real.name}.", suffix=".tmp", dir=real.parent)
    os.close(fd)
    if real.exists():
        mode_bits = real.stat().st_mode & 0o777
    else:
        umask = os.umask(0)
        os.umask(umask)
        mode_bits = 0o666 & ~umask
    os.chmod(tmp, mode_bits)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, real)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


@contextmanager
def atomic_h5(path, copy_existing=False):
    """Open a temporary HDF5 file next to the file ``path`` leads to; rename it over that file on success.

    copy_existing : start from a copy of the existing file (to append to it) instead of an empty nnm file.
    The write holds the file's inter-process lock (file_lock) from before the copy until after the rename, so
    concurrent writes from several processes are applied one after the other and no append is lost; the block
    sees the file as the previous writer left it.  Links are resolved as in atomic_file.
    """
    with file_lock(path), atomic_file(path) as tmp:
        real = Path(os.path.realpath(path))
        if copy_existing and real.exists():
            shutil.copyfile(real, tmp)
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
