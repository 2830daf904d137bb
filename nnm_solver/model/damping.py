r"""Viscous damping of a model in its mass-normalised modal coordinates (``modal.py``).

Modal damping gives mode k the term 2 zeta_k w_k q_k' (ratio zeta_k, angular frequency w_k); a damping
matrix C (N s/m) adds Phi^T C Phi, diagonal for proportional (e.g. Rayleigh) damping, full when it couples
the modes.  ``modal_damping`` checks the user's values (one-line NNMInputError) and returns both forms.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import NNMInputError
from .modal import modal_system

__all__ = ["modal_damping"]


def modal_damping(model, damping, damping_matrix=None):
    """(zeta (n,), c (n,) or None, Cq (n, n)): the modal damping ratios, the modal damping coefficients
    2 zeta_k w_k plus the diagonal of Phi^T C Phi when that is diagonal (None when the damping matrix couples
    the modes), and the full modal damping matrix.  NNMInputError (one line) for bad values."""
    n = model.n
    if np.ndim(damping) == 0:
        z = float(damping) if isinstance(damping, (int, float, np.number)) and not isinstance(damping, bool) else None
        if z is None:
            raise NNMInputError(f"damping must be a ratio or one ratio per mode, got {damping!r}")
        if not math.isfinite(z):
            raise NNMInputError(f"damping is {z}: the damping ratio must be finite")
        if z < 0:
            raise NNMInputError(f"damping is {z:g}: damping ratios must be >= 0 (negative damping feeds energy in)")
        zeta = np.full(n, z)
    else:
        try:
            zeta = np.asarray(damping, dtype=float)
        except (TypeError, ValueError):
            what = type(damping).__name__
            raise NNMInputError(f"damping must be a ratio or one ratio per mode, got {what}") from None
        if zeta.ndim != 1 or len(zeta) != n:
            raise NNMInputError(f"damping has {zeta.size} ratios, the model has {n} modes: give one ratio or one "
                                f"per mode")
        bad = np.flatnonzero(~np.isfinite(zeta))
        if len(bad):
            raise NNMInputError(f"damping ratio of mode {bad[0] + 1} is {zeta[bad[0]]}: ratios must be finite")
        neg = np.flatnonzero(zeta < 0)
        if len(neg):
            raise NNMInputError(f"damping ratio of mode {neg[0] + 1} is {zeta[neg[0]]:g}: damping ratios must be >= 0")
    system = modal_system(model)
    w = np.sqrt(system.omega2)
    c = 2.0 * zeta * w
    Cq = np.diag(c)
    if damping_matrix is not None:
        try:
            C = np.asarray(damping_matrix.toarray() if hasattr(damping_matrix, "toarray") else damping_matrix,
                           dtype=float)
        except (TypeError, ValueError):
            raise NNMInputError("damping_matrix must be a numeric n x n matrix (N s/m)") from None
        if C.shape != (n, n):
            raise NNMInputError(f"damping_matrix has shape {C.shape}, the model has {n} DOFs: give an {n} x {n} matrix")
        if not np.all(np.isfinite(C)):
            raise NNMInputError("damping_matrix contains NaN or infinite entries")
        scale = max(float(np.max(np.abs(C))), 1e-300)
        if np.max(np.abs(C - C.T)) > 1e-8 * scale:
            raise NNMInputError("damping_matrix is not symmetric: viscous damping matrices are symmetric")
        Cm = system.Phi.T @ C @ system.Phi
        Cm = 0.5 * (Cm + Cm.T)
        ev = np.linalg.eigvalsh(Cm)
        if ev[0] < -1e-9 * max(abs(ev[-1]), 1e-300):
            raise NNMInputError(f"damping_matrix is not positive semi-definite (eigenvalue {ev[0]:.3g} in modal "
                                f"coordinates): it would feed energy in")
        Cq = Cq + Cm
        off = Cm - np.diag(np.diag(Cm))
        if np.max(np.abs(off)) <= 1e-10 * max(float(np.max(np.abs(Cm))), 1e-300):
            c = c + np.diag(Cm)
        else:
            c = None
    return zeta, c, Cq
