r"""Geometrically nonlinear structures: linear matrices plus a distributed polynomial strain energy.

``GeometricStructure`` holds, on the free DOFs of a von Karman beam or plate, the mass M (kg), the
linear stiffness K (N/m) and the nonlinear part of the strain energy (``PolynomialEnergy``, one entry
per Gauss point).  Its internal force  f(x) = K x + f_nl(x)  and tangent  K_t(x) = K + d f_nl / dx
are evaluated here directly (numpy); ``model()`` hands the same energy to the solver as one
``nnm.PolynomialStiffness`` per Gauss point, and ``GeometricStructure.from_model`` reads it back from a
model's elements, so a check of the model's force against this module is a check of the elements.
``static_solve`` finds equilibria  f(x) = lam F  by Newton's method with load steps.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from nnm_solver.errors import NNMInputError
from .polynomial import PolynomialEnergy

__all__ = ["GeometricStructure", "StaticSolution", "internal_force", "tangent_stiffness", "static_solve"]


@dataclass
class GeometricStructure:
    """M, K (sparse, free DOFs, SI) and the nonlinear strain energy of a geometrically nonlinear structure.

    labels: one string per DOF ("node k uz"); mesh: a DisplayMesh (or None); name, info: as for nnm.Model;
    unit_loads: named consistent load vectors (n,) of a unit distributed load ("pressure": 1 Pa on a plate,
    "uniform": 1 N/m on a beam) for static solutions.
    """

    M: sp.csr_matrix
    K: sp.csr_matrix
    energy: PolynomialEnergy
    labels: list
    mesh: object = None
    name: str = ""
    info: dict = field(default_factory=dict)
    unit_loads: dict = field(default_factory=dict)

    @property
    def n(self):
        return self.K.shape[0]

    def internal_force(self, x):
        """f(x) = K x + f_nl(x) (n,) in N for displacements x (n,) in m."""
        x = np.asarray(x, dtype=float)
        return self.K @ x + self.energy.force(x)

    def tangent(self, x):
        """K_t(x) = K + d f_nl / dx (sparse CSR, N/m)."""
        return (self.K + self.energy.tangent(x)).tocsr()

    def strain_energy(self, x):
        """Total strain energy (J): x^T K x / 2 + the nonlinear part."""
        x = np.asarray(x, dtype=float)
        return float(0.5 * x @ (self.K @ x) + self.energy.potential(x))

    def dof(self, label):
        """Index of the DOF with this label (e.g. "node 9 uz")."""
        try:
            return self.labels.index(label)
        except ValueError:
            raise NNMInputError(f"no DOF labelled {label!r} (labels look like {self.labels[:3]})") from None

    def springs(self):
        """The nonlinear energy as solver elements: one nnm.PolynomialStiffness per Gauss point."""
        import nnm_solver as nnm
        e = self.energy
        out = []
        for g in range(len(e.weights)):
            used = np.any(e.directions[g] != 0.0, axis=0)
            dofs, cols = np.unique(e.dofs[g][used], return_index=True)
            dirs = np.zeros((e.directions.shape[1], len(dofs)))
            for c, k in zip(np.flatnonzero(used), e.dofs[g][used]):
                dirs[:, np.searchsorted(dofs, k)] += e.directions[g][:, c]
            out.append(nnm.PolynomialStiffness(e.exponents, e.weights[g] * e.coefficients, dofs=dofs,
                                               directions=dirs))
        return out

    def model(self):
        """The structure as an nnm.Model: M, K and one PolynomialStiffness per Gauss point."""
        import nnm_solver as nnm
        return nnm.Model(self.M, self.K, self.springs(), dof_labels=self.labels, mesh=self.mesh, name=self.name,
                         info=self.info)

    @classmethod
    def from_model(cls, model):
        """Rebuild the structure from a model's PolynomialStiffness elements (each on the same variables d)."""
        springs = list(model.springs)
        if not springs or not all(hasattr(s, "exponents") and hasattr(s, "directions") for s in springs):
            raise NNMInputError("from_model needs a model whose elements are all PolynomialStiffness")
        F = np.asarray(springs[0].exponents, dtype=np.int64)
        nd = max(len(np.atleast_1d(s.dofs)) for s in springs)
        m = F.shape[1]
        dofs = np.zeros((len(springs), nd), dtype=np.int64)
        dirs = np.zeros((len(springs), m, nd))
        weights = np.ones(len(springs))
        # energy density of each point: V = sum_i z_i (C_i . d) / (p_i + 1), written on the energy monomials
        E_rows, e_coef = _energy_from_force(F, np.asarray(springs[0].coefficients, dtype=float))
        ref = np.asarray(springs[0].coefficients, dtype=float)
        scale = np.max(np.abs(ref))
        for g, s in enumerate(springs):
            if not np.array_equal(np.asarray(s.exponents), F):
                raise NNMInputError("from_model: the elements' exponents differ; they must share one law")
            C = np.asarray(s.coefficients, dtype=float)
            w = float(np.sum(C * ref) / np.sum(ref * ref))
            if np.max(np.abs(C - w * ref)) > 1e-12 * abs(w) * scale:
                raise NNMInputError("from_model: the elements' coefficients are not multiples of one law")
            k = len(np.atleast_1d(s.dofs))
            dofs[g, :k] = s.dofs
            dirs[g, :, :k] = np.asarray(s.directions, dtype=float).reshape(m, k)
            weights[g] = w
        energy = PolynomialEnergy(model.n, dofs, dirs, weights, E_rows, e_coef)
        return cls(model.M, model.K, energy, list(model.dof_labels or []), model.mesh, model.name, dict(model.info))


def _energy_from_force(F, C):
    """Energy monomials (exponents, coefficients) of V = sum_i z_i (C_i . d) / (p_i + 1)."""
    rows = {}
    for i in range(len(F)):
        p = int(F[i].sum())
        for j in range(F.shape[1]):
            if C[i, j] != 0.0:
                key = tuple(F[i] + np.eye(F.shape[1], dtype=np.int64)[j])
                rows[key] = rows.get(key, 0.0) + C[i, j] / (p + 1)
    keys = sorted(rows)
    return np.array(keys, dtype=np.int64), np.array([rows[k] for k in keys])


def _structure(obj):
    if isinstance(obj, GeometricStructure):
        return obj
    return GeometricStructure.from_model(obj)


def internal_force(structure, x):
    """Internal force K x + f_nl(x) (N) of a GeometricStructure or of an nnm.Model built from one."""
    return _structure(structure).internal_force(x)


def tangent_stiffness(structure, x):
    """Tangent stiffness K + d f_nl / dx (sparse, N/m) of a GeometricStructure or nnm.Model built from one."""
    return _structure(structure).tangent(x)


@dataclass(frozen=True)
class StaticSolution:
    """An equilibrium K x + f_nl(x) = load_factor * F: x (n,) m; converged: the residual norm fell below
    tol * |F| at every load step; iterations: Newton iterations in all; residual: final |r| / |F|."""

    x: np.ndarray
    load_factor: float
    converged: bool
    iterations: int
    residual: float


def static_solve(structure, load, *, steps=10, tol=1e-10, max_iter=30, x0=None):
    """Nonlinear static solution of f(x) = F by Newton's method over ``steps`` equal load increments.

    structure: GeometricStructure or nnm.Model built from one; load: F (n,) in N.  Each increment starts
    from the previous equilibrium (x0 for the first) and iterates x <- x - K_t(x)^-1 (f(x) - lam F) until
    |f(x) - lam F| <= tol |F|.  Returns a StaticSolution (converged False if an increment did not).
    """
    s = _structure(structure)
    F = np.asarray(load, dtype=float)
    if F.shape != (s.n,):
        raise NNMInputError(f"static_solve: load must have shape ({s.n},), got {F.shape}")
    if not np.all(np.isfinite(F)):
        raise NNMInputError("static_solve: load contains NaN or infinite entries")
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 1:
        raise NNMInputError(f"static_solve: steps must be a positive integer, got {steps!r}")
    x = np.zeros(s.n) if x0 is None else np.array(x0, dtype=float)
    fn = max(np.linalg.norm(F), 1e-300)
    total, ok, rel = 0, True, 0.0
    for lam in np.linspace(0.0, 1.0, steps + 1)[1:]:
        for _ in range(max_iter):
            r = s.internal_force(x) - lam * F
            rel = np.linalg.norm(r) / fn
            if rel <= tol:
                break
            x = x - spla.spsolve(s.tangent(x).tocsc(), r)
            total += 1
        else:
            r = s.internal_force(x) - lam * F
            rel = np.linalg.norm(r) / fn
            ok = ok and rel <= tol
    return StaticSolution(x, 1.0, bool(ok), total, float(rel))
