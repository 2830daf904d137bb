"""Display meshes: the triangle surface on which a model's motion is shown (viewer, exports)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import NNMInputError


@dataclass
class DisplayMesh:
    """Triangle surface used to show a model's motion.

    vertices : (V, 3) m; faces : (F, 3) vertex indices; displacement_map : (3V, n) maps the
    model coordinates x to vertex displacements, vertex-major (v0x, v0y, v0z, v1x, ...);
    part_ids : (F,) index into part_names (optional).

    The map may be a scipy.sparse matrix (kept sparse, as CSR): a large FE model's map selects a few
    DOFs per vertex, and its dense form (3V x n float32) would be gigabytes.
    """

    vertices: np.ndarray
    faces: np.ndarray
    displacement_map: np.ndarray
    part_ids: np.ndarray | None = None
    part_names: list[str] = field(default_factory=list)

    def __post_init__(self):
        self.vertices = np.asarray(self.vertices, dtype=float)
        self.faces = np.asarray(self.faces, dtype=np.int64)
        if sp.issparse(self.displacement_map):
            self.displacement_map = sp.csr_matrix(self.displacement_map)
        else:
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
        if sp.issparse(self.displacement_map):
            u = np.asarray(self.displacement_map @ x.T, dtype=float).T
        else:
            u = x @ self.displacement_map.T
        return u.reshape(x.shape[:-1] + (len(self.vertices), 3))

    def map_rows(self, rows):
        """Rows of the displacement map as a dense float array (len(rows), n), dense or sparse map."""
        D = self.displacement_map[np.asarray(rows, dtype=np.int64)]
        return np.asarray(D.toarray() if sp.issparse(D) else D, dtype=float)
