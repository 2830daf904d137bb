"""Flat 4-node shell (MITC4 plate + bilinear membrane + Hughes-Brezzi drilling), vectorised.

6 DOF/node (ux, uy, uz, rx, ry, rz).  Nodes in order around the quad; the element
normal follows the right-hand rule.  SI units: E in Pa, thicknesses in m, rho in kg/m^3, nsm (non-structural mass)
in kg/m^2.  ``t`` is the membrane thickness, ``tb`` the equivalent bending thickness
(tb > t models stringer- or sandwich-stiffened panels; tb = t for a plain plate).
Warped quads are projected on their mean plane.
"""
from __future__ import annotations

import numpy as np

from nnm_solver.errors import NNMInputError

_G = 1.0 / np.sqrt(3.0)
_GP = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0])


def _dN(xi, eta):
    """Derivatives of the bilinear shape functions: (2, 4) [d/dxi; d/deta]."""
    return 0.25 * np.array([_XI * (1 + _ETA * eta), _ETA * (1 + _XI * xi)])


def _N(xi, eta):
    return 0.25 * (1 + _XI * xi) * (1 + _ETA * eta)


def quad_frames(X):
    """Local frames (E, 3, 3) (rows e1, e2, n), centres (E, 3) and local 2D coords (E, 4, 2)."""
    c = X.mean(axis=1)
    g1 = 0.5 * (X[:, 1] + X[:, 2] - X[:, 0] - X[:, 3])
    n = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    nn = np.linalg.norm(n, axis=1)
    if np.any(nn <= 0):
        raise NNMInputError("degenerate shell element (zero area); check the mesh for collapsed quads")
    n /= nn[:, None]
    e1 = g1 - np.sum(g1 * n, axis=1)[:, None] * n
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(n, e1)
    R = np.stack([e1, e2, n], axis=1)
    xy = np.einsum("eij,enj->eni", R[:, :2], X - c[:, None])
    return R, c, xy


def shell_matrices(X, E, nu, t, tb=None, rho=0.0, nsm=0.0, drill=1e-2, shear_factor=5.0 / 6.0, ex_scale=1.0):
    """Global stiffness and lumped mass matrices (E, 24, 24) of flat quad shells.

    X : (E, 4, 3) node coordinates.  Material arrays broadcast over elements.
    drill : drilling penalty as a fraction of G t.
    ex_scale : membrane stiffness factor along the local x axis (node 1 -> node 2 edge
    direction), a simple orthotropy for skins whose panels carry less direct stress
    one way (the membrane matrix becomes S Dm S, S = diag(sqrt(ex_scale), 1, 1)).
    Mass is lumped: a quarter of (rho t + nsm) * area per node, with rotary inertia
    m_node * (tb^2/12 + area/400) on the three rotations.
    """
    X = np.asarray(X, float)
    if X.ndim != 3 or X.shape[1:] != (4, 3):
        raise NNMInputError(f"shell nodes must have shape (E, 4, 3), got {X.shape}")
    ne = len(X)
    tb = t if tb is None else tb
    E, nu, t, tb, rho, nsm = (np.broadcast_to(np.asarray(a, float), (ne,)) for a in (E, nu, t, tb, rho, nsm))
    G = E / (2 * (1 + nu))
    R, c, xy = quad_frames(X)
    Dm = (E * t / (1 - nu ** 2))[:, None, None] * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 0]], float)
    Dm = Dm + (E * t * nu / (1 - nu ** 2))[:, None, None] * np.array([[0, 1, 0], [1, 0, 0], [0, 0, 0]], float)
    Dm[:, 2, 2] = G * t
    ex = np.broadcast_to(np.asarray(ex_scale, float), (ne,))
    if np.any(ex <= 0):
        raise NNMInputError("ex_scale must be positive")
    Sx = np.ones((ne, 3))
    Sx[:, 0] = np.sqrt(ex)
    Db_iso = Dm.copy()
    Dm = Dm * Sx[:, :, None] * Sx[:, None, :]
    Db = Db_iso * (tb ** 2 / 12 * tb / t)[:, None, None]
    ks = shear_factor * G * tb
    k = np.zeros((ne, 24, 24))
    area = np.zeros(ne)
    # tying points for MITC4 transverse shear: A(0,1), C(0,-1) for g_xi; B(1,0), D(-1,0) for g_eta
    def cov_shear(xi, eta, which):
        dN = _dN(xi, eta)
        N = _N(xi, eta)
        Jrow = np.einsum("n,enk->ek", dN[which], xy)  # (E, 2): dx/dxi_w, dy/dxi_w
        B = np.zeros((ne, 24))
        B[:, 2::6] = dN[which]
        B[:, 3::6] = -Jrow[:, 1:2] * N          # -theta_x * dy/dxi
        B[:, 4::6] = Jrow[:, 0:1] * N           # +theta_y * dx/dxi
        return B
    BA, BC = cov_shear(0.0, 1.0, 0), cov_shear(0.0, -1.0, 0)
    BB, BD = cov_shear(1.0, 0.0, 1), cov_shear(-1.0, 0.0, 1)
    for xi, eta in _GP:
        dN = _dN(xi, eta)
        J = np.einsum("an,enb->eab", dN, xy)  # J[a,b] = d x_b / d xi_a
        detJ = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        if np.any(detJ <= 0):
            raise NNMInputError("shell element with non-positive Jacobian: order its nodes counter-clockwise "
                                "and avoid concave quads")
        Ji = np.linalg.inv(J)
        dNx = np.einsum("eab,bn->ean", Ji, dN)  # (E, 2, 4): d/dx, d/dy
        area += detJ
        Bm = np.zeros((ne, 3, 24))
        Bm[:, 0, 0::6] = dNx[:, 0]
        Bm[:, 1, 1::6] = dNx[:, 1]
        Bm[:, 2, 0::6] = dNx[:, 1]
        Bm[:, 2, 1::6] = dNx[:, 0]
        Bb = np.zeros((ne, 3, 24))
        Bb[:, 0, 4::6] = dNx[:, 0]
        Bb[:, 1, 3::6] = -dNx[:, 1]
        Bb[:, 2, 4::6] = dNx[:, 1]
        Bb[:, 2, 3::6] = -dNx[:, 0]
        gxi = 0.5 * (1 + eta) * BA + 0.5 * (1 - eta) * BC
        geta = 0.5 * (1 + xi) * BB + 0.5 * (1 - xi) * BD
        Bs = np.einsum("eab,bek->eak", Ji, np.stack([gxi, geta]))
        k += detJ[:, None, None] * (np.einsum("eak,eab,ebl->ekl", Bm, Dm, Bm)
                                    + np.einsum("eak,eab,ebl->ekl", Bb, Db, Bb)
                                    + ks[:, None, None] * np.einsum("eak,eal->ekl", Bs, Bs))
    # drilling: gamma * area * (theta_z(centre) - omega(centre))^2, plus a weak nodal stabilisation
    dN = _dN(0.0, 0.0)
    J = np.einsum("an,enb->eab", dN, xy)
    dNx = np.einsum("eab,bn->ean", np.linalg.inv(J), dN)
    bd = np.zeros((ne, 24))
    bd[:, 5::6] = 0.25
    bd[:, 1::6] -= 0.5 * dNx[:, 0]
    bd[:, 0::6] += 0.5 * dNx[:, 1]
    gam = drill * G * t * area
    k += gam[:, None, None] * np.einsum("ek,el->ekl", bd, bd)
    P = np.eye(4) - 0.25
    for a in range(4):
        for b in range(4):
            k[:, 6 * a + 5, 6 * b + 5] += 1e-3 * gam * P[a, b]
    # local -> global
    T = np.zeros((ne, 24, 24))
    for b in range(8):
        T[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = R
    kg = np.einsum("eji,ejk,ekl->eil", T, k, T)
    mn = (rho * t + nsm) * area / 4
    jr = mn * (tb ** 2 / 12 + area / 400)
    m = np.zeros((ne, 24, 24))
    for a in range(4):
        for d in range(3):
            m[:, 6 * a + d, 6 * a + d] = mn
            m[:, 6 * a + 3 + d, 6 * a + 3 + d] = jr
    return kg, m, area
