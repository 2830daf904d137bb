"""One converged periodic orbit of a branch (a row of a Branch), and the modal state it is rebuilt from.

A point of a large model is computed in modal coordinates (q, m of them); its physical state x = Phi q (n DOFs) costs
O(n m) a vector, more than the rest of the point's bookkeeping for condensed harmonic balance.  A Point made with a
``ModalState`` computes its physical x0, v0 and coefficients when one of them is first read (or set), and
``resolve_points`` does it for many points at once (one matrix product: what Branch.from_points calls), so that
a branch's points cost O(N_b n_s m) each while they are computed (issue 52).  The numbers are those of the eager
product to round-off (a matrix product instead of a matrix-vector one).
"""
from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from ..threads import blas_limited

__all__ = ["Point", "ModalState", "resolve_points", "map_modal", "PhysicalColumns"]


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

    def split(self, rows):
        """(x0, v0, coefficients or None) of mapped rows (rows() times phi^T)."""
        n_b = 0 if self.coefficients is None else len(self.coefficients)
        return rows[0], rows[1], (rows[2:2 + n_b] if n_b else None)


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
        d = self.__dict__
        d["_x0"], d["_v0"], d["_coefficients"] = modal.split(rows)
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


def map_modal(states):
    """The physical rows (2 + N_b, n) of each ModalState of ``states`` (its rows() times phi^T: x0, v0 and the
    coefficients), those of one modal system in one matrix product (rows (N (2 + N_b), m) times phi^T)."""
    out = [None] * len(states)
    groups = {}
    for i, modal in enumerate(states):
        groups.setdefault(id(modal.phi), []).append(i)
    for idx in groups.values():
        rows = [states[i].rows() for i in idx]
        with blas_limited():                 # in any thread: a region, so no BLAS limit changes during the product
            x = np.concatenate(rows) @ states[idx[0]].phi.T
        start = 0
        for i, r in zip(idx, rows):
            out[i] = x[start:start + len(r)]
            start += len(r)
    return out


def resolve_points(points):
    """Compute the physical state of the points that still hold a ModalState (map_modal: one product per modal
    system).  Safe when two threads resolve the same point (each maps the state it read; the numbers are the same)."""
    pending = [(p, modal) for p, modal in ((p, p.__dict__.get("modal")) for p in points) if modal is not None]
    for (p, modal), rows in zip(pending, map_modal([modal for _, modal in pending])):
        p._set_physical(modal, rows)
    return points


class PhysicalColumns:
    """A branch's physical columns: x0, v0 (N, n) (m, m/s) and coefficients (N, N_b, n) (m) or None.  Rows given as
    arrays, then the rows of points appended to the branch (``appended``): a point still holding its modal state is
    kept with that state, and both are mapped (map_modal: one product for all of them) when a column is first read.
    A branch's points then cost no O(n m) work each unless their physical states are read (a condensed-HB branch of
    the aircraft: 2.2 ms of the 41 ms its 34 points cost, issue 52).  The numbers are those of mapping the points as
    they are appended.  Thread-safe."""

    def __init__(self, n, x0, v0, coefficients=None, batches=()):
        """batches : rows appended after those of x0, v0 and coefficients (``appended``'s)."""
        x0 = np.asarray(x0, dtype=float).reshape(-1, n)
        self.n = n
        self._arrays = (x0, np.asarray(v0, dtype=float).reshape(len(x0), n),
                        None if coefficients is None else np.asarray(coefficients, dtype=float).reshape(len(x0), -1, n))
        self._batches = list(batches)   # per appended list of points: its rows, each (point, its ModalState) or (x0,
                                        # v0, coefficients)
        self._lock = threading.Lock()

    def appended(self, points):
        """These columns with the rows of ``points`` (a non-empty list of Points) after them, their modal states not
        yet mapped."""
        batch = []
        for p in points:
            modal = p.__dict__.get("modal")
            batch.append((p, modal) if modal is not None else
                         (np.array(p.x0, dtype=float), np.array(p.v0, dtype=float),
                          None if p.coefficients is None else np.array(p.coefficients, dtype=float)))
        with self._lock:
            arrays, batches = self._arrays, self._batches + [batch]
        return PhysicalColumns(self.n, *arrays, batches=batches)

    def arrays(self):
        """(x0, v0, coefficients or None), every row mapped to physical coordinates."""
        with self._lock:
            if self._batches:
                self._arrays = self._mapped()
                self._batches = []
            return self._arrays

    def _mapped(self):
        n = self.n
        x0, v0, coeffs = self._arrays
        held = [r for batch in self._batches for r in batch if isinstance(r[1], ModalState)]
        mapped = dict(zip((id(modal) for _, modal in held), map_modal([modal for _, modal in held])))
        for batch in self._batches:
            rows = []
            for r in batch:
                if isinstance(r[1], ModalState):
                    (p, modal), m = r, mapped[id(r[1])]
                    if p.__dict__.get("modal") is modal:        # the point itself, still unmapped: mapped once
                        p._set_physical(modal, m)
                    r = modal.split(m)
                rows.append(r)
            x0 = np.vstack([x0, np.array([r[0] for r in rows]).reshape(len(rows), n)])
            v0 = np.vstack([v0, np.array([r[1] for r in rows]).reshape(len(rows), n)])
            if rows[0][2] is not None and (coeffs is not None or len(x0) == len(rows)):
                shape = rows[0][2].shape
                coeffs = np.concatenate([np.zeros((0,) + shape) if coeffs is None else coeffs,
                                         np.array([r[2] for r in rows], dtype=float).reshape((len(rows),) + shape)])
            else:
                coeffs = None
        return x0, v0, None if coeffs is None else coeffs.reshape(len(x0), -1, n)

    def __len__(self):
        with self._lock:
            return len(self._arrays[0]) + sum(len(b) for b in self._batches)

    def __getstate__(self):                  # pickled mapped (the modal systems' shapes are not the branch's)
        return dict(n=self.n, arrays=self.arrays())

    def __setstate__(self, state):
        self.n, self._arrays, self._batches = state["n"], state["arrays"], []
        self._lock = threading.Lock()
