r"""Distributed polynomial strain energies: one homogeneous-by-term polynomial density per Gauss point.

A geometrically nonlinear FE model (von Karman beam or plate) stores, for every Gauss point g,

* ``dofs[g]`` (nd,) the global DOFs of its element and ``directions[g]`` (m, nd) the rows that give the
  point's strain measures d = directions[g] @ x[dofs[g]] (for the beam d = (u', w'); for the plate
  d = (u_x, v_y, u_y + v_x, w_x, w_y));
* ``weights[g]`` the quadrature weight times the section stiffness (N for the beam, N/m... see the
  builders), and one shared energy polynomial V(d) = sum_k e_k prod_j d_j^{E_kj} (the nonlinear part of
  the strain energy density, degree 3 and 4 terms).

The point's potential is weights[g] V(d), its force along d the gradient g(d) = weights[g] grad V(d).
``force_law`` writes that gradient in NLvib's convention g = C^T z, z_i = prod_j d_j^{F_ij}
(``nnm.PolynomialStiffness(exponents=F, coefficients=C)``), whose potential sum_i z_i (C_i . d) / (p_i + 1)
(p_i the degree of z_i) is V again because every term of V is homogeneous (Euler's theorem).

``PolynomialEnergy`` evaluates the model's nonlinear force, tangent and potential directly (numpy,
vectorised over the Gauss points) for static solutions and for the finite-difference checks; it is the
reference the solver's element is tested against.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["PolynomialEnergy", "force_law"]


def force_law(energy_exponents, energy_coefficients):
    """Gradient of V(d) = sum_k e_k prod_j d_j^{E_kj} as (F (n_z, m) int, C (n_z, m)): grad V = C^T z(d)."""
    E = np.asarray(energy_exponents, dtype=np.int64)
    e = np.asarray(energy_coefficients, dtype=float)
    rows = {}
    for k in range(len(E)):
        for j in range(E.shape[1]):
            if E[k, j] == 0 or e[k] == 0.0:
                continue
            key = tuple(E[k] - np.eye(E.shape[1], dtype=np.int64)[j])
            rows.setdefault(key, np.zeros(E.shape[1]))[j] += e[k] * E[k, j]
    keys = sorted(rows, key=lambda t: (sum(t), t[::-1]))
    return np.array(keys, dtype=np.int64), np.array([rows[k] for k in keys])


def _monomials(d, F):
    """z (G, n_z) = prod_j d_j^F_ij and dz (G, n_z, m) = d z_i / d d_j for d (G, m)."""
    G, m = d.shape
    pw = d[:, None, :] ** F[None]                                        # (G, n_z, m)
    z = np.prod(pw, axis=2)
    dz = np.empty((G, len(F), m))
    for j in range(m):
        others = np.prod(np.delete(pw, j, axis=2), axis=2)
        dj = np.where(F[:, j] > 0, F[:, j] * d[:, None, j] ** np.maximum(F[:, j] - 1, 0), 0.0)
        dz[:, :, j] = others * dj
    return z, dz


@dataclass
class PolynomialEnergy:
    """The nonlinear strain energy of a model: sum_g weights[g] V(directions[g] @ x[dofs[g]]).

    dofs (G, nd) int; directions (G, m, nd); weights (G,); energy_exponents (K, m), energy_coefficients (K,)
    (the density V, SI units: weights x V is in J); n the number of model DOFs.
    """

    n: int
    dofs: np.ndarray
    directions: np.ndarray
    weights: np.ndarray
    energy_exponents: np.ndarray
    energy_coefficients: np.ndarray

    def __post_init__(self):
        self.dofs = np.asarray(self.dofs, dtype=np.int64)
        self.directions = np.asarray(self.directions, dtype=float)
        self.weights = np.asarray(self.weights, dtype=float)
        self.energy_exponents = np.asarray(self.energy_exponents, dtype=np.int64)
        self.energy_coefficients = np.asarray(self.energy_coefficients, dtype=float)
        self.exponents, self.coefficients = force_law(self.energy_exponents, self.energy_coefficients)

    def strains(self, x):
        """d (G, m) at every Gauss point for displacements x (n,)."""
        return np.einsum("gmk,gk->gm", self.directions, np.asarray(x, dtype=float)[self.dofs])

    def potential(self, x):
        """Nonlinear part of the strain energy (J) at x (n,)."""
        d = self.strains(x)
        z = np.prod(d[:, None, :] ** self.energy_exponents[None], axis=2)
        return float(self.weights @ (z @ self.energy_coefficients))

    def force(self, x):
        """Nonlinear internal force f_nl(x) (n,) = dV/dx (N)."""
        d = self.strains(x)
        z, _ = _monomials(d, self.exponents)
        g = self.weights[:, None] * (z @ self.coefficients)             # (G, m)
        f = np.zeros(self.n)
        np.add.at(f, self.dofs, np.einsum("gmk,gm->gk", self.directions, g))
        return f

    def tangent(self, x):
        """Tangent stiffness of the nonlinear part d f_nl / dx (sparse CSR, n x n, N/m)."""
        d = self.strains(x)
        _, dz = _monomials(d, self.exponents)
        H = self.weights[:, None, None] * np.einsum("gij,il->glj", dz, self.coefficients)   # dg_l/dd_j
        ke = np.einsum("glk,glj,gjq->gkq", self.directions, H, self.directions)
        nd = self.dofs.shape[1]
        rows = np.repeat(self.dofs, nd, axis=1).ravel()
        cols = np.tile(self.dofs, (1, nd)).ravel()
        return sp.csr_matrix((ke.ravel(), (rows, cols)), shape=(self.n, self.n))

    def restricted(self, keep):
        """The same energy on the DOFs ``keep`` (the others fixed at zero): columns of removed DOFs dropped."""
        keep = np.asarray(keep, dtype=np.int64)
        new = np.full(self.n, -1, dtype=np.int64)
        new[keep] = np.arange(len(keep))
        idx = new[self.dofs]
        dirs = np.where(idx[:, None, :] >= 0, self.directions, 0.0)
        return PolynomialEnergy(len(keep), np.where(idx >= 0, idx, 0), dirs, self.weights,
                                self.energy_exponents, self.energy_coefficients)
