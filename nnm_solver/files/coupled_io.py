"""The coupled elements (PolynomialStiffness, model/coupled.py) of an nnm model file: /model/coupled.

Layout (one row per element e, in the order of the model's element list):
    position (E,) int64          its index in Model.springs (the scalar springs fill the other indices)
    sizes (E, 3) int64           n_z, m, k (k = number of dofs; 0 when the element acts on every DOF)
    has_directions (E,) bool     whether it has a directions matrix (m, k or n)
    exponents (sum n_z m,) int64, coefficients (sum n_z m,) float, dofs (sum k,) int64,
    directions (sum m k',) float  each element's arrays flattened (row-major), in turn.
Arrays, not JSON: a von Karman beam has one element per Gauss point.  /model/springs then holds one entry of type
"polynomial_stiffness" (dof = other = -1), so that a reader that does not know the group refuses the file
(unknown spring type) instead of reading the model without these forces.
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMFileError, NNMInputError
from ..model.coupled import PolynomialStiffness

GROUP = "coupled"
#: the laws_json entry of the marker row in /model/springs
MARKER = {"type": "polynomial_stiffness", "group": "/model/" + GROUP}


def is_coupled(element):
    return isinstance(element, PolynomialStiffness)


def same_element(a, b, rtol=1e-12):
    """True when a and b are PolynomialStiffness elements with the same exponents, dofs, directions and
    coefficients (relative rtol)."""
    if not (is_coupled(a) and is_coupled(b)) or a.exponents.shape != b.exponents.shape or a.dofs != b.dofs:
        return False
    if (a.directions is None) != (b.directions is None) or not np.array_equal(a.exponents, b.exponents):
        return False
    if a.directions is not None and (a.directions.shape != b.directions.shape
                                     or not np.allclose(a.directions, b.directions, rtol=rtol, atol=0)):
        return False
    return bool(np.allclose(a.coefficients, b.coefficients, rtol=rtol, atol=0))


def split(springs):
    """(scalar springs, [(position, PolynomialStiffness)]) of a model's element list."""
    scalar = [s for s in springs if not isinstance(s, PolynomialStiffness)]
    coupled = [(i, s) for i, s in enumerate(springs) if isinstance(s, PolynomialStiffness)]
    return scalar, coupled


def write_coupled(g, coupled):
    """Write the (position, element) list into the /model group g."""
    cg = g.create_group(GROUP)
    cat = (lambda parts, t: np.concatenate(parts).astype(t) if parts else np.zeros(0, dtype=t))
    cg.create_dataset("position", data=np.array([p for p, _ in coupled], dtype=np.int64))
    cg.create_dataset("sizes", data=np.array([(e.exponents.shape[0], e.m, 0 if e.dofs is None else len(e.dofs))
                                              for _, e in coupled], dtype=np.int64).reshape(-1, 3))
    cg.create_dataset("has_directions", data=np.array([e.directions is not None for _, e in coupled], dtype=bool))
    cg.create_dataset("exponents", data=cat([e.exponents.ravel() for _, e in coupled], np.int64))
    cg.create_dataset("coefficients", data=cat([e.coefficients.ravel() for _, e in coupled], float))
    cg.create_dataset("dofs", data=cat([np.asarray(e.dofs) for _, e in coupled if e.dofs is not None], np.int64))
    cg.create_dataset("directions", data=cat([e.directions.ravel() for _, e in coupled if e.directions is not None],
                                             float))
    cg.create_dataset("direction_columns", data=np.array([e.directions.shape[1] for _, e in coupled
                                                          if e.directions is not None], dtype=np.int64))


def read_coupled(g, path):
    """[(position, PolynomialStiffness)] of the /model group g (empty without the group)."""
    if GROUP not in g:
        return []
    cg = g[GROUP]
    try:
        pos, sizes, has_dir = cg["position"][()], cg["sizes"][()].reshape(-1, 3), cg["has_directions"][()]
        ex, co, dofs = cg["exponents"][()], cg["coefficients"][()], cg["dofs"][()]
        dirs, dcols = cg["directions"][()], cg["direction_columns"][()]
    except KeyError as exc:
        raise NNMFileError(f"{path}: /model/{GROUP} is incomplete ({exc})") from None
    out, a, b, c, k = [], 0, 0, 0, 0
    try:
        for e, (nz, m, nd) in enumerate(sizes):
            D = None
            if has_dir[e]:
                cols = int(dcols[k])
                D = dirs[c:c + m * cols].reshape(m, cols)
                c += m * cols
                k += 1
            el = PolynomialStiffness(ex[a:a + nz * m].reshape(nz, m), co[a:a + nz * m].reshape(nz, m),
                                     dofs=None if nd == 0 else [int(v) for v in dofs[b:b + nd]], directions=D)
            a += nz * m
            b += nd
            out.append((int(pos[e]), el))
    except (ValueError, IndexError, NNMInputError) as exc:
        raise NNMFileError(f"{path}: /model/{GROUP} element {len(out) + 1} is not valid ({exc})") from None
    if a != len(ex) or b != len(dofs) or c != len(dirs) or len(pos) != len(sizes):
        raise NNMFileError(f"{path}: /model/{GROUP} arrays do not match its sizes")
    return out


def merge(scalar, coupled, path):
    """The element list: the coupled elements at their positions, the scalar springs in order elsewhere."""
    n = len(scalar) + len(coupled)
    out = [None] * n
    for p, e in coupled:
        if not 0 <= p < n or out[p] is not None:
            raise NNMFileError(f"{path}: /model/{GROUP}/position {p} is not a free place among {n} elements")
        out[p] = e
    rest = iter(scalar)
    return [e if e is not None else next(rest) for e in out]
