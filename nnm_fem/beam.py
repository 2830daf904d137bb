"""3D two-node Timoshenko beam (6 DOF/node: ux, uy, uz, rx, ry, rz), vectorised.

SI units: E, G in Pa, A in m^2, Iy, Iz, J in m^4, rho in kg/m^3, lengths in m.
Local axes: e1 along the beam (node 1 -> node 2); e2 in the plane of e1 and the
orientation vector v; e3 = e1 x e2.  Iy is about e2 (bending in the e1-e3 plane),
Iz about e3 (bending in the e1-e2 plane).
"""
from __future__ import annotations

import numpy as np

from nnm_solver.errors import NNMInputError


def beam_frames(x1, x2, orient):
    """Rotation matrices (E, 3, 3) whose rows are the local axes e1, e2, e3; lengths (E,)."""
    d = x2 - x1
    L = np.linalg.norm(d, axis=1)
    if np.any(L <= 0):
        raise NNMInputError("beam with zero length: its two nodes coincide; move one node or drop the beam")
    e1 = d / L[:, None]
    v = np.broadcast_to(np.asarray(orient, dtype=float), e1.shape).copy()
    e3 = np.cross(e1, v)
    n3 = np.linalg.norm(e3, axis=1)
    bad = n3 < 1e-6 * np.linalg.norm(v, axis=1).clip(1e-300)
    if np.any(bad):  # orientation parallel to the axis: pick another one
        alt = np.where(np.abs(e1[bad, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        e3[bad] = np.cross(e1[bad], alt)
        n3 = np.linalg.norm(e3, axis=1)
    e3 /= n3[:, None]
    e2 = np.cross(e3, e1)
    return np.stack([e1, e2, e3], axis=1), L


def _transform(k_local, lam):
    """T^T k T for T = blockdiag(lam x4)."""
    E = len(lam)
    T = np.zeros((E, 12, 12))
    for b in range(4):
        T[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = lam
    return np.einsum("eji,ejk,ekl->eil", T, k_local, T)


def beam_matrices(x1, x2, orient, E, G, A, Iy, Iz, J, rho, shear_factor=5.0 / 6.0, lumped=False):
    """Global stiffness and mass matrices (E, 12, 12) of Timoshenko beams.

    Arrays broadcast over the E beams.  ``shear_factor`` = 0 gives Euler-Bernoulli
    beams (no shear deformation); a pair (k2, k3) sets the shear factors along e2 and e3.  Mass: consistent (Euler-Bernoulli shape functions)
    or lumped (half the mass and polar inertia at each node).
    """
    x1 = np.atleast_2d(np.asarray(x1, float))
    x2 = np.atleast_2d(np.asarray(x2, float))
    lam, L = beam_frames(x1, x2, orient)
    ne = len(L)
    E, G, A, Iy, Iz, J, rho = (np.broadcast_to(np.asarray(a, float), (ne,)) for a in (E, G, A, Iy, Iz, J, rho))
    if np.any(E <= 0) or np.any(A <= 0) or np.any(Iy <= 0) or np.any(Iz <= 0) or np.any(J <= 0):
        raise NNMInputError("beam E, A, Iy, Iz and J must be positive")
    k2, k3 = (shear_factor, shear_factor) if np.ndim(shear_factor) == 0 else shear_factor
    phi_y = 12 * E * Iz / (k2 * G * A * L ** 2) if k2 > 0 else np.zeros(ne)  # shear along e2
    phi_z = 12 * E * Iy / (k3 * G * A * L ** 2) if k3 > 0 else np.zeros(ne)  # shear along e3
    k = np.zeros((ne, 12, 12))
    ka = E * A / L
    kt = G * J / L
    for (i, j, s) in ((0, 0, 1), (0, 6, -1), (6, 6, 1)):
        k[:, i, j] = k[:, j, i] = s * ka
        k[:, i + 3, j + 3] = k[:, j + 3, i + 3] = s * kt
    # bending in e1-e2: dofs v1=1, rz1=5, v2=7, rz2=11
    a = E * Iz / (L ** 3 * (1 + phi_y))
    kb = np.array([[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]], float)
    Lp = np.array([0, 1, 0, 1])
    idx = [1, 5, 7, 11]
    for r in range(4):
        for c in range(4):
            val = kb[r, c] * L ** (Lp[r] + Lp[c])
            if Lp[r] and Lp[c]:
                val = val + (phi_y if r == c else -phi_y) * L ** 2
            k[:, idx[r], idx[c]] = a * val
    # bending in e1-e3: dofs w1=2, ry1=4, w2=8, ry2=10 (sign of rotation terms flips)
    a = E * Iy / (L ** 3 * (1 + phi_z))
    idx = [2, 4, 8, 10]
    sgn = np.array([1, -1, 1, -1])
    for r in range(4):
        for c in range(4):
            val = kb[r, c] * L ** (Lp[r] + Lp[c])
            if Lp[r] and Lp[c]:
                val = val + (phi_z if r == c else -phi_z) * L ** 2
            k[:, idx[r], idx[c]] = a * val * sgn[r] * sgn[c]
    m = np.zeros((ne, 12, 12))
    mt = rho * A * L
    mr = rho * (Iy + Iz) * L
    if lumped:
        for i in (0, 1, 2, 6, 7, 8):
            m[:, i, i] = mt / 2
        for i in (3, 9):
            m[:, i, i] = mr / 2
        for i in (4, 5, 10, 11):
            m[:, i, i] = mt * L ** 2 / 24 + 1e-12
    else:
        for (i, j, s) in ((0, 0, 2), (0, 6, 1), (6, 6, 2)):
            m[:, i, j] = m[:, j, i] = s * mt / 6
            m[:, i + 3, j + 3] = m[:, j + 3, i + 3] = s * mr / 6
        mb = np.array([[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]], float)
        for idx, sg in (([1, 5, 7, 11], np.ones(4)), ([2, 4, 8, 10], sgn)):
            for r in range(4):
                for c in range(4):
                    m[:, idx[r], idx[c]] = mt / 420 * mb[r, c] * L ** (Lp[r] + Lp[c]) * sg[r] * sg[c]
    return _transform(k, lam), _transform(m, lam)
