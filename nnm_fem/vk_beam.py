r"""Plane von Karman beam with immovable ends: the contract ``von_karman_beam`` (issue 55).

Kinematics (beam along x, deflection w along z, SI units): membrane strain eps = u' + w'^2 / 2, strain
energy  U = EA/2 int eps^2 dx + EI/2 int w''^2 dx,  kinetic energy  rho A/2 int (u_t^2 + w_t^2) dx
(Euler-Bernoulli: no rotary inertia, no shear).  U splits into the quadratic part (the matrix K) and
the nonlinear part  EA/2 int (u' w'^2 + w'^4 / 4) dx,  which the model carries as one
``nnm.PolynomialStiffness`` per Gauss point on d = (u', w') at that point.

Elements: w cubic Hermite (DOFs w and ry = -w' at the end nodes), u quadratic Lagrange (DOFs ux at the
end nodes and at the element midpoint).  With linear u the membrane strain u' (constant) cannot follow
w'^2 / 2 (quadratic) and the element is too stiff in stretching (membrane locking, relative error
~1.6 / N^2 in the cubic stiffness of the first mode for N elements); with quadratic u and two Gauss
points per element u' can cancel the fluctuation of w'^2 / 2 at both points, so the axial force is
uniform at the points, as in the continuum ("field consistent"), and the membrane energy converges
like N^-4 (docs/geometric.md has the measured table).  The two-point rule integrates K exactly
(u'^2 and w''^2 are quadratic); M is integrated exactly (four points).

Nodes: 2N + 1 stations x_k = k L / (2N) (1-based node numbers k + 1 in the DOF labels): odd node
numbers are element ends (ux, uz, ry), even ones element midpoints (ux only).  Ends: "hinged"
(ux = uz = 0) or "clamped" (ux = uz = ry = 0) at both ends; the axial DOF fixed at both ends is what
makes the beam stretch (immovable ends).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from nnm_solver.errors import NNMInputError, finite_number
from .polynomial import PolynomialEnergy

__all__ = ["BeamMesh", "beam_mesh", "BEAM_ENERGY", "DEFAULT_BEAM_ELEMENTS"]

#: default element count of ``von_karman_beam`` (measured: docs/geometric.md, tests/test_geometric_beam.py)
DEFAULT_BEAM_ELEMENTS = 16

#: nonlinear membrane energy density per unit EA and length on d = (u', w'):  u' w'^2 / 2 + w'^4 / 8
BEAM_ENERGY = (np.array([[1, 2], [0, 4]]), np.array([0.5, 0.125]))

_G2 = np.array([-1.0, 1.0]) / np.sqrt(3.0)           # two-point Gauss on [-1, 1], weights 1
_G4, _W4 = np.polynomial.legendre.leggauss(4)


def _shapes(xi, h):
    """At xi in [-1, 1] of an element of length h: Hermite (w1, ry1, w2, ry2) values, d/dx, d2/dx2 and the
    quadratic Lagrange (u1, um, u2) values and d/dx.  ry = -w' (rotation about y of the x-z plane)."""
    s = (1 + xi) / 2                                      # in [0, 1]
    H = np.array([1 - 3 * s ** 2 + 2 * s ** 3, -h * (s - 2 * s ** 2 + s ** 3), 3 * s ** 2 - 2 * s ** 3,
                  -h * (-s ** 2 + s ** 3)])
    dH = np.array([-6 * s + 6 * s ** 2, -h * (1 - 4 * s + 3 * s ** 2), 6 * s - 6 * s ** 2,
                   -h * (-2 * s + 3 * s ** 2)]) / h
    d2H = np.array([-6 + 12 * s, -h * (-4 + 6 * s), 6 - 12 * s, -h * (-2 + 6 * s)]) / h ** 2
    Q = np.array([xi * (xi - 1) / 2, 1 - xi ** 2, xi * (xi + 1) / 2])
    dQ = np.array([xi - 0.5, -2 * xi, xi + 0.5]) * 2 / h
    return H, dH, d2H, Q, dQ


# element DOF order: (u1, w1, ry1, um, u2, w2, ry2)
_W_IDX = [1, 2, 5, 6]
_U_IDX = [0, 3, 4]


@dataclass
class BeamMesh:
    """A discretised plane von Karman beam before boundary conditions (all 3 (N+1) + N DOFs).

    x (2N+1,) node stations (m); labels (n,) DOF labels "node k ux|uz|ry"; elem_dofs (N, 7) global DOFs of
    each element (u1, w1, ry1, um, u2, w2, ry2); K, M sparse (n, n) (N/m, kg); energy the nonlinear
    membrane energy (PolynomialEnergy on d = (u', w'), one entry per Gauss point); fixed the DOFs the ends
    fix; n_elements, length, EA, EI, rhoA.
    """

    x: np.ndarray
    labels: list
    elem_dofs: np.ndarray
    K: sp.csr_matrix
    M: sp.csr_matrix
    energy: PolynomialEnergy
    fixed: np.ndarray
    n_elements: int
    length: float
    EA: float
    EI: float
    rhoA: float

    def free(self):
        """Indices of the DOFs left after the end conditions."""
        return np.setdiff1d(np.arange(len(self.labels)), self.fixed)

    def load_vector(self, q):
        """Consistent nodal loads (n,) of a distributed transverse load q(x) (N/m, vectorised callable)."""
        f = np.zeros(len(self.labels))
        h = self.length / self.n_elements
        g, wg = np.polynomial.legendre.leggauss(8)
        for xi, wi in zip(g, wg):
            H = _shapes(xi, h)[0]
            xe = (np.arange(self.n_elements) + (1 + xi) / 2) * h
            np.add.at(f, self.elem_dofs[:, _W_IDX], (wi * h / 2 * q(xe))[:, None] * H[None])
        return f


def _node_dofs(N):
    """Global DOF numbers: element-end node i (0..N): ux, uz, ry; midpoint node of element e: ux."""
    end = np.arange(N + 1)
    base = 4 * end                       # node stations 2i: DOFs 4i, 4i+1, 4i+2; midpoint 2i+1: DOF 4i+3
    elem = np.stack([base[:-1], base[:-1] + 1, base[:-1] + 2, base[:-1] + 3, base[1:], base[1:] + 1,
                     base[1:] + 2], axis=1)
    labels = []
    for i in range(N + 1):
        k = 2 * i + 1                    # 1-based node number
        labels += [f"node {k} ux", f"node {k} uz", f"node {k} ry"]
        if i < N:
            labels.append(f"node {k + 1} ux")
    return elem, labels


def beam_mesh(length, thickness, width, E, rho, elements, ends):
    """The beam's matrices and Gauss-point data (see module docstring); checks the input (NNMInputError)."""
    L, h, b, E, rho = (finite_number(v, name) for v, name in ((length, "length (m)"), (thickness, "thickness (m)"),
                                                              (width, "width (m)"), (E, "E (Pa)"),
                                                              (rho, "rho (kg/m^3)")))
    for v, name in ((L, "length"), (h, "thickness"), (b, "width"), (E, "E"), (rho, "rho")):
        if v <= 0:
            raise NNMInputError(f"von_karman_beam: {name} must be positive, got {v}")
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)) or elements < 2:
        raise NNMInputError(f"von_karman_beam: elements must be an integer >= 2, got {elements!r}")
    if ends not in ("hinged", "clamped"):
        raise NNMInputError(f"von_karman_beam: ends must be 'hinged' or 'clamped', got {ends!r}")
    N = int(elements)
    A, I = b * h, b * h ** 3 / 12
    EA, EI, rhoA = E * A, E * I, rho * A
    he = L / N
    elem, labels = _node_dofs(N)
    n = len(labels)
    ke = np.zeros((7, 7))
    dirs = []
    for xi in _G2:                                         # weights 1, Jacobian h/2
        H, dH, d2H, Q, dQ = _shapes(xi, he)
        bu = np.zeros(7)
        bu[_U_IDX] = dQ
        bw = np.zeros(7)
        bw[_W_IDX] = dH
        bk = np.zeros(7)
        bk[_W_IDX] = d2H
        ke += he / 2 * (EA * np.outer(bu, bu) + EI * np.outer(bk, bk))
        dirs.append(np.stack([bu, bw]))
    me = np.zeros((7, 7))
    for xi, wi in zip(_G4, _W4):
        H, _, _, Q, _ = _shapes(xi, he)
        nu = np.zeros(7)
        nu[_U_IDX] = Q
        nw = np.zeros(7)
        nw[_W_IDX] = H
        me += wi * he / 2 * rhoA * (np.outer(nu, nu) + np.outer(nw, nw))
    rows = np.repeat(elem, 7, axis=1).ravel()
    cols = np.tile(elem, (1, 7)).ravel()
    K = sp.csr_matrix((np.tile(ke.ravel(), N), (rows, cols)), shape=(n, n))
    M = sp.csr_matrix((np.tile(me.ravel(), N), (rows, cols)), shape=(n, n))
    gp_dofs = np.repeat(elem, 2, axis=0)                   # Gauss points element-major
    gp_dirs = np.tile(np.stack(dirs), (N, 1, 1))
    energy = PolynomialEnergy(n, gp_dofs, gp_dirs, np.full(2 * N, EA * he / 2), *BEAM_ENERGY)
    last = 4 * N
    fixed = [0, 1, last, last + 1] + ([2, last + 2] if ends == "clamped" else [])
    x = np.linspace(0.0, L, 2 * N + 1)
    return BeamMesh(x, labels, elem, K, M, energy, np.array(sorted(fixed)), N, L, EA, EI, rhoA)


def _ribbon(bm, free, width):
    """Display ribbon of the beam (2 vertices per station, y = -+width/2) and its map to the free DOFs."""
    import nnm_solver as nnm
    N, h = bm.n_elements, bm.length / bm.n_elements
    pos = {k: j for j, k in enumerate(free)}
    S = len(bm.x)
    verts = np.repeat(np.stack([bm.x, np.zeros(S), np.zeros(S)], 1), 2, axis=0)
    verts[:, 1] = np.tile([-width / 2, width / 2], S)
    D = sp.lil_matrix((3 * 2 * S, len(free)))
    Hmid = _shapes(0.0, h)[0]
    for k in range(S):
        e, mid = divmod(k, 2)
        ux = 4 * e + 3 if mid else 4 * e
        uz = {} if mid else {4 * e + 1: 1.0}
        if mid:
            uz = dict(zip(bm.elem_dofs[e, _W_IDX], Hmid))
        for v in (2 * k, 2 * k + 1):
            if ux in pos:
                D[3 * v, pos[ux]] = 1.0
            for dof, c in uz.items():
                if dof in pos:
                    D[3 * v + 2, pos[dof]] += c
    quads = np.array([[2 * k, 2 * k + 2, 2 * k + 3, 2 * k + 1] for k in range(S - 1)])
    faces = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return nnm.DisplayMesh(verts, faces, D.tocsr(), part_ids=np.zeros(len(faces)), part_names=["beam"])


def beam_structure(length, thickness, width, E, rho, elements=DEFAULT_BEAM_ELEMENTS, ends="hinged"):
    """The von Karman beam as a GeometricStructure on its free DOFs (see ``von_karman_beam``)."""
    from .geometric import GeometricStructure
    bm = beam_mesh(length, thickness, width, E, rho, elements, ends)
    free = bm.free()
    K = bm.K[free][:, free].tocsr()
    M = bm.M[free][:, free].tocsr()
    info = {"builder": "nnm_fem.von_karman_beam", "length_m": bm.length, "thickness_m": float(thickness),
            "width_m": float(width), "E_Pa": float(E), "rho_kg_m3": float(rho), "elements": bm.n_elements,
            "ends": ends, "midspan_dof": f"node {bm.n_elements + 1} uz"}
    return GeometricStructure(M, K, bm.energy.restricted(free), [bm.labels[k] for k in free],
                              _ribbon(bm, free, float(width)), f"von Karman beam ({ends})", info,
                              {"uniform": bm.load_vector(np.ones_like)[free]})


def von_karman_beam(length, thickness, width, E, rho, elements=DEFAULT_BEAM_ELEMENTS, ends="hinged"):
    """Plane beam with immovable ends and von Karman kinematics as an ``nnm.Model`` (contract, issue 55).

    length, thickness (m, along z), width (m), E (Pa), rho (kg/m^3); rectangular section A = width *
    thickness, I = width * thickness^3 / 12.  ``elements`` beam elements (cubic Hermite w, quadratic u,
    two Gauss points; module docstring); ends "hinged" (ux = uz = 0) or "clamped" (ux = uz = ry = 0) at
    both ends.  M, K: consistent mass (axial and transverse inertia, no rotary inertia) and the linear
    stiffness; the nonlinear membrane energy EA/2 int (u' w'^2 + w'^4 / 4) dx is one
    ``nnm.PolynomialStiffness`` per Gauss point on d = (u', w').  DOF labels "node k ux|uz|ry" (1-based
    stations x = (k - 1) L / (2 elements); odd k element ends, even k midpoints with ux only; ry = -dw/dx);
    the midspan deflection is "node <elements + 1> uz" for an even element count (``info["midspan_dof"]``).

    Default ``elements`` = 16, measured (docs/geometric.md, L/h = 100): static large deflection (exact sine-load
    solution) 3e-6 at a = 1 and 2 thicknesses, linear frequencies 1e-6 (mode 1) to 3e-4 (mode 4); NNM 1 of
    the hinged beam against its closed-form backbone up to a = h: 4.7e-5 with 8 elements, 9.5e-6 with 16 (full
    model).  The model keeps the axial inertia the closed form neglects: full model minus one-mode ROM (no axial
    inertia) ~7e-6 at a = h here; the effect scales like (f / f_axial)^2 (estimated, not
    measured: ~2e-2 at 2 thicknesses for a stubby L/h = 20).
    """
    return beam_structure(length, thickness, width, E, rho, elements, ends).model()


def hinged_backbone(amplitude, length, thickness, E, rho):
    """Closed-form NNM 1 of the hinged-hinged beam with immovable ends (axial inertia neglected).

    With w = a(t) sin(pi x / L) the axial force is uniform, N = EA / (2L) int w'^2 = EA pi^2 a^2 / (4 L^2), and the
    continuum reduces exactly to  a'' + w0^2 (a + a^3 / (4 r^2)) = 0,  w0 = (pi / L)^2 sqrt(EI / (rho A)),
    r^2 = I / A = h^2 / 12.  For midspan amplitudes ``amplitude`` (m) returns (frequency_hz, energy_per_width):
    the period is 4 K(m) / (w0 sqrt(1 + kap)), kap = a^2 / (4 r^2), m = kap / (2 (1 + kap)) (K the complete
    elliptic integral of the first kind, parameter m); the energy of a beam of width 1 m is
    (rho h L / 2) w0^2 (a^2 / 2 + a^4 / (16 r^2)) (J/m; multiply by the width).
    """
    from scipy.special import ellipk
    a = np.asarray(amplitude, dtype=float)
    r2 = thickness ** 2 / 12
    w0 = (np.pi / length) ** 2 * np.sqrt(E * r2 / rho)
    kap = a ** 2 / (4 * r2)
    period = 4 * ellipk(kap / (2 * (1 + kap))) / (w0 * np.sqrt(1 + kap))
    energy = rho * thickness * length / 2 * w0 ** 2 * (a ** 2 / 2 + a ** 4 / (16 * r2))
    return 1 / period, energy
