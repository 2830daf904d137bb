"""A Ritz basis stored in its model's nnm file: /ritz_basis (docs/format.md), so that condensed harmonic balance on
a large model starts without the minutes of Lanczos (model/ritz.py computes the basis).

``store_ritz_basis(path, model, mode, harmonics)`` (files/io.py) computes (or takes from the process's cache) the
basis of a branch of ``mode`` with ``harmonics`` and writes it into the file, atomically; the file's model must be
``model`` (the basis belongs to the linear part: M, K_linear and the elements' places, checked by
``linear_fingerprint``).  Reading the file (``load_model``, ``load_branches``) registers a stored basis with
model/ritz.py (``register_basis_of_file``): only its eigenvalues are read then; the shapes (n x (m + 2 n_s) float64,
330 MB for the full aircraft) when a branch needs them.  A basis whose fingerprint is not the file's model's is not
used.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import h5py
import numpy as np

from ..errors import NNMFileError
from ..model.ritz import StoredBasis, register_stored_basis
from .h5file import atomic_file, file_lock, open_nnm

GROUP = "ritz_basis"

__all__ = ["store_basis_in_file", "register_basis_of_file", "GROUP"]


def write_basis_group(dst, system, fingerprint, mode, harmonics):
    """/ritz_basis in the open (new) file ``dst``: the basis of the ModalSystem ``system`` (ritz_system)."""
    g = dst.create_group(GROUP)
    g.attrs["fingerprint"] = fingerprint
    g.attrs["exact_modes"] = int(system.exact_modes)
    g.attrs["cutoff_hz"] = float(system.cutoff_hz)
    g.attrs["mode"] = int(mode)
    g.attrs["harmonics"] = int(harmonics)
    g.attrs["n_dof"] = int(system.Phi.shape[0])
    g.create_dataset("omega2", data=np.asarray(system.omega2, dtype=float))
    g.create_dataset("Phi", data=np.asarray(system.Phi, dtype=float))


def store_basis_in_file(path, system, fingerprint, mode, harmonics):
    """Write the basis into the existing nnm file ``path`` atomically: a copy of everything in it but an older
    basis (deleting a group in place would keep its space in the file), plus the new /ritz_basis.  The copy and
    rename hold the file's inter-process lock (h5file.file_lock), so a concurrent save to it is not lost."""
    with file_lock(path), atomic_file(path) as tmp:
        with open_nnm(path) as src, h5py.File(tmp, "w") as dst:
            for key, value in src.attrs.items():
                dst.attrs[key] = value
            for name in src:
                if name != GROUP:
                    src.copy(src[name], dst, name=name)
            write_basis_group(dst, system, fingerprint, mode, harmonics)
    register_basis_of_file(path, fingerprint)


def _read_phi(path, fingerprint):
    """The stored shapes of the basis ``fingerprint`` in ``path``, or None if the file no longer holds it."""
    try:
        with open_nnm(path) as f:
            g = f.get(GROUP)
            if g is None or g.attrs.get("fingerprint") != fingerprint:
                return None
            return np.ascontiguousarray(g["Phi"][()], dtype=float)
    except (NNMFileError, OSError, KeyError):
        return None


def register_basis_of_file(path, fingerprint, f=None):
    """Register the basis stored in the nnm file ``path`` (open as ``f``, or opened here) with model/ritz.py if it
    belongs to the model of linear fingerprint ``fingerprint``; a basis of another model is ignored (a warning).
    True if registered."""
    if f is None:
        with open_nnm(path) as f:
            return register_basis_of_file(path, fingerprint, f)
    g = f.get(GROUP)
    if g is None:
        return False
    try:
        stored_fp = str(g.attrs["fingerprint"])
        omega2 = np.asarray(g["omega2"][()], dtype=float)
        exact, cutoff = int(g.attrs["exact_modes"]), float(g.attrs["cutoff_hz"])
        shape = g["Phi"].shape
    except (KeyError, OSError, ValueError) as exc:
        warnings.warn(f"{path}: /{GROUP} is incomplete ({exc}); not used", stacklevel=3)
        return False
    if stored_fp != fingerprint or shape != (int(g.attrs.get("n_dof", shape[0])), len(omega2)):
        warnings.warn(f"{path}: the stored Ritz basis belongs to another model than the file's; not used "
                      f"(store it again: nnm_solver.store_ritz_basis)", stacklevel=3)
        return False
    source = str(Path(path).resolve())
    register_stored_basis(StoredBasis(fingerprint=stored_fp, omega2=omega2, exact_modes=exact, cutoff_hz=cutoff,
                                      load=lambda: _read_phi(source, stored_fp), source=source))
    return True
