"""Model variants for parameter sweeps, and the TOML sweep file.

A ``Variant`` is a named change of a model's parameters:

* ``spring_factor``: multiplies every spring's force (one number, or one number per spring);
* ``added_stiffness``: linear springs added to K, ``(dof, k)`` to ground or ``(dof, other, k)``
  between two DOFs (k in N/m; e.g. a stiffer or softer attachment);
* ``mass_factor`` (with ``mass_dofs``): scales the mass at those DOFs (all DOFs if none), as
  ``M' = S M S`` with ``S = diag(sqrt(factor))`` on those DOFs, so a lumped mass is multiplied by
  the factor and M stays symmetric positive definite (e.g. a fuller or emptier tank).

``variant_grid`` makes every combination of lists of values; ``load_sweep_file`` reads the same from
a small TOML file (format in docs/sweep.md)::

    modes = "10-24"            # optional: the command line's --modes wins
    energy_max = 100.0         # optional: --energy-max wins
    [options]                  # continue_nnm keywords
    max_points = 150
    [grid]                     # every combination
    spring_factor = [0.5, 1.0, 2.0]
    stiffness = [0.0, 1e6]     # N/m added to ground at each of stiffness_dofs
    stiffness_dofs = [12, 40]
    [[variant]]                # and/or variants one by one
    name = "heavy-tanks"
    mass_factor = 1.3
    mass_dofs = [3, 4]

Variant names are part of the branch names in a sweep's file (``<variant>:mode<N>``), so they
contain neither ``/`` nor ``:``.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from .errors import NNMInputError, finite_number

__all__ = ["Variant", "variant_grid", "as_variants", "parse_modes", "SweepSpec", "load_sweep_file"]


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


def as_variants(variants):
    """None, a Variant, a dict (Variant keywords) or a sequence of those -> list of Variants, names unique."""
    if variants is None:
        out = [Variant()]
    elif isinstance(variants, (Variant, dict)):
        out = [variants]
    else:
        try:
            out = list(variants)
        except TypeError:
            raise NNMInputError(f"variants must be None, a Variant or a list of Variants, got "
                                f"{type(variants).__name__}") from None
    out = [Variant.from_dict(v) if isinstance(v, dict) else v for v in out]
    for v in out:
        if not isinstance(v, Variant):
            raise NNMInputError(f"variants must be nnm_solver.Variant objects (or dicts), got {type(v).__name__}")
    if not out:
        raise NNMInputError("variants is empty; give None for the model as it is")
    names = [v.name for v in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise NNMInputError(f"variant names must be unique; repeated: {dup} (give each variant a name)")
    return out


def parse_modes(modes):
    """1-based mode numbers from an int, a sequence of ints, or a string such as "10-24" or "1,3,5-7"."""
    if isinstance(modes, str):
        out = []
        for part in modes.replace(" ", "").split(","):
            if not part:
                continue
            lo, sep, hi = part.partition("-")
            try:
                a, b = int(lo), int(hi) if sep else int(lo)
            except ValueError:
                raise NNMInputError(f"modes {modes!r}: {part!r} is not a mode number or a range like 10-24") from None
            if b < a:
                raise NNMInputError(f"modes {modes!r}: the range {part!r} is empty (write low-high)")
            out.extend(range(a, b + 1))
    elif isinstance(modes, (int, np.integer)) and not isinstance(modes, bool):
        out = [int(modes)]
    else:
        try:
            out = list(modes)
        except TypeError:
            raise NNMInputError(f"modes must be mode numbers (a list, a range or a string like '10-24'), "
                                f"got {modes!r}") from None
        for m in out:
            if isinstance(m, bool) or not isinstance(m, (int, np.integer)):
                raise NNMInputError(f"modes must be integers (1-based), got {m!r}")
        out = [int(m) for m in out]
    if not out:
        raise NNMInputError("no mode to compute: modes is empty")
    dup = sorted({m for m in out if out.count(m) > 1})
    if dup:
        raise NNMInputError(f"modes repeats {dup}")
    return out


@dataclass
class SweepSpec:
    """A TOML sweep file: variants, and optional modes, energy_max and continuation options."""

    variants: list
    modes: list | None = None
    energy_max: float | None = None
    options: dict = field(default_factory=dict)


_GRID_KEYS = {"spring_factor", "stiffness", "stiffness_dofs", "mass_factor", "mass_dofs"}


def load_sweep_file(path):
    """Read a TOML sweep file (module docstring, docs/sweep.md) into a SweepSpec."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        try:
            import tomli as tomllib
        except ModuleNotFoundError:
            raise NNMInputError("reading a TOML sweep file needs Python >= 3.11 (tomllib) or `pip install tomli`") from None
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise NNMInputError(f"sweep file {path} does not exist") from None
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise NNMInputError(f"sweep file {path} is not valid TOML: {exc}") from None
    unknown = set(data) - {"modes", "energy_max", "options", "grid", "variant"}
    if unknown:
        raise NNMInputError(f"{path}: unknown key(s) {sorted(unknown)}; known: modes, energy_max, [options], [grid], "
                            f"[[variant]]")
    variants = []
    if "grid" in data:
        grid = data["grid"]
        if not isinstance(grid, dict) or set(grid) - _GRID_KEYS:
            raise NNMInputError(f"{path}: [grid] takes {sorted(_GRID_KEYS)}, got {sorted(grid) if isinstance(grid, dict) else grid!r}")
        variants += variant_grid(**grid)
    for i, v in enumerate(data.get("variant", [])):
        if not isinstance(v, dict):
            raise NNMInputError(f"{path}: [[variant]] {i + 1} must be a table")
        variants.append(Variant.from_dict(v, where=f"{path}: [[variant]] {i + 1}"))
    modes = parse_modes(data["modes"]) if "modes" in data else None
    energy_max = _finite(f"{path}: energy_max", data["energy_max"]) if "energy_max" in data else None
    options = data.get("options", {})
    if not isinstance(options, dict):
        raise NNMInputError(f"{path}: [options] must be a table of continue_nnm keywords")
    return SweepSpec(variants=as_variants(variants or None), modes=modes, energy_max=energy_max, options=dict(options))
