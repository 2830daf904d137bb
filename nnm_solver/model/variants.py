"""Model variants: named changes of a model's parameters (for parameter sweeps, ``nnm.sweep``).

A ``Variant`` is a named change of a model's parameters:

* ``spring_factor``: multiplies every spring's force (one number, or one number per spring);
* ``added_stiffness``: linear springs added to K, ``(dof, k)`` to ground or ``(dof, other, k)``
  between two DOFs (k in N/m; e.g. a stiffer or softer attachment);
* ``mass_factor`` (with ``mass_dofs``): scales the mass at those DOFs (all DOFs if none), as
  ``M' = S M S`` with ``S = diag(sqrt(factor))`` on those DOFs, so a lumped mass is multiplied by
  the factor and M stays symmetric positive definite (e.g. a fuller or emptier tank).

``variant_grid`` makes every combination of lists of values (the TOML sweep file that gives the same:
``sweeps/spec.py``, docs/sweep.md).  Variant names are part of the branch names in a sweep's file
(``<variant>:mode<N>``), so they contain neither ``/`` nor ``:``.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import NNMInputError, finite_number

__all__ = ["Variant", "variant_grid"]


def _finite(name, value):
    return finite_number(value, name)


def _dof(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise NNMInputError(f"{name} must be a DOF index (integer >= 0, 0-based), got {value!r}")
    return int(value)


@dataclass(frozen=True)
class Variant:
    """A named change of a model: spring factor, added linear stiffness, mass scaling.

    name : label (default: made from the non-default values, "base" when there are none).
    spring_factor : number, or tuple with one number per spring, multiplying the springs' forces.
    added_stiffness : tuple of ``(dof, k)`` (to ground) or ``(dof, other, k)`` (between two DOFs), k in N/m.
    mass_factor : scales the mass at ``mass_dofs`` (all DOFs when empty).
    """

    name: str = ""
    spring_factor: float | tuple = 1.0
    added_stiffness: tuple = ()
    mass_factor: float = 1.0
    mass_dofs: tuple = field(default=())

    def __post_init__(self):
        sf = self.spring_factor
        if isinstance(sf, (list, tuple, np.ndarray)):
            sf = tuple(_finite(f"spring_factor[{i}]", f) for i, f in enumerate(sf))
        else:
            sf = _finite("spring_factor", sf)
        added = []
        for i, entry in enumerate(self.added_stiffness):
            entry = tuple(entry)
            if len(entry) == 2:
                added.append((_dof(f"added_stiffness[{i}] dof", entry[0]), _finite(f"added_stiffness[{i}] k", entry[1])))
            elif len(entry) == 3:
                d, o = _dof(f"added_stiffness[{i}] dof", entry[0]), _dof(f"added_stiffness[{i}] other", entry[1])
                if d == o:
                    raise NNMInputError(f"added_stiffness[{i}]: dof and other are both {d}")
                added.append((d, o, _finite(f"added_stiffness[{i}] k", entry[2])))
            else:
                raise NNMInputError(f"added_stiffness[{i}] must be (dof, k) or (dof, other, k), got {entry!r}")
        mf = _finite("mass_factor", self.mass_factor)
        if mf <= 0:
            raise NNMInputError(f"mass_factor must be positive, got {mf!r}")
        dofs = tuple(_dof(f"mass_dofs[{i}]", d) for i, d in enumerate(self.mass_dofs))
        object.__setattr__(self, "spring_factor", sf)
        object.__setattr__(self, "added_stiffness", tuple(added))
        object.__setattr__(self, "mass_factor", mf)
        object.__setattr__(self, "mass_dofs", dofs)
        name = str(self.name).strip() or self._label()
        if "/" in name or ":" in name or name.startswith("."):
            raise NNMInputError(f"variant name {name!r} may not contain '/' or ':' nor start with '.'")
        object.__setattr__(self, "name", name)

    def _label(self):
        parts = []
        sf = self.spring_factor
        if isinstance(sf, tuple):
            parts.append("springs[" + ",".join(f"{f:g}" for f in sf) + "]")
        elif sf != 1.0:
            parts.append(f"springs{sf:g}")
        if self.added_stiffness:
            ks = {e[-1] for e in self.added_stiffness}
            where = ",".join("-".join(str(d) for d in e[:-1]) for e in self.added_stiffness)
            parts.append(f"k{ks.pop():g}@{where}" if len(ks) == 1 else
                         "k[" + ",".join(f"{e[-1]:g}@{'-'.join(str(d) for d in e[:-1])}" for e in self.added_stiffness) + "]")
        if self.mass_factor != 1.0:
            parts.append(f"mass{self.mass_factor:g}" + ("@" + ",".join(map(str, self.mass_dofs)) if self.mass_dofs else ""))
        return "_".join(parts) or "base"

    @property
    def is_identity(self):
        """True when the variant leaves the model unchanged."""
        return (self.spring_factor == 1.0 and all(e[-1] == 0.0 for e in self.added_stiffness)
                and self.mass_factor == 1.0)

    def apply(self, model):
        """The varied Model (the model itself when nothing changes); NNMInputError if it does not fit."""
        if self.is_identity:
            return model
        n = model.n
        sf = self.spring_factor
        if isinstance(sf, tuple):
            if len(sf) != len(model.springs):
                raise NNMInputError(f"variant {self.name!r}: spring_factor has {len(sf)} values but the model has "
                                    f"{len(model.springs)} springs")
            springs = [s.scaled(f) for s, f in zip(model.springs, sf)]
        else:
            springs = [s.scaled(sf) for s in model.springs] if sf != 1.0 else list(model.springs)
        dofs = [d for e in self.added_stiffness for d in e[:-1]] + list(self.mass_dofs)
        bad = [d for d in dofs if d >= n]
        if bad:
            raise NNMInputError(f"variant {self.name!r}: DOF {bad[0]} is not a DOF of this model (valid: 0..{n - 1})")
        K = model.K
        if any(e[-1] != 0.0 for e in self.added_stiffness):
            rows, cols, vals = [], [], []
            for e in self.added_stiffness:
                k = e[-1]
                if len(e) == 2:
                    rows.append(e[0]); cols.append(e[0]); vals.append(k)
                else:
                    d, o = e[0], e[1]
                    rows += [d, o, d, o]; cols += [d, o, o, d]; vals += [k, k, -k, -k]
            delta = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
            K = (K + delta).tocsr() if sp.issparse(K) else K + delta.toarray()
        M = model.M
        if self.mass_factor != 1.0:
            f = np.ones(n)
            f[list(self.mass_dofs) if self.mass_dofs else slice(None)] = self.mass_factor
            if sp.issparse(M):   # entry (i, j) times sqrt(f_i f_j): exactly f on the diagonal
                C = M.tocoo()
                M = sp.csr_matrix((C.data * np.sqrt(f[C.row] * f[C.col]), (C.row, C.col)), shape=C.shape)
            else:
                M = M * np.sqrt(np.outer(f, f))
        from .model import Model

        info = dict(model.info)
        info["variant"] = self.name
        return Model(M, K, springs, dof_labels=model.dof_labels, mode_labels=model.mode_labels, mesh=model.mesh,
                     name=f"{model.name} [{self.name}]" if model.name else self.name, info=info)

    def as_dict(self):
        """Plain dict (JSON/TOML values) that ``Variant.from_dict`` reads back."""
        sf = self.spring_factor
        return {"name": self.name, "spring_factor": list(sf) if isinstance(sf, tuple) else sf,
                "added_stiffness": [list(e) for e in self.added_stiffness], "mass_factor": self.mass_factor,
                "mass_dofs": list(self.mass_dofs)}

    @classmethod
    def from_dict(cls, d, where="variant"):
        unknown = set(d) - {"name", "spring_factor", "added_stiffness", "mass_factor", "mass_dofs"}
        if unknown:
            raise NNMInputError(f"{where}: unknown key(s) {sorted(unknown)}; known: name, spring_factor, "
                                f"added_stiffness, mass_factor, mass_dofs")
        return cls(**d)


def variant_grid(spring_factor=(1.0,), stiffness=(0.0,), stiffness_dofs=(), mass_factor=(1.0,), mass_dofs=()):
    """Every combination of the given values (lists), as Variants in that nested order.

    spring_factor : factors on every spring (or tuples, one factor per spring);
    stiffness : N/m added to ground at each DOF of ``stiffness_dofs`` (0 adds nothing);
    mass_factor : factors on the mass at ``mass_dofs`` (all DOFs when empty).
    """
    def values(name, v):
        v = list(v) if isinstance(v, (list, tuple, np.ndarray)) else [v]
        if not v:
            raise NNMInputError(f"grid {name} is empty; give at least one value")
        return v

    sfs, ks, mfs = values("spring_factor", spring_factor), values("stiffness", stiffness), values("mass_factor", mass_factor)
    if any(_finite("stiffness", k) != 0.0 for k in ks) and not len(stiffness_dofs):
        raise NNMInputError("grid stiffness needs stiffness_dofs (the DOFs the stiffness is added at)")
    out = []
    for sf, k, mf in itertools.product(sfs, ks, mfs):
        added = tuple((d, k) for d in stiffness_dofs) if _finite("stiffness", k) != 0.0 else ()
        out.append(Variant(spring_factor=tuple(sf) if isinstance(sf, (list, tuple)) else sf, added_stiffness=added,
                           mass_factor=mf, mass_dofs=tuple(mass_dofs)))
    return out
