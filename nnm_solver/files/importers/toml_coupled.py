"""``type = "polynomial_stiffness"`` in a description's ``[[springs]]``: ``nnm.PolynomialStiffness`` (NLvib's convention).

::

    [[springs]]
    type = "polynomial_stiffness"
    exponents = [[2, 0], [1, 1], [0, 2], [3, 0]]       # n_z rows, m columns: z_i = prod_j d_j ** exponents[i][j]
    coefficients = [[1.5, 0.5], [1.0, 1.0], [0.5, 1.5], [2.0, 0.0]]   # n_z rows, m columns: g = coefficients^T z
    dofs = [3, 7]                                      # 0-based DOFs x[dofs] (default: every DOF of the model)
    # nodes = [12, 14], direction = "uz"               # ... or by node and direction (one, or one per node)
    # directions = [[1.0, -1.0]]                       # optional (m, k): d = directions @ x[dofs]

The force on the model is f_nl = W^T g(W x) (model/coupled.py); the tangent must be symmetric (a potential).
Units: row i's coefficients are force / length^p_i, p_i the monomial's degree (sum of row i of exponents), in the
description's units, converted like a polynomial spring's c_p (``Units.coefficient_scale``); the DOFs must be all
translations or all rotations.  Errors name the table: ``model.toml [[springs]] #2: ...``.
"""
from __future__ import annotations

import numpy as np

from ...errors import NNMInputError
from .common import direction_name

KEYS = {"type", "exponents", "coefficients", "dofs", "nodes", "direction", "directions"}


def _matrix(row, key, where, integer=False):
    """A list of lists of numbers (rows of equal length) as a float array; one-line errors."""
    v = row[key]
    if not isinstance(v, list) or not v or not all(isinstance(r, list) and r for r in v):
        raise NNMInputError(f"{where}: {key} must be a list of rows, e.g. {key} = [[3, 0], [1, 2]]")
    if len({len(r) for r in v}) != 1:
        raise NNMInputError(f"{where}: {key} rows have different lengths ({', '.join(str(len(r)) for r in v)})")
    for i, r in enumerate(v, 1):
        for x in r:
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not np.isfinite(x):
                raise NNMInputError(f"{where}: {key} row {i}: {x!r} is not a finite number")
            if integer and (not isinstance(x, int) or x < 0):
                raise NNMInputError(f"{where}: {key} row {i}: {x!r} is not an integer >= 0")
    return np.array(v, dtype=float)


def _located(row, n, dof_map, where):
    """The 0-based DOF indices of ``dofs`` or ``nodes`` + ``direction`` (None: every DOF)."""
    if "dofs" in row and "nodes" in row:
        raise NNMInputError(f"{where}: give dofs or nodes, not both")
    if "direction" in row and "nodes" not in row:
        raise NNMInputError(f"{where}: direction goes with nodes = [...]")
    if "dofs" in row:
        d = row["dofs"]
        if not isinstance(d, list) or not d or any(isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < n
                                                   for v in d):
            raise NNMInputError(f"{where}: dofs = {d!r} must list 0-based DOF indices of the model (0..{n - 1})")
        return [int(v) for v in d]
    if "nodes" not in row:
        return None
    nodes = row["nodes"]
    if not isinstance(nodes, list) or not nodes:
        raise NNMInputError(f"{where}: nodes must be a list of node labels, e.g. nodes = [12, 14]")
    if dof_map is None:
        raise NNMInputError(f"{where}: nodes need a DOF map; these matrix files have none: give dofs = [...] "
                            f"(0-based), or [matrices] dof_map = <file>")
    dirs = row.get("direction")
    if dirs is None:
        raise NNMInputError(f"{where}: nodes need direction = \"uz\" (one for all) or a list, one per node")
    dirs = dirs if isinstance(dirs, list) else [dirs] * len(nodes)
    if len(dirs) != len(nodes):
        raise NNMInputError(f"{where}: {len(dirs)} directions for {len(nodes)} nodes")
    return [dof_map.index(node, direction_name(dr, f"{where}: "), f"{where}: ") for node, dr in zip(nodes, dirs)]


def build_polynomial_stiffness(row, n, dof_map, units, where):
    """The PolynomialStiffness of a ``[[springs]]`` table (module docstring), in SI."""
    from ...model.coupled import PolynomialStiffness

    extra = sorted(set(row) - KEYS)
    if extra:
        raise NNMInputError(f"{where}: unknown key(s) {', '.join(extra)} for a polynomial_stiffness; known: "
                            f"{', '.join(sorted(KEYS))}")
    missing = [k for k in ("exponents", "coefficients") if k not in row]
    if missing:
        raise NNMInputError(f"{where}: missing {', '.join(missing)} (a polynomial_stiffness needs exponents and "
                            f"coefficients, n_z rows of m numbers each)")
    ex = _matrix(row, "exponents", where, integer=True)
    co = _matrix(row, "coefficients", where)
    dofs = _located(row, n, dof_map, where)
    D = None if "directions" not in row else _matrix(row, "directions", where)
    rotations = dof_map.rotations() if dof_map is not None else np.zeros(n, bool)
    used = rotations[list(range(n)) if dofs is None else dofs]
    if not units.is_si and used.any() and not used.all():
        raise NNMInputError(f"{where}: units {units}: the coefficients of a force on translations and rotations at "
                            f"once have no single unit; give this element in SI")
    scale = units.coefficient_scale(bool(used.all()))
    if ex.shape == co.shape:
        co = co * np.array([scale(int(p)) for p in ex.sum(axis=1)])[:, None]
    try:
        element = PolynomialStiffness(ex.astype(np.int64), co, dofs=dofs, directions=D)
        element.matrix(n)                                  # its coordinates fit the model
        return element
    except NNMInputError as exc:
        raise NNMInputError(f"{where}: {exc}") from None
