"""Abaqus matrix output: ``*MATRIX GENERATE, STIFFNESS, MASS`` + ``*MATRIX OUTPUT, STIFFNESS, MASS``.

Abaqus writes ``<job>_STIF<step>.mtx`` and ``<job>_MASS<step>.mtx`` in one of two text formats:

* ``FORMAT=MATRIX INPUT`` (the default): one entry per line,
  ``row node, row DOF, column node, column DOF, value`` -- the DOF map comes with the matrix
  (DOF 1..6 = ux, uy, uz, rx, ry, rz; node labels may be instance-qualified, ``Part-1-1.12``);
* ``FORMAT=COORDINATE``: ``row, column, value`` in 1-based equation numbers (no DOF map).

Symmetric matrices are written as one triangle and mirrored here.  Lines starting with ``*`` are
comments or keywords and are skipped; Fortran ``D`` exponents are accepted.
"""
from __future__ import annotations

import re

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError
from .common import DofMap, direction_name, existing, node_key, sort_nodes, symmetric_from_storage

_SPLIT = re.compile(r"[,\s]+")


def _number(token, path, lineno):
    try:
        return float(token.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise NNMFileError(f"{path} line {lineno}: {token!r} is not a number") from None


def _int(token, path, lineno, what):
    try:
        return int(token)
    except ValueError:
        raise NNMFileError(f"{path} line {lineno}: {what} {token!r} is not an integer") from None


def parse_abaqus_matrix(path, what="matrix"):
    """Entries of an Abaqus matrix file: ('labels', [(row node, row dir, col node, col dir, value)]) for
    MATRIX INPUT format, or ('coordinate', [(row, col, value)]) (0-based) for COORDINATE format."""
    path = existing(path, f"{what} matrix")
    kind, rows = None, []
    with open(path, "r", errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            s = line.strip()
            if not s or s.startswith("*"):
                continue
            parts = [p for p in _SPLIT.split(s) if p]
            k = {5: "labels", 3: "coordinate"}.get(len(parts))
            if k is None:
                raise NNMFileError(f"{path} line {lineno}: expected 'row node, row DOF, column node, column DOF, "
                                   f"value' (5 fields) or 'row, column, value' (3 fields), got {len(parts)} fields")
            if kind is None:
                kind = k
            elif k != kind:
                raise NNMFileError(f"{path} line {lineno}: {len(parts)} fields where earlier lines had "
                                   f"{5 if kind == 'labels' else 3}")
            if kind == "labels":
                try:
                    rd = direction_name(_int(parts[1], path, lineno, "row DOF"))
                    cd = direction_name(_int(parts[3], path, lineno, "column DOF"))
                except NNMInputError as exc:
                    raise NNMFileError(f"{path} line {lineno}: {exc}") from None
                rows.append((node_key(parts[0]), rd, node_key(parts[2]), cd, _number(parts[4], path, lineno)))
            else:
                r = _int(parts[0], path, lineno, "row")
                c = _int(parts[1], path, lineno, "column")
                if r < 1 or c < 1:
                    raise NNMFileError(f"{path} line {lineno}: equation numbers start at 1, got ({r}, {c})")
                rows.append((r - 1, c - 1, _number(parts[2], path, lineno)))
    if kind is None:
        raise NNMFileError(f"{path}: no matrix entries (is it an Abaqus *MATRIX OUTPUT file?)")
    return kind, rows


def read_abaqus_pair(mass, stiffness):
    """(M, K, dof_map or None) from Abaqus MASS and STIF files (the DOF map is their union of (node, DOF))."""
    km, rm = parse_abaqus_matrix(mass, "mass")
    kk, rk = parse_abaqus_matrix(stiffness, "stiffness")
    if km != kk:
        raise NNMFileError(f"{mass} and {stiffness} are in different formats ({km} vs {kk}); "
                           f"write both with the same *MATRIX OUTPUT FORMAT")
    if km == "labels":
        keys = {(r[0], r[1]) for r in rm + rk} | {(r[2], r[3]) for r in rm + rk}
        order = {d: i for i, d in enumerate(("ux", "uy", "uz", "rx", "ry", "rz"))}
        nodes = sort_nodes({n for n, _ in keys})
        rank = {n: i for i, n in enumerate(nodes)}
        entries = sorted(keys, key=lambda e: (rank[e[0]], order.get(e[1], 6), e[1]))
        dof_map = DofMap(entries)
        index = {e: i for i, e in enumerate(entries)}

        def build(rows, path):
            r = [index[(x[0], x[1])] for x in rows]
            c = [index[(x[2], x[3])] for x in rows]
            v = [x[4] for x in rows]
            return symmetric_from_storage(sp.coo_matrix((v, (r, c)), shape=(len(entries),) * 2), path)

        return build(rm, mass), build(rk, stiffness), dof_map
    n = 1 + max(max(r[0], r[1]) for r in rm + rk)

    def build(rows, path):
        a = np.array(rows, dtype=float)
        return symmetric_from_storage(sp.coo_matrix((a[:, 2], (a[:, 0].astype(int), a[:, 1].astype(int))),
                                                    shape=(n, n)), path)

    return build(rm, mass), build(rk, stiffness), None


def write_abaqus_matrix(path, A, dof_map=None):
    """Write the lower triangle of a symmetric matrix as Abaqus does: MATRIX INPUT format with a DOF map
    (node, direction), else COORDINATE format.  Used by the tests and the tutorial to produce files."""
    A = sp.tril(sp.coo_matrix(A)).tocoo()
    order = np.lexsort((A.col, A.row))
    number = {d: str(i + 1) for i, d in enumerate(("ux", "uy", "uz", "rx", "ry", "rz"))}
    with open(path, "w") as fh:
        fh.write("** written by nnm (Abaqus *MATRIX OUTPUT layout)\n")
        for r, c, v in zip(A.row[order], A.col[order], A.data[order]):
            if dof_map is None:
                fh.write(f"{r + 1},{c + 1}, {float(v)!r}\n")
            else:
                (nr, dr), (nc, dc) = dof_map.entries[r], dof_map.entries[c]
                fh.write(f"{nr},{number.get(dr, dr[3:])}, {nc},{number.get(dc, dc[3:])}, {float(v)!r}\n")
