r"""Rectangular von Karman plate with immovable edges: ``von_karman_plate`` (issue 55).

Plate a x b (m) in the x-y plane, thickness h, deflection w along z, in-plane displacements u, v (SI).
Membrane strains  eps_xx = u_x + w_x^2 / 2,  eps_yy = v_y + w_y^2 / 2,  gamma_xy = u_y + v_x + w_x w_y;
strain energy  1/2 int eps^T A eps + 1/2 int kappa^T D kappa,  A = E h / (1 - nu^2) [[1, nu, 0], [nu, 1, 0],
[0, 0, (1 - nu) / 2]],  D = A h^2 / 12,  kappa = (w_xx, w_yy, 2 w_xy); kinetic energy rho h / 2 int (u_t^2 +
v_t^2 + w_t^2) (no rotary inertia).  The nonlinear part of the membrane energy,
eps_lin^T A eps_nl + eps_nl^T A eps_nl / 2, is one ``nnm.PolynomialStiffness`` per Gauss point on
d = (u_x, v_y, u_y + v_x, w_x, w_y).

Elements on a regular nx x ny grid: w by the Bogner-Fox-Schmit bicubic Hermite rectangle (C1; DOFs w,
w_x, w_y, w_xy at the element corners), u and v biquadratic (9-node Lagrange: corners, mid-sides, centre),
so that u_x and v_y can follow w_x^2 / 2 and w_y^2 / 2 in the way the beam's quadratic axial field does
(less membrane locking); 3 x 3 Gauss points for the membrane energy (linear and nonlinear parts, one rule),
4 x 4 for bending and mass (exact).  Node numbers (1-based, in the DOF labels) run over the
(2 nx + 1) x (2 ny + 1) grid of the in-plane nodes, x fastest; w DOFs sit on the nodes with even grid
indices: "node k uz", "node k dw/dx", "node k dw/dy", "node k d2w/dxdy", in-plane "node k ux", "node k uy".
Edges: "clamped" (u = v = w = w_n = 0, hence all four w DOFs) or "hinged" (u = v = w = 0, the tangential
slope and twist at the corners follow).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from nnm_solver.errors import NNMInputError, finite_number
from .polynomial import PolynomialEnergy

__all__ = ["plate_structure", "von_karman_plate", "plate_energy", "DEFAULT_PLATE_ELEMENTS"]

#: default grid of ``von_karman_plate`` (elements along x, along y)
DEFAULT_PLATE_ELEMENTS = (6, 6)


def plate_energy(nu):
    """Nonlinear membrane energy density per unit E h / (1 - nu^2) on d = (u_x, v_y, gamma, w_x, w_y)."""
    E = np.array([[1, 0, 0, 2, 0], [1, 0, 0, 0, 2], [0, 1, 0, 2, 0], [0, 1, 0, 0, 2], [0, 0, 1, 1, 1],
                  [0, 0, 0, 4, 0], [0, 0, 0, 0, 4], [0, 0, 0, 2, 2]])
    c = np.array([0.5, nu / 2, nu / 2, 0.5, (1 - nu) / 2, 0.125, 0.125, 0.25])
    return E, c



def _hermite(xi, h):
    """1D cubic Hermite (w1, w1', w2, w2') values and first, second x-derivatives at xi in [-1, 1]."""
    s = (1 + xi) / 2
    H = np.array([1 - 3 * s ** 2 + 2 * s ** 3, h * (s - 2 * s ** 2 + s ** 3), 3 * s ** 2 - 2 * s ** 3,
                  h * (-s ** 2 + s ** 3)])
    dH = np.array([-6 * s + 6 * s ** 2, h * (1 - 4 * s + 3 * s ** 2), 6 * s - 6 * s ** 2, h * (-2 * s + 3 * s ** 2)]) / h
    d2H = np.array([-6 + 12 * s, h * (-4 + 6 * s), 6 - 12 * s, h * (-2 + 6 * s)]) / h ** 2
    return H, dH, d2H


def _lagrange(xi, h):
    """1D quadratic Lagrange (left, middle, right) values and x-derivatives at xi in [-1, 1]."""
    return np.array([xi * (xi - 1) / 2, 1 - xi ** 2, xi * (xi + 1) / 2]), np.array([xi - 0.5, -2 * xi, xi + 0.5]) * 2 / h


# element w DOFs: corner c = (p, q) in (0,0), (1,0), (0,1), (1,1), component k = w, w_x, w_y, w_xy
_CORNERS = [(0, 0), (1, 0), (0, 1), (1, 1)]
_COMP = [(0, 0), (1, 0), (0, 1), (1, 1)]           # (x slope?, y slope?) of each w component


def _element_rows(xi, eta, hx, hy):
    """At one point: w-rows (value, w_x, w_y, w_xx, w_yy, w_xy) (6, 16) and uv rows (u, v, u_x, v_y, u_y + v_x) (5, 18)."""
    Hx, dHx, d2Hx = _hermite(xi, hx)
    Hy, dHy, d2Hy = _hermite(eta, hy)
    W = np.zeros((6, 16))
    for c, (p, q) in enumerate(_CORNERS):
        for k, (sx, sy) in enumerate(_COMP):
            ix, iy = 2 * p + sx, 2 * q + sy
            col = 4 * c + k
            W[:, col] = [Hx[ix] * Hy[iy], dHx[ix] * Hy[iy], Hx[ix] * dHy[iy], d2Hx[ix] * Hy[iy], Hx[ix] * d2Hy[iy],
                         dHx[ix] * dHy[iy]]
    Lx, dLx = _lagrange(xi, hx)
    Ly, dLy = _lagrange(eta, hy)
    U = np.zeros((5, 18))
    for j in range(3):
        for i in range(3):
            a = 3 * j + i                          # in-plane node (i, j) of the element, x fastest
            U[0, 2 * a] = Lx[i] * Ly[j]
            U[1, 2 * a + 1] = Lx[i] * Ly[j]
            U[2, 2 * a] = dLx[i] * Ly[j]
            U[3, 2 * a + 1] = Lx[i] * dLy[j]
            U[4, 2 * a] = Lx[i] * dLy[j]
            U[4, 2 * a + 1] = dLx[i] * Ly[j]
    return W, U


def _grid_dofs(nx, ny):
    """Global DOF numbers of every element (E, 34): 16 w DOFs then 18 in-plane; and the DOF labels."""
    gx, gy = 2 * nx + 1, 2 * ny + 1
    node = lambda i, j: i + gx * j                                     # fine-grid node index
    wnodes = {(i, j): k for k, (j, i) in enumerate((j, i) for j in range(0, gy, 2) for i in range(0, gx, 2))}
    nw = 4 * len(wnodes)
    labels = [None] * (nw + 2 * gx * gy)
    for (i, j), k in wnodes.items():
        nn = node(i, j) + 1
        labels[4 * k:4 * k + 4] = [f"node {nn} uz", f"node {nn} dw/dx", f"node {nn} dw/dy", f"node {nn} d2w/dxdy"]
    for j in range(gy):
        for i in range(gx):
            labels[nw + 2 * node(i, j)] = f"node {node(i, j) + 1} ux"
            labels[nw + 2 * node(i, j) + 1] = f"node {node(i, j) + 1} uy"
    elems = []
    for ey in range(ny):
        for ex in range(nx):
            d = []
            for p, q in _CORNERS:
                k = wnodes[(2 * (ex + p), 2 * (ey + q))]
                d += [4 * k + c for c in range(4)]
            for j in range(3):
                for i in range(3):
                    a = node(2 * ex + i, 2 * ey + j)
                    d += [nw + 2 * a, nw + 2 * a + 1]
            elems.append(d)
    return np.array(elems), labels, wnodes, nw, (gx, gy)


def _check(a, b, h, E, nu, rho, elements, edges):
    vals = [finite_number(v, n) for v, n in ((a, "a (m)"), (b, "b (m)"), (h, "thickness (m)"), (E, "E (Pa)"),
                                            (nu, "nu"), (rho, "rho (kg/m^3)"))]
    if min(vals[:4] + [vals[5]]) <= 0:
        raise NNMInputError("von_karman_plate: a, b, thickness, E and rho must be positive")
    if not -1 < vals[4] < 0.5:
        raise NNMInputError(f"von_karman_plate: nu must be in (-1, 0.5), got {vals[4]}")
    el = (elements, elements) if np.ndim(elements) == 0 else tuple(elements)
    if len(el) != 2 or any(isinstance(e, bool) or not isinstance(e, (int, np.integer)) or e < 2 for e in el):
        raise NNMInputError(f"von_karman_plate: elements must be an integer >= 2 or a pair of them, got {elements!r}")
    if edges not in ("clamped", "hinged"):
        raise NNMInputError(f"von_karman_plate: edges must be 'clamped' or 'hinged', got {edges!r}")
    return vals, (int(el[0]), int(el[1]))


_EDGE_KINDS = ("clamped", "hinged", "symmetric")


def _fixed_dofs(edges, wnodes, nw, gx, gy):
    """DOFs fixed by the edge conditions (x = 0, x = a, y = 0, y = b), each 'clamped', 'hinged' or 'symmetric'
    (u_n = 0, w_n = 0, twist = 0: a plane of symmetry)."""
    fixed = set()
    for e, kind in enumerate(edges):
        along_x = e >= 2                                   # edges y = 0, y = b run along x
        on = (lambda i, j: i == (0 if e == 0 else gx - 1)) if e < 2 else (lambda i, j: j == (0 if e == 2 else gy - 1))
        normal, tangential = (2, 1) if along_x else (1, 2)  # w DOF offsets of the normal / tangential slope
        for j in range(gy):
            for i in range(gx):
                if not on(i, j):
                    continue
                a = i + gx * j
                if kind == "symmetric":
                    fixed.add(nw + 2 * a + (1 if along_x else 0))
                else:
                    fixed.update((nw + 2 * a, nw + 2 * a + 1))
                k = wnodes.get((i, j))
                if k is None:
                    continue
                comps = {"clamped": (0, 1, 2, 3), "hinged": (0, tangential), "symmetric": (normal, 3)}[kind]
                fixed.update(4 * k + c for c in comps)
    return np.array(sorted(fixed))


def _display(nx, ny, hx, hy, elems, nw, gx, gy, free):
    """Plate surface on the in-plane node grid; w interpolated by the element's Hermite functions."""
    import nnm_solver as nnm
    pos = np.full(elems.max() + 1, -1)
    pos[free] = np.arange(len(free))
    verts = np.array([[i * hx / 2, j * hy / 2, 0.0] for j in range(gy) for i in range(gx)])
    D = sp.lil_matrix((3 * gx * gy, len(free)))
    for j in range(gy):
        for i in range(gx):
            v = i + gx * j
            for c in (0, 1):
                if pos[nw + 2 * v + c] >= 0:
                    D[3 * v + c, pos[nw + 2 * v + c]] = 1.0
            ex, ey = min(i // 2, nx - 1), min(j // 2, ny - 1)
            W, _ = _element_rows(i - 2 * ex - 1.0, j - 2 * ey - 1.0, hx, hy)
            for col, dof in enumerate(elems[ex + nx * ey, :16]):
                if pos[dof] >= 0 and W[0, col] != 0.0:
                    D[3 * v + 2, pos[dof]] += W[0, col]
    quads = np.array([[i + gx * j, i + 1 + gx * j, i + 1 + gx * (j + 1), i + gx * (j + 1)]
                      for j in range(gy - 1) for i in range(gx - 1)])
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return nnm.DisplayMesh(verts, faces, D.tocsr(), part_ids=np.zeros(len(faces)), part_names=["plate"])


def plate_structure(a, b, thickness, E, nu, rho, elements=DEFAULT_PLATE_ELEMENTS, edges="clamped"):
    """The von Karman plate as a GeometricStructure on its free DOFs (see ``von_karman_plate``).

    edges: "clamped", "hinged", or a 4-tuple of 'clamped' | 'hinged' | 'symmetric' for the edges x = 0, x = a,
    y = 0, y = b ('symmetric': a plane of symmetry, u_n = 0, w_n = 0, twist = 0).
    """
    from .geometric import GeometricStructure
    ed = (edges,) * 4 if isinstance(edges, str) else tuple(edges)
    if len(ed) != 4 or any(e not in _EDGE_KINDS for e in ed):
        raise NNMInputError(f"von_karman_plate: edges must be 'clamped', 'hinged' or 4 of {_EDGE_KINDS}, got {edges!r}")
    (a, b, h, E, nu, rho), (nx, ny) = _check(a, b, thickness, E, nu, rho, elements, "clamped")
    hx, hy = a / nx, b / ny
    elems, labels, wnodes, nw, (gx, gy) = _grid_dofs(nx, ny)
    n = len(labels)
    C = E * h / (1 - nu ** 2)
    Am = C * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    Db = Am * h ** 2 / 12
    ke = np.zeros((34, 34))
    me = np.zeros((34, 34))
    pe = np.zeros(34)                                      # consistent load of a unit pressure (1 Pa)
    g4, w4 = np.polynomial.legendre.leggauss(4)
    jac = hx * hy / 4
    for xi, wx in zip(g4, w4):
        for eta, wy in zip(g4, w4):
            W, U = _element_rows(xi, eta, hx, hy)
            kb = np.stack([W[3], W[4], 2 * W[5]])
            ke[:16, :16] += wx * wy * jac * kb.T @ Db @ kb
            me[:16, :16] += wx * wy * jac * rho * h * np.outer(W[0], W[0])
            me[16:, 16:] += wx * wy * jac * rho * h * (np.outer(U[0], U[0]) + np.outer(U[1], U[1]))
            pe[:16] += wx * wy * jac * W[0]
    g3, w3 = np.polynomial.legendre.leggauss(3)
    dirs, wts = [], []
    for xi, wx in zip(g3, w3):
        for eta, wy in zip(g3, w3):
            W, U = _element_rows(xi, eta, hx, hy)
            em = np.zeros((3, 34))
            em[:, 16:] = U[2:5]
            ke += wx * wy * jac * em.T @ Am @ em
            dirs.append(np.vstack([em, np.hstack([W[1:3], np.zeros((2, 18))])]))
            wts.append(wx * wy * jac * C)
    ne = len(elems)
    rows = np.repeat(elems, 34, axis=1).ravel()
    cols = np.tile(elems, (1, 34)).ravel()
    K = sp.csr_matrix((np.tile(ke.ravel(), ne), (rows, cols)), shape=(n, n))
    M = sp.csr_matrix((np.tile(me.ravel(), ne), (rows, cols)), shape=(n, n))
    pressure = np.zeros(n)
    np.add.at(pressure, elems, np.tile(pe, (ne, 1)))
    ng = len(wts)
    energy = PolynomialEnergy(n, np.repeat(elems, ng, axis=0), np.tile(np.stack(dirs), (ne, 1, 1)),
                              np.tile(wts, ne), *plate_energy(nu))
    fixed = _fixed_dofs(ed, wnodes, nw, gx, gy)
    free = np.setdiff1d(np.arange(n), fixed)
    mid = (nx // 2 * 2) + gx * (ny // 2 * 2) + 1
    info = {"builder": "nnm_fem.von_karman_plate", "a_m": a, "b_m": b, "thickness_m": h, "E_Pa": E, "nu": nu,
            "rho_kg_m3": rho, "elements": f"{nx} x {ny}", "edges": ",".join(ed), "centre_dof": f"node {mid} uz"}
    return GeometricStructure(K=K[free][:, free].tocsr(), M=M[free][:, free].tocsr(), energy=energy.restricted(free),
                              labels=[labels[k] for k in free], mesh=_display(nx, ny, hx, hy, elems, nw, gx, gy, free),
                              name=f"von Karman plate ({edges if isinstance(edges, str) else 'mixed'})", info=info,
                              unit_loads={"pressure": pressure[free]})


def von_karman_plate(a, b, thickness, E, nu, rho, elements=DEFAULT_PLATE_ELEMENTS, edges="clamped"):
    """Rectangular von Karman plate with immovable edges as an ``nnm.Model`` (module docstring).

    a, b (m) side lengths along x, y; thickness (m); E (Pa); nu; rho (kg/m^3); elements: nx or (nx, ny);
    edges: "clamped" (default) or "hinged" on all four edges (plate_structure takes one per edge).  The centre
    deflection is ``info["centre_dof"]`` (even element counts put a node there).
    """
    return plate_structure(a, b, thickness, E, nu, rho, elements, edges).model()
