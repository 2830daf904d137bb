"""The display mesh of a Nastran model: its bulk data's GRID points and elements, read by pyNastran's BDF reader.

``[mesh] file = "model.bdf"`` (suffix .bdf, .dat, .nas, .blk, .bulk; no ``format``) in a description of a Nastran
model.  A bulk data file alone (no BEGIN BULK) is read as a punch file.  Each grid is placed at its position in
the basic system (CP coordinate systems applied); its model DOFs are found by grid ID and direction in the model's
DOF map (the a-set's ASET/QSET cards or a 'grid component' file), in the grid's displacement system CD
(rectangular systems: CORD1R, CORD2R).  A grid or component outside the model (constrained, reduced out) stays
still.

* Shells (CQUAD4, CQUAD8, CQUADR, CTRIA3, CTRIA6, CTRIAR, CSHEAR: corner grids) are faces on the grids
  themselves, split into triangles.
* Line elements (CBAR, CBEAM, CROD, CTUBE, CONROD) are drawn as flat ribbons (the viewer draws triangles):
  four vertices per element, at offsets r = +-w/2 e from its two grids, e the element's orientation vector
  made normal to its axis (CBAR/CBEAM x or G0; else a normal to the axis), w = ``FILES.ribbon_width`` of the
  model's size.  A ribbon vertex moves rigidly with its grid: u + theta x r (theta: the grid's rotations
  when the model has them), so a bending beam's ribbon twists and bends with it.

Spring, mass and rigid elements (CBUSH, CELASi, CONM2, RBE2, ...) are not drawn.  Coordinates are in the
description's length unit (scaled to m by ``scale``); the map's rotation columns carry r in the same unit, as
meshfile.py's (toml.py converts both).
"""
from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError
from ...model.mesh import DisplayMesh
from .common import existing
from ..settings import FILES

EXTRA = 'pip install "nnm[nastran]" (pyNastran)'
#: bulk data file suffixes whose [mesh] is read here (meshio with [mesh] format = "nastran")
BULK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk", ".bulk")
#: an alias of files/settings.py's FILES.ribbon_width (the code reads that)
RIBBON_WIDTH = FILES.ribbon_width
SHELLS = ("CQUAD4", "CQUAD8", "CQUADR", "CTRIA3", "CTRIA6", "CTRIAR", "CSHEAR")
LINES = ("CBAR", "CBEAM", "CROD", "CTUBE", "CONROD")

__all__ = ["read_bdf_mesh", "read_bdf_geometry", "BULK_SUFFIXES", "RIBBON_WIDTH"]


def _read(path):
    """pyNastran's BDF of ``path``, nodes cross-referenced (positions, CD systems); one-line errors."""
    try:
        from pyNastran.bdf.bdf import BDF
    except ImportError as exc:
        raise NNMInputError(f"{path}: the geometry of a Nastran bulk data file needs the optional package pyNastran: "
                            f"{EXTRA} ({exc})") from None
    try:
        text = path.read_text(errors="strict")
    except UnicodeDecodeError:
        raise NNMFileError(f"{path}: not a text (bulk data) file") from None
    quiet = logging.getLogger("nnm.nastran")
    quiet.setLevel(logging.ERROR)
    model = BDF(log=quiet, debug=False)
    try:
        model.read_bdf(str(path), xref=False, punch="BEGIN BULK" not in text.upper())
        model.cross_reference(xref=True, xref_nodes=True, xref_elements=False, xref_nodes_with_elements=False,
                              xref_properties=False, xref_masses=False, xref_materials=False, xref_loads=False,
                              xref_constraints=False, xref_aero=False, xref_sets=False, xref_optimization=False)
    except Exception as exc:           # pyNastran raises many kinds on a bad deck
        msg = str(exc).strip().splitlines()
        raise NNMFileError(f"{path}: not a readable Nastran bulk data file ({exc.__class__.__name__}: "
                           f"{(msg[0] if msg else '')[:160]})") from None
    return model


def read_bdf_geometry(path):
    """(grids {id: (xyz basic (3,), R (3, 3) from CD to basic)}, shells [(eid, grid ids)], lines [(eid, g1, g2,
    orientation (3,) basic or None)]) of a bulk data file."""
    path = existing(path, "Nastran bulk data file")
    model = _read(path)
    grids = {}
    for nid, node in model.nodes.items():
        cd = node.cd_ref if node.cd else None
        if cd is not None and getattr(cd, "Type", "R") != "R":
            raise NNMFileError(f"{path}: GRID {nid} has its displacement system CD {node.cd}, a "
                               f"{type(cd).__name__}; only rectangular CD systems are supported for the display mesh")
        R = np.eye(3) if cd is None else np.asarray(cd.beta(), dtype=float).T
        grids[int(nid)] = (np.asarray(node.get_position(), dtype=float), R)
    shells, lines = [], []
    for eid, el in sorted(model.elements.items()):
        kind = el.type
        if kind in SHELLS:
            corners = 3 if kind.startswith("CTRIA") else 4
            shells.append((int(eid), [int(g) for g in el.node_ids[:corners]]))
        elif kind in LINES:
            g1, g2 = (int(g) for g in el.node_ids[:2])
            v = None
            if kind in ("CBAR", "CBEAM"):
                if getattr(el, "g0", None):
                    if int(el.g0) not in grids:
                        raise NNMFileError(f"{path}: {kind} {eid}: orientation grid G0 {el.g0} is not a GRID")
                    v = grids[int(el.g0)][0] - grids[g1][0]
                elif getattr(el, "x", None) is not None and np.any(np.asarray(el.x, dtype=float) != 0):
                    v = grids[g1][1] @ np.asarray(el.x, dtype=float)      # x is in g1's displacement system
            lines.append((int(eid), g1, g2, v))
    for eid, ids in shells + [(e, [a, b]) for e, a, b, _ in lines]:
        missing = [g for g in ids if g not in grids]
        if missing:
            raise NNMFileError(f"{path}: element {eid} uses grid {missing[0]}, which has no GRID card")
    return grids, shells, lines


def _normal(axis, v):
    """Unit vector normal to ``axis``: v's normal part, or a normal to the axis if v is None or parallel."""
    a = axis / np.linalg.norm(axis)
    if v is not None:
        e = v - (v @ a) * a
        if np.linalg.norm(e) > 1e-9 * np.linalg.norm(v):
            return e / np.linalg.norm(e)
    e = np.cross(a, np.eye(3)[np.argmin(np.abs(a))])
    return e / np.linalg.norm(e)


def read_bdf_mesh(path, n, dof_map, *, recovery=None, scale=1.0, where=""):
    """DisplayMesh of the grids and elements of a Nastran bulk data file for a model of n DOFs (module docstring).

    dof_map : the model's DofMap (grid, direction), needed unless ``recovery`` (a (3 V, n) matrix, meshfile.py)
    gives the vertex displacements; scale : metres per length unit of the file."""
    path = existing(path, where + "display mesh" if where else "display mesh")
    grids, shells, lines = read_bdf_geometry(path)
    if not shells and not lines:
        raise NNMFileError(f"{path}: no elements to draw (CQUAD4, CTRIA3, CBAR, CBEAM, CROD ...); the display mesh "
                           f"needs the model's elements, not only its GRID cards")
    used = sorted({g for _, ids in shells for g in ids})
    vertex = {g: i for i, g in enumerate(used)}
    points = [grids[g][0] for g in used]
    owners = [(g, np.zeros(3)) for g in used]                  # (grid, offset r from it) of each vertex
    faces = []
    for _, ids in shells:
        v = [vertex[g] for g in ids]
        faces += [v[:3]] if len(v) == 3 else [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
    part_ids = [0] * len(faces)
    if lines:
        xyz = np.array([grids[g][0] for _, a, b, _ in lines for g in (a, b)] + points)
        width = FILES.ribbon_width * max(float(np.linalg.norm(xyz.max(axis=0) - xyz.min(axis=0))), 1e-300)
        for _, a, b, orient in lines:
            axis = grids[b][0] - grids[a][0]
            if not np.linalg.norm(axis) > 0:
                continue                                        # zero-length element: nothing to draw
            r = 0.5 * width * _normal(axis, orient)
            k = len(points)
            for g, off in ((a, r), (a, -r), (b, -r), (b, r)):
                points.append(grids[g][0] + off)
                owners.append((g, off))
            faces += [[k, k + 1, k + 2], [k, k + 2, k + 3]]
            part_ids += [1 if shells else 0] * 2
    V = len(points)
    if recovery is not None:
        from .meshfile import read_recovery
        D = read_recovery(recovery, 3 * V, n)
    else:
        if dof_map is None:
            raise NNMInputError(f"{where}the display mesh of {path} moves with the model's DOFs by grid: give "
                                f"[matrices] dof_map (the bulk data's ASET/QSET cards or a 'grid component' file)")
        D = _grid_map(owners, grids, dof_map, n)
        if D.nnz == 0:
            raise NNMInputError(f"{where}no grid of {path} matches a DOF of the model (its DOF map has nodes "
                                f"{', '.join(map(str, dof_map.nodes[:4]))} ...): is it the model's bulk data?")
    names = [p for p, present in (("shells", shells), ("bars", lines)) if present]
    return DisplayMesh(np.array(points) * float(scale), np.array(faces, dtype=np.int64).reshape(-1, 3), D,
                       part_ids=np.array(part_ids, dtype=np.int64), part_names=[f"{Path(path).stem} {p}" for p in names])


def _grid_map(owners, grids, dof_map, n):
    """(3 V, n) sparse map: vertex displacement (basic) = R (u + theta x r_local) of its grid, R its CD to basic.
    With r = R^T r_basic in the grid's CD system: u_basic = R u, (theta x r)_basic = R (theta x r_local)."""
    rows, cols, vals = [], [], []
    for i, (g, off) in enumerate(owners):
        R = grids[g][1]
        rl = R.T @ off
        # local vertex displacement w = u + theta x r: w = I u + [r]x^T theta, [r]x^T = -[r]x
        cross = np.array([[0.0, rl[2], -rl[1]], [-rl[2], 0.0, rl[0]], [rl[1], -rl[0], 0.0]])
        for c, name in enumerate(("ux", "uy", "uz", "rx", "ry", "rz")):
            j = dof_map.get(g, name)
            if j is None:
                continue
            local = np.eye(3)[:, c] if c < 3 else cross[:, c - 3]
            w = R @ local
            for k in range(3):
                if w[k] != 0.0:
                    rows.append(3 * i + k)
                    cols.append(j)
                    vals.append(w[k])
    return sp.csr_matrix((vals, (rows, cols)), shape=(3 * len(owners), n))
