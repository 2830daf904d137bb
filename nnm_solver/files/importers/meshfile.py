"""A display mesh from any mesh file meshio reads (Gmsh .msh, Abaqus .inp, VTK/VTU, Nastran .bdf ...).  In a model
description a Nastran bulk data file is read by pyNastran instead (nastran_mesh.py: grids by ID, bars as ribbons;
toml.py's ``display_mesh`` chooses), or here with ``format = "nastran"``.

meshio is an optional extra (``pip install "nnm[io]"``).  The viewer draws triangles: surface cells
are split into triangles, and volume cells contribute their boundary faces (faces used by one cell
only); higher-order cells use their corner nodes.  Lines and points are not drawn.

meshio numbers the points 0..V-1 in file order (it does not keep the file's node labels), so the
map from the model's DOFs to the mesh points is given by one of:

* the model's DOF map (node, direction): mesh point i is the model node ``nodes[i]`` if given, else
  node ``first_node + i`` (default 1: the file's nodes numbered 1..V in order); its ux, uy, uz
  move it (a node missing from the model, e.g. clamped, stays still);
* ``dofs_per_node = k`` for models without a DOF map: mesh point i moves with DOFs k i .. k i + 2
  (inferred when the model has exactly 3 V or 6 V DOFs);
* ``recovery``: a (3 V, n) matrix (MatrixMarket .mtx, .npy or .mat variable ``recovery``) from the
  model coordinates to vertex displacements, vertex-major -- for reduced models.
"""
from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError
from ...model.mesh import DisplayMesh
from .common import existing

EXTRA = 'pip install "nnm[io]" (meshio)'

# corner-node faces of volume cells (meshio / VTK node order)
_VOLUME_FACES = {
    "tetra": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
    "wedge": [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    "pyramid": [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
}


def _base(cell_type):
    for base in ("triangle", "quad", "tetra", "hexahedron", "wedge", "pyramid"):
        if cell_type.startswith(base):
            return base
    return None


def _triangles(polys):
    """Triangles of polygons (k, 3 or 4) by a fan."""
    polys = np.asarray(polys)
    if polys.shape[1] == 3:
        return polys
    return np.concatenate([polys[:, [0, 1, 2]], polys[:, [0, 2, 3]]])


def mesh_surface(mesh, path):
    """(faces (F, 3), part_ids (F,), part_names) of a meshio Mesh."""
    surface, volume_faces = [], {}
    for block in mesh.cells:
        base = _base(block.type)
        data = np.asarray(block.data, dtype=np.int64)
        if base in ("triangle", "quad"):
            surface.append(_triangles(data[:, :3 if base == "triangle" else 4]))
        elif base in _VOLUME_FACES:
            for face in _VOLUME_FACES[base]:
                for cell_face in data[:, face]:
                    key = tuple(sorted(cell_face.tolist()))
                    volume_faces[key] = None if key in volume_faces else tuple(cell_face.tolist())
    boundary = [f for f in volume_faces.values() if f is not None]
    parts, ids = [], []
    if surface:
        parts.append("surface")
        s = np.concatenate(surface)
        ids.append(np.zeros(len(s), np.int64))
        surface = [s]
    if boundary:
        tris = np.concatenate([_triangles(np.array([f for f in boundary if len(f) == k]))
                               for k in (3, 4) if any(len(f) == k for f in boundary)])
        surface.append(tris)
        ids.append(np.full(len(tris), len(parts), np.int64))
        parts.append("volume boundary")
    if not surface:
        kinds = sorted({b.type for b in mesh.cells}) or ["no cells"]
        raise NNMFileError(f"{path}: no surface or volume cells to draw (found {', '.join(kinds)}); "
                           f"the viewer draws triangles: export the structure's surface")
    return np.concatenate(surface), np.concatenate(ids), parts


def read_recovery(path, rows, n):
    path = existing(path, "mesh recovery matrix")
    suffix = path.suffix.lower()
    try:
        if suffix == ".npy":
            R = np.load(path)
        elif suffix == ".mat":
            from .matlab import read_mat
            data = read_mat(path, ["recovery"])
            if "recovery" not in data:
                raise NNMFileError(f"{path}: no variable 'recovery'")
            R = data["recovery"]
        else:
            from .matrixmarket import read_mtx
            R = read_mtx(path, "recovery", square=False)
    except (OSError, ValueError) as exc:
        raise NNMFileError(f"{path}: unreadable recovery matrix ({exc})") from None
    R = R.toarray() if sp.issparse(R) else np.asarray(R, dtype=float)
    if R.shape != (rows, n):
        raise NNMFileError(f"{path}: the recovery matrix is {R.shape[0]}x{R.shape[1]}, expected {rows}x{n} "
                           f"(3 x mesh points, model DOFs)")
    return R


def read_display_mesh(path, n, dof_map=None, *, nodes=None, first_node=1, dofs_per_node=None, recovery=None,
                      scale=1.0, file_format=None, where=""):
    """DisplayMesh of the mesh file ``path`` for a model of n DOFs (see the module docstring).

    scale : metres per length unit of the mesh coordinates; file_format : meshio's name of the
    format when the suffix is ambiguous (default: from the suffix).
    """
    path = existing(path, where + "display mesh" if where else "display mesh")
    try:
        import meshio
    except ImportError:
        raise NNMInputError(f"{path}: display meshes from mesh files need the optional package meshio: "
                            f"{EXTRA}") from None
    # meshio tries every reader of a suffix, prints their failures and calls sys.exit when none fits
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            mesh = meshio.read(path, file_format=file_format)
    except SystemExit:
        raise NNMFileError(f"{path}: not a mesh file meshio can read"
                           f"{' as ' + file_format if file_format else ''} (set [mesh] format to one of "
                           f"meshio's formats, e.g. gmsh, nastran, abaqus, vtu)") from None
    except Exception as exc:  # meshio raises ReadError, KeyError, ValueError, ... on bad input
        raise NNMFileError(f"{path}: not a mesh file meshio can read ({exc.__class__.__name__}: "
                           f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or not len(points):
        raise NNMFileError(f"{path}: the mesh has no points")
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    V = len(points)
    faces, part_ids, part_names = mesh_surface(mesh, path)
    D = np.zeros((3 * V, n))
    if recovery is not None:
        D = read_recovery(recovery, 3 * V, n)
    elif dof_map is not None and dofs_per_node is None:
        if nodes is not None:
            nodes = list(nodes)
            if len(nodes) != V:
                raise NNMInputError(f"{where}nodes lists {len(nodes)} model nodes but {path} has {V} points")
        else:
            nodes = [int(first_node) + i for i in range(V)]
        for i, node in enumerate(nodes):
            for c, d in enumerate(("ux", "uy", "uz")):
                j = dof_map.get(node, d)
                if j is not None:
                    D[3 * i + c, j] = 1.0
        if not D.any():
            raise NNMInputError(f"{where}no point of {path} matches a translational DOF of the model: "
                                f"set first_node (now {first_node}) or nodes = [...] in [mesh]")
    else:
        k = dofs_per_node
        if k is None:
            if n == 3 * V:
                k = 3
            elif n == 6 * V:
                k = 6
            else:
                raise NNMInputError(f"{where}cannot tell which DOFs move the {V} points of {path} ({n} model DOFs, "
                                    f"no DOF map): give dofs_per_node, a dof_map file or a recovery matrix")
        k = int(k)
        if k < 1 or k * (V - 1) + min(3, k) > n:
            raise NNMInputError(f"{where}dofs_per_node = {k} needs {k * (V - 1) + 3} DOFs for {V} mesh points, "
                                f"the model has {n}")
        for i in range(V):
            for c in range(min(3, k)):
                D[3 * i + c, k * i + c] = 1.0
    return DisplayMesh(points * float(scale), faces, D, part_ids=part_ids,
                       part_names=[f"{Path(path).stem} {p}" for p in part_names])
