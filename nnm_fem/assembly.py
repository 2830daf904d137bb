"""Finite-element model container with vectorised sparse assembly (COO -> CSR).

Nodes carry 6 DOF (ux, uy, uz, rx, ry, rz); DOF of node i, component c = 6 i + c.
Every element belongs to a named part so that strain energies can be split by part.
SI units throughout (m, kg, N, Pa).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from nnm_solver.errors import NNMInputError
from .beam import beam_matrices
from .shell import shell_matrices

DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")


class FEModel:
    """Nodes, elements and point properties; ``assemble()`` returns sparse K, M."""

    def __init__(self):
        self.nodes = np.zeros((0, 3))
        self._blocks = []   # (part, dofs (E, nd), k (E, nd, nd) or None, m (E, nd, nd) or None)
        self.parts = []

    # ------------------------------------------------------------ nodes
    @property
    def n_nodes(self):
        return len(self.nodes)

    @property
    def n_dof(self):
        return 6 * len(self.nodes)

    def add_nodes(self, xyz):
        """Append nodes (N, 3) in m; return their indices."""
        xyz = np.atleast_2d(np.asarray(xyz, float))
        if xyz.ndim != 2 or xyz.shape[1] != 3:
            raise NNMInputError(f"nodes must have shape (N, 3), got {xyz.shape}")
        i0 = len(self.nodes)
        self.nodes = np.vstack([self.nodes, xyz])
        return np.arange(i0, i0 + len(xyz))

    def _part(self, name):
        if name not in self.parts:
            self.parts.append(name)
        return name

    def _check_nodes(self, idx):
        idx = np.asarray(idx, dtype=np.int64)
        if idx.size and (idx.min() < 0 or idx.max() >= self.n_nodes):
            raise NNMInputError(f"element refers to node outside 0..{self.n_nodes - 1}")
        return idx

    @staticmethod
    def node_dofs(nodes):
        """DOF indices (E, 6*nn) of element node lists (E, nn)."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return (6 * nodes[..., None] + np.arange(6)).reshape(nodes.shape[0], -1)

    def add_block(self, part, dofs, k=None, m=None):
        """Add element matrices k, m (E, nd, nd) on global DOFs (E, nd)."""
        self._blocks.append((self._part(part), np.asarray(dofs, np.int64), k, m))

    # ------------------------------------------------------------ elements
    def add_beams(self, part, n1, n2, orient, E, G, A, Iy, Iz, J, rho=0.0, **kw):
        """Timoshenko beams between nodes n1[i] and n2[i] (see beam.beam_matrices)."""
        n1, n2 = self._check_nodes(np.atleast_1d(n1)), self._check_nodes(np.atleast_1d(n2))
        if len(n1) == 0:
            return
        k, m = beam_matrices(self.nodes[n1], self.nodes[n2], orient, E, G, A, Iy, Iz, J,
                             np.maximum(rho, 1e-300) if np.ndim(rho) == 0 else rho, **kw)
        self.add_block(part, self.node_dofs(np.stack([n1, n2], 1)), k, m)

    def add_shells(self, part, quads, E, nu, t, tb=None, rho=0.0, nsm=0.0, **kw):
        """Flat quad shells on node quadruples (E, 4) (see shell.shell_matrices); returns areas."""
        quads = self._check_nodes(np.atleast_2d(quads))
        if quads.shape[1] != 4:
            raise NNMInputError(f"shell connectivity must have 4 nodes per element, got {quads.shape[1]}")
        k, m, area = shell_matrices(self.nodes[quads], E, nu, t, tb, rho, nsm, **kw)
        self.add_block(part, self.node_dofs(quads), k, m)
        return area

    def add_rigid_links(self, part, master, slaves, stiffness=1e10):
        """Penalty rigid links (massless stiff beams) from node ``master`` to each of ``slaves``.

        ``stiffness`` (N/m) sets the axial stiffness EA/L of each link; bending and torsion
        are scaled to be equally stiff.
        """
        slaves = np.atleast_1d(slaves)
        n1 = np.full(len(slaves), master) if np.ndim(master) == 0 else np.asarray(master)
        L = np.linalg.norm(self.nodes[slaves] - self.nodes[n1], axis=1)
        if np.any(L <= 0):
            raise NNMInputError("rigid link between coincident nodes: use a spring (add_spring) instead")
        E = 1e11
        A = stiffness * L / E
        I = A * L ** 2 / 12 + 1e-12
        self.add_beams(part, n1, slaves, [0.123, 0.456, 0.789], E, E / 2.6, A, I, I, 2 * I, rho=0.0,
                       shear_factor=5 / 6)

    def add_point_mass(self, part, node, mass, inertia=(0.0, 0.0, 0.0)):
        """Point mass (kg) and rotary inertias (kg m^2 about x, y, z) at a node."""
        d = np.concatenate([[mass] * 3, np.broadcast_to(inertia, 3)]).astype(float)
        self.add_block(part, self.node_dofs([[node]]), None, np.diag(d)[None])

    def add_bushing(self, part, n1, n2, k6, frame=None):
        """6-component spring between nodes n1 and n2 (n2 = None: to ground).

        k6 : stiffnesses (N/m x3, N m/rad x3) along the rows of ``frame`` (3x3, default
        global axes).
        """
        R = np.eye(3) if frame is None else np.asarray(frame, float)
        kl = np.diag(np.asarray(k6, float))
        T = np.zeros((6, 6))
        T[:3, :3] = R
        T[3:, 3:] = R
        kg = T.T @ kl @ T
        if n2 is None:
            self.add_block(part, self.node_dofs([[n1]]), kg[None], None)
        else:
            k = np.block([[kg, -kg], [-kg, kg]])
            self.add_block(part, self.node_dofs([[n1, n2]]), k[None], None)

    def add_dof_spring(self, part, dofs, coeffs, k):
        """Spring of stiffness k on the combination d = sum coeffs[i] * x[dofs[i]]: energy k d^2/2."""
        c = np.asarray(coeffs, float)
        self.add_block(part, np.asarray(dofs, np.int64)[None], (k * np.outer(c, c))[None], None)

    # ------------------------------------------------------------ assembly
    def _assemble(self, which, parts=None):
        n = self.n_dof
        rows, cols, vals = [], [], []
        for part, dofs, k, m in self._blocks:
            mat = k if which == "k" else m
            if mat is None or (parts is not None and part not in parts):
                continue
            nd = dofs.shape[1]
            rows.append(np.repeat(dofs, nd, axis=1).ravel())
            cols.append(np.tile(dofs, (1, nd)).ravel())
            vals.append(np.asarray(mat).reshape(len(dofs), -1).ravel())
        if not rows:
            return sp.csr_matrix((n, n))
        A = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
        A = A.tocsr()
        A.sum_duplicates()
        A = 0.5 * (A + A.T)
        A.eliminate_zeros()
        return A.tocsr()

    def assemble(self):
        """Global sparse (CSR) stiffness K (N/m) and mass M (kg)."""
        return self._assemble("k"), self._assemble("m")

    def part_stiffness(self, part):
        """Sparse stiffness of the elements of one part (for strain-energy splits)."""
        return self._assemble("k", {part})

    def element_dofs(self, part):
        """Global DOF indices (E, nd) of every element block of one part (a list, one array per block)."""
        return [dofs for p, dofs, _, _ in self._blocks if p == part]

    def total_mass(self, M=None):
        """Total translational mass (kg) from the assembled M (x direction)."""
        M = self._assemble("m") if M is None else M
        ix = np.arange(0, self.n_dof, 6)
        return float(M[ix][:, ix].sum())
