"""One converged periodic orbit of a branch (a row of a Branch), and the modal state it is rebuilt from.

A point of a large model is computed in modal coordinates (q, m of them); its physical state x = Phi q (n DOFs) costs
O(n m) a vector, more than the rest of the point's bookkeeping for condensed harmonic balance.  A Point made with a
``ModalState`` computes its physical x0, v0 and coefficients when one of them is first read (or set), and
``resolve_points`` does it for many points at once (one matrix product: what Branch.from_points calls), so that
a branch's points cost O(N_b n_s m) each while they are computed (issue 52).  The numbers are those of the eager
product to round-off (a matrix product instead of a matrix-vector one).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..threads import blas_limited

__all__ = ["Point", "ModalState", "resolve_points"]


@dataclass(frozen=True)
class ModalState:
    """The modal state of a point: phi (n, m) the shapes of its modal system (x = phi q; shared, not copied), q0,
    v0 (m,) its initial state (sqrt(kg) m, sqrt(kg) m/s), coefficients (N_b, m) its modal Fourier coefficients
    (harmonic balance) or None."""

    phi: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    coefficients: np.ndarray | None = None

    def rows(self):
        """The modal vectors to map (2 + N_b, m): q0, v0 and the coefficients' rows."""
        parts = [self.q0[None], self.v0[None]] + ([] if self.coefficients is None else [self.coefficients])
        return np.concatenate(parts)


@dataclass
class Point:
    """One converged periodic orbit of a branch (a row of a Branch).

    energy J; frequency_hz Hz; period s; x0, v0 (n,) initial state (m, m/s, t = 0 at the phase
    condition); floquet (2n,) complex multipliers, largest modulus first (NaN if not computed);
    stable bool; iterations: corrector iterations; coefficients: (N_b, n) Fourier coefficients (m)
    for harmonic-balance points, else None; label: "backbone" or "tongue k:1" (tongue_skip.py);
    freq_error: estimated relative error of frequency_hz from the discretisation (NaN: not estimated;
    shooting: the time step, ShootingProblem.frequency_error; harmonic balance: the truncation of the harmonics,
    orbits/hb_error.py); steps: time steps per period this point was computed with
    (0: the branch settings' steps_per_period); fundamental_share: the fraction of the orbit's modal
    amplitude in its fundamental harmonic (1: a single harmonic; NaN: not measured).  ``point["energy"]``
    works too (first-release rows).  modal: the ModalState that x0, v0 and coefficients are computed from when
    first read (then None), or None (module docstring).
    """

    energy: float
    frequency_hz: float
    period: float
    x0: np.ndarray | None
    v0: np.ndarray | None
    floquet: np.ndarray
    stable: bool
    iterations: int = 0
    coefficients: np.ndarray | None = field(default=None, repr=False)
    label: str = "backbone"
    freq_error: float = float("nan")
    steps: int = 0
    fundamental_share: float = float("nan")
    modal: ModalState | None = field(default=None, repr=False, compare=False)

    def __getitem__(self, key):
        try:
            return getattr(self, key)
        except AttributeError:
            raise KeyError(key) from None

    def __getstate__(self):                  # pickled with its physical state, not the modal system's shapes
        resolve_points([self])
        return dict(self.__dict__)

    def resolve(self):
        """Compute x0, v0 and coefficients from the modal state (if not done yet)."""
        resolve_points([self])
        return self

    def _set_physical(self, modal, rows):
        """Store x0, v0 and coefficients mapped from ``modal`` (rows: its rows() times phi^T)."""
        n_b = 0 if modal.coefficients is None else len(modal.coefficients)
        d = self.__dict__
        d["_x0"], d["_v0"] = rows[0], rows[1]
        d["_coefficients"] = rows[2:2 + n_b] if n_b else None
        self.modal = None


def _physical(name):
    key = "_" + name

    def get(self):
        if self.__dict__.get("modal") is not None:
            resolve_points([self])
        return self.__dict__.get(key)

    def put(self, value):
        if self.__dict__.get("modal") is not None:      # the other two from the modal state first
            resolve_points([self])
        self.__dict__[key] = value

    return property(get, put, doc=f"{name} of the point (physical; computed from its modal state when first read)")


for _name in ("x0", "v0", "coefficients"):
    setattr(Point, _name, _physical(_name))


def resolve_points(points):
    """Compute the physical state of the points that still hold a ModalState, those of one modal system in one
    matrix product (rows (N (2 + N_b), m) times phi^T).  Safe when two threads resolve the same point (each maps
    the state it read; the numbers are the same)."""
    groups = {}
    for p in points:
        modal = p.__dict__.get("modal")
        if modal is not None:
            groups.setdefault(id(modal.phi), []).append((p, modal))
    for pending in groups.values():
        rows = [modal.rows() for _, modal in pending]
        stacked = np.concatenate(rows)
        with blas_limited():                 # in any thread: a region, so no BLAS limit changes during the product
            x = stacked @ pending[0][1].phi.T
        start = 0
        for (p, modal), r in zip(pending, rows):
            p._set_physical(modal, x[start:start + len(r)])
            start += len(r)
    return points
