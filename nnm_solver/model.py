"""Conservative structural models  M x'' + K x + f_nl(x) = 0  with cubic springs.

Units are SI throughout: M in kg (or kg m^2 for rotations), K in N/m, k3 in N/m^3,
frequencies in Hz, energies in J.  Mode numbers seen by users are 1-based (as in the
seed paper's Table 2); DOF indices are 0-based array indices.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .errors import NNMInputError

#: Largest model the shooting solver accepts (it works in the full modal basis).
MAX_DENSE_DOF = 6000


@dataclass(frozen=True)
class CubicSpring:
    """Cubic spring with force k3 * d**3 on the deformation d.

    Grounded (``other=None``): d = x[dof].  Relative: d = x[dof] - x[other].
    k3 in N/m^3 (negative: softening).
    """

    dof: int
    k3: float
    other: int | None = None

    def potential(self, d):
        """Potential energy (J) stored at deformation d (m)."""
        return 0.25 * self.k3 * np.asarray(d) ** 4


@dataclass
class DisplayMesh:
    """Triangle surface used to show a model's motion.

    vertices : (V, 3) m; faces : (F, 3) vertex indices; displacement_map : (3V, n) maps the
    model coordinates x to vertex displacements, vertex-major (v0x, v0y, v0z, v1x, ...);
    part_ids : (F,) index into part_names (optional).
    """

    vertices: np.ndarray
    faces: np.ndarray
    displacement_map: np.ndarray
    part_ids: np.ndarray | None = None
    part_names: list[str] = field(default_factory=list)

    def __post_init__(self):
        self.vertices = np.asarray(self.vertices, dtype=float)
        self.faces = np.asarray(self.faces, dtype=np.int64)
        self.displacement_map = np.asarray(self.displacement_map)
        nv = len(self.vertices)
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3:
            raise NNMInputError(f"mesh vertices must have shape (V, 3), got {self.vertices.shape}")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise NNMInputError(f"mesh faces must have shape (F, 3), got {self.faces.shape}")
        if self.faces.size and (self.faces.min() < 0 or self.faces.max() >= nv):
            raise NNMInputError(f"mesh faces refer to vertices outside 0..{nv - 1}")
        if self.displacement_map.ndim != 2 or self.displacement_map.shape[0] != 3 * nv:
            raise NNMInputError(
                f"mesh displacement_map must have 3*V = {3 * nv} rows, got {self.displacement_map.shape}")
        if self.part_ids is not None:
            self.part_ids = np.asarray(self.part_ids, dtype=np.int64)

    def displacements(self, x):
        """Vertex displacements (V, 3) in m for model coordinates x (n,); or (k, V, 3) for x (k, n)."""
        x = np.asarray(x, dtype=float)
        u = x @ self.displacement_map.T
        return u.reshape(x.shape[:-1] + (len(self.vertices), 3))


def _as_matrix(name, A):
    if sp.issparse(A):
        A = A.tocsr().astype(float)
        data = A.data
    else:
        try:
            A = np.asarray(A, dtype=float)
        except (TypeError, ValueError) as exc:
            raise NNMInputError(f"{name} must be a numeric matrix ({exc})") from None
        data = A
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise NNMInputError(f"{name} must be a non-empty square matrix, got shape {A.shape}")
    if not np.all(np.isfinite(data)):
        raise NNMInputError(f"{name} contains NaN or infinite entries; fix the matrix before building the model")
    return A


def _dense(A):
    return A.toarray() if sp.issparse(A) else A


def _check_symmetric(name, A):
    D = _dense(A)
    scale = np.max(np.abs(D)) if D.size else 0.0
    asym = np.max(np.abs(D - D.T)) if D.size else 0.0
    if asym > 1e-8 * max(scale, 1e-300):
        raise NNMInputError(
            f"{name} is not symmetric (max |{name}-{name}^T| = {asym:.3g} vs max |{name}| = {scale:.3g}); "
            f"conservative models need symmetric matrices")


class Model:
    """Conservative model  M x'' + K x + sum_s B_s^T k3_s d_s^3 = 0,  d_s = B_s x.

    Parameters
    ----------
    M, K : (n, n) dense arrays or scipy.sparse matrices (SI units). M symmetric positive
        definite, K symmetric positive semi-definite.
    springs : list of CubicSpring.
    dof_labels : optional list of n strings (e.g. "node 12 uz").
    mode_labels : optional list of strings, label of linear mode k at index k-1.
    mesh : optional DisplayMesh for viewing.
    name : short model name.  info : dict of provenance strings/numbers.
    """

    def __init__(self, M, K, springs=(), *, dof_labels=None, mode_labels=None, mesh=None,
                 name="", info=None):
        self.M = M
        self.K = K
        self.springs = list(springs)
        Md = _as_matrix("M", M)
        Kd = _as_matrix("K", K)
        if Md.shape != Kd.shape:
            raise NNMInputError(f"M has shape {Md.shape} but K has shape {Kd.shape}; they must match")
        self.n = Md.shape[0]
        _check_symmetric("M", Md)
        _check_symmetric("K", Kd)
        self._M = Md
        self._K = Kd
        for i, s in enumerate(self.springs):
            if not isinstance(s, CubicSpring):
                raise NNMInputError(f"spring {i} is {type(s).__name__}, expected nnm_solver.CubicSpring")
            for which, d in (("dof", s.dof), ("other", s.other)):
                if d is None and which == "other":
                    continue
                if not isinstance(d, (int, np.integer)) or not 0 <= d < self.n:
                    raise NNMInputError(
                        f"spring {i}: {which}={d} is not a DOF of this model (valid: 0..{self.n - 1})")
            if s.other is not None and s.other == s.dof:
                raise NNMInputError(f"spring {i}: dof and other are both {s.dof}; a relative spring needs two DOFs")
            if not np.isfinite(s.k3):
                raise NNMInputError(f"spring {i}: k3={s.k3} is not finite")
        if dof_labels is not None and len(dof_labels) != self.n:
            raise NNMInputError(f"dof_labels has {len(dof_labels)} entries, the model has {self.n} DOFs")
        self.dof_labels = None if dof_labels is None else [str(s) for s in dof_labels]
        self.mode_labels = None if mode_labels is None else [str(s) for s in mode_labels]
        if mesh is not None and mesh.displacement_map.shape[1] != self.n:
            raise NNMInputError(
                f"mesh displacement_map has {mesh.displacement_map.shape[1]} columns, the model has {self.n} DOFs")
        self.mesh = mesh
        self.name = str(name)
        self.info = dict(info or {})

    # ------------------------------------------------------------------ springs
    @cached_property
    def spring_matrix(self):
        """B (n_s, n): spring deformations d = B x."""
        B = np.zeros((len(self.springs), self.n))
        for s, spring in enumerate(self.springs):
            B[s, spring.dof] = 1.0
            if spring.other is not None:
                B[s, spring.other] = -1.0
        return B

    @property
    def k3(self):
        """Cubic coefficients (n_s,) in N/m^3."""
        return np.array([s.k3 for s in self.springs], dtype=float)

    def nonlinear_force(self, x):
        """f_nl(x) (n,) in N for displacements x (n,) in m."""
        B = self.spring_matrix
        d = B @ np.asarray(x, dtype=float)
        return B.T @ (self.k3 * d ** 3)

    def with_springs(self, springs):
        """Same linear model and metadata with other springs."""
        return Model(self.M, self.K, springs, dof_labels=self.dof_labels, mode_labels=self.mode_labels,
                     mesh=self.mesh, name=self.name, info=self.info)

    def scaled(self, factor):
        """Same model with every k3 multiplied by ``factor``."""
        return self.with_springs([CubicSpring(dof=s.dof, other=s.other, k3=s.k3 * factor)
                                  for s in self.springs])

    # ------------------------------------------------------------------ energy
    def energy(self, x, v):
        """Total conserved energy (J): kinetic + linear potential + sum k3 d^4/4.

        x, v : (n,) displacement (m) and velocity (m/s); or (k, n) for k states at once.
        """
        x = np.asarray(x, dtype=float)
        v = np.asarray(v, dtype=float)
        if x.shape[-1] != self.n or v.shape != x.shape:
            raise NNMInputError(f"x and v must both have last dimension {self.n}, got {x.shape} and {v.shape}")
        M, K = self._M, self._K
        kin = 0.5 * np.sum(v * (v @ M.T if not sp.issparse(M) else (M @ v.T).T), axis=-1)
        pot = 0.5 * np.sum(x * (x @ K.T if not sp.issparse(K) else (K @ x.T).T), axis=-1)
        d = x @ self.spring_matrix.T
        return kin + pot + np.sum(0.25 * self.k3 * d ** 4, axis=-1)

    # ------------------------------------------------------------------ linear modes
    @cached_property
    def _eig(self):
        if self.n > MAX_DENSE_DOF:
            raise NNMInputError(
                f"the model has {self.n} DOFs; the NNM solver works in the full modal basis and accepts at most "
                f"{MAX_DENSE_DOF}: reduce it first (nnm_solver.craig_bampton)")
        Md, Kd = _dense(self._M), _dense(self._K)
        try:
            lam, Phi = sla.eigh(Kd, Md)
        except np.linalg.LinAlgError:
            raise NNMInputError(
                "M is not positive definite (Cholesky failed); check for massless DOFs or a sign error") from None
        scale = max(np.max(np.abs(lam)), 1e-300)
        if lam[0] < -1e-9 * scale:
            raise NNMInputError(
                f"K is not positive semi-definite (eigenvalue {lam[0]:.3g} of K x = w^2 M x); "
                f"the linear structure is unstable")
        lam = np.maximum(lam, 0.0)
        # fix the sign of each shape: largest-magnitude component positive
        idx = np.argmax(np.abs(Phi), axis=0)
        Phi = Phi * np.sign(Phi[idx, np.arange(self.n)])
        return lam, Phi

    def linear_modes(self):
        """Linear normal modes: (freqs_hz (n,), shapes (n, n)), ascending.

        ``shapes[:, k-1]`` is mode k, mass-normalised (shapes^T M shapes = I).
        """
        lam, Phi = self._eig
        return np.sqrt(lam) / (2 * np.pi), Phi.copy()

    def check_mode(self, mode):
        """Validate a 1-based mode number for continuation; return its 0-based index."""
        if not isinstance(mode, (int, np.integer)) or isinstance(mode, bool):
            raise NNMInputError(f"mode must be an integer (1-based), got {mode!r}")
        if not 1 <= mode <= self.n:
            raise NNMInputError(f"mode {mode} is out of range: this model has modes 1..{self.n}")
        lam, _ = self._eig
        if lam[mode - 1] <= 1e-12 * max(lam[-1], 1e-300):
            raise NNMInputError(
                f"mode {mode} is a rigid-body (zero-frequency) mode and has no periodic NNM; "
                f"pick an elastic mode or ground the structure")
        return mode - 1

    def __repr__(self):
        return f"Model(n={self.n}, springs={len(self.springs)}{', name=' + repr(self.name) if self.name else ''})"
