"""What every importer shares: the DOF map (node, direction), units, and one-line file errors.

A DOF map says which node and direction each model DOF is: ``dof_map[i] = (node, direction)``
with node an int (or a string label, e.g. an Abaqus instance node) and direction one of
``DIRECTIONS`` (or ``"dof<k>"`` for a degree of freedom with no name).  Models keep it as their
``dof_labels`` (``"node 12 uz"``), so it survives the nnm HDF5 file and is found again by
``DofMap.from_labels``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError

#: direction names, in the order FE codes number them (Abaqus 1..6, ANSYS UX..ROTZ)
DIRECTIONS = ("ux", "uy", "uz", "rx", "ry", "rz")

_ALIASES = {"x": "ux", "y": "uy", "z": "uz", "u1": "ux", "u2": "uy", "u3": "uz",
            "rotx": "rx", "roty": "ry", "rotz": "rz", "ur1": "rx", "ur2": "ry", "ur3": "rz"}

#: directions of a Nastran scalar point (SPOINT, component 0): "modal" for the modal coordinates of a superelement
#: (its q-set: QSET/QSET1), "scalar" for any other; their labels read "spoint 1001 modal"
SCALAR_DIRECTIONS = ("modal", "scalar")

_LABEL = re.compile(r"^(node|spoint) (\S+) (\S+)$")


def direction_name(d, where=""):
    """Canonical direction name of ``d``: 'ux'..'rz' (also x/y/z, UX, ROTX, U1, UR1, or 1..6), or 'dof<k>'."""
    if isinstance(d, (int, np.integer)) and not isinstance(d, bool):
        if 1 <= d <= 6:
            return DIRECTIONS[d - 1]
        if d > 6:
            return f"dof{int(d)}"
    elif isinstance(d, str):
        s = d.strip().lower()
        if s in DIRECTIONS:
            return s
        if s in _ALIASES:
            return _ALIASES[s]
        if s in SCALAR_DIRECTIONS:
            return s
        if s.isdigit():
            return direction_name(int(s), where)
        if re.fullmatch(r"dof\d+", s):
            return s
    raise NNMInputError(f"{where}direction {d!r} is not one of {', '.join(DIRECTIONS)} (or 1..6)")


def is_rotation(direction):
    return direction in ("rx", "ry", "rz")


def node_key(node):
    """Node labels are ints where they look like ints (12, '12'), else strings ('Part-1-1.12')."""
    if isinstance(node, (int, np.integer)) and not isinstance(node, bool):
        return int(node)
    s = str(node).strip()
    return int(s) if re.fullmatch(r"[+-]?\d+", s) else s


def _sort_key(node):
    return (0, node, "") if isinstance(node, int) else (1, 0, node)


def sort_nodes(nodes):
    return sorted(nodes, key=_sort_key)


@dataclass
class DofMap:
    """(node, direction) of each model DOF."""

    entries: list

    def __post_init__(self):
        self.entries = [(node_key(n), str(d)) for n, d in self.entries]
        self._index = {e: i for i, e in enumerate(self.entries)}
        if len(self._index) != len(self.entries):
            dup = next(e for i, e in enumerate(self.entries) if self._index[e] != i)
            raise NNMInputError(f"the DOF map lists node {dup[0]} {dup[1]} twice")

    def __len__(self):
        return len(self.entries)

    def labels(self):
        """'node 12 uz' for a node's DOF, 'spoint 1001 modal' for a scalar point (SCALAR_DIRECTIONS)."""
        return [f"{'spoint' if d in SCALAR_DIRECTIONS else 'node'} {n} {d}" for n, d in self.entries]

    @property
    def nodes(self):
        """Node labels in ascending order."""
        return sort_nodes({n for n, _ in self.entries})

    def index(self, node, direction, where=""):
        """0-based DOF index of (node, direction); one-line NNMInputError if the model has no such DOF."""
        key = (node_key(node), direction_name(direction, where))
        if key not in self._index:
            nodes = {n for n, _ in self.entries}
            if key[0] not in nodes:
                raise NNMInputError(f"{where}node {key[0]} is not a node of the model ({len(nodes)} nodes with DOFs, "
                                    f"e.g. {', '.join(map(str, sort_nodes(nodes)[:4]))}; a fully constrained node "
                                    f"has none)")
            have = [d for n, d in self.entries if n == key[0]]
            raise NNMInputError(f"{where}node {key[0]} has no DOF {key[1]} in the model "
                                f"(its DOFs: {', '.join(have)}; constrained DOFs are not model DOFs)")
        return self._index[key]

    def get(self, node, direction):
        return self._index.get((node_key(node), direction))

    def modal(self):
        """Boolean (n,): True where the DOF is a modal coordinate (a superelement's q-set scalar point)."""
        return np.array([d == "modal" for _, d in self.entries], dtype=bool)

    def rotations(self):
        """Boolean (n,): True where the DOF is a rotation."""
        return np.array([is_rotation(d) for _, d in self.entries], dtype=bool)

    @classmethod
    def from_labels(cls, labels):
        """The DOF map written into ``dof_labels`` by an importer ('node 12 uz'), or None."""
        if not labels:
            return None
        entries = []
        for s in labels:
            m = _LABEL.match(str(s))
            if not m:
                return None
            if (m.group(1) == "spoint") != (m.group(3) in SCALAR_DIRECTIONS):
                return None
            entries.append((m.group(2), m.group(3)))
        try:
            return cls(entries)
        except NNMInputError:
            return None


def read_dof_map_file(path, where=""):
    """A DOF map from a text file: one line per model DOF, 'node direction' (comma or blank separated)."""
    path = existing(path, where)
    entries = []
    for lineno, line in enumerate(path.read_text().splitlines(), 1):
        line = line.split("#")[0].strip()
        if not line:
            continue
        parts = [p for p in re.split(r"[,\s]+", line) if p]
        if len(parts) != 2:
            raise NNMFileError(f"{path} line {lineno}: expected 'node direction', got {line!r}")
        entries.append((parts[0], direction_name(parts[1], f"{path} line {lineno}: ")))
    try:
        return DofMap(entries)
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None


def existing(path, where=""):
    """Path to an existing file, or a one-line NNMFileError naming who asked for it."""
    path = Path(path)
    if not path.is_file():
        raise NNMFileError(f"{path}: no such file{' (' + where.rstrip(': ') + ')' if where else ''}")
    return path


def as_csr(A):
    return A.tocsr().astype(float) if sp.issparse(A) else sp.csr_matrix(np.asarray(A, dtype=float))


def symmetric_from_storage(A, path):
    """A symmetric matrix from entries given as one triangle (mirrored) or as both (kept).

    FE codes write symmetric matrices as one triangle, in their own equation order, which need not be
    the order of our DOF map: a matrix is treated as triangular storage when no off-diagonal entry
    has its transpose stored.
    """
    A = sp.coo_matrix(A)
    A.sum_duplicates()
    off = A.row != A.col
    if not np.any(off):
        return A.tocsr()
    keys = set(zip(A.row[off].tolist(), A.col[off].tolist()))
    paired = sum((c, r) in keys for r, c in keys)
    if paired == 0:
        D = sp.coo_matrix((A.data[~off], (A.row[~off], A.col[~off])), shape=A.shape)
        O = sp.coo_matrix((A.data[off], (A.row[off], A.col[off])), shape=A.shape)
        return (D + O + O.T).tocsr()
    if paired != len(keys):
        r, c = next((r, c) for r, c in keys if (c, r) not in keys)
        raise NNMFileError(f"{path}: entry ({r + 1}, {c + 1}) has no symmetric partner while others do; "
                           f"give one triangle or the whole symmetric matrix")
    return A.tocsr()


# ---------------------------------------------------------------------- units
LENGTH = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254, "ft": 0.3048}
MASS = {"kg": 1.0, "g": 1e-3, "t": 1e3, "tonne": 1e3, "lbm": 0.45359237, "slug": 14.593902937206364,
        "slinch": 175.12683524647636, "lbf*s^2/in": 175.12683524647636}
TIME = {"s": 1.0, "ms": 1e-3}
#: consistent unit systems by name: (length, mass, time); force and energy follow
SYSTEMS = {"si": ("m", "kg", "s"), "m-kg-s": ("m", "kg", "s"), "mm-t-s": ("mm", "t", "s"),
           "mm-kg-ms": ("mm", "kg", "ms"), "in-lbf-s": ("in", "slinch", "s"), "ft-lbf-s": ("ft", "slug", "s")}


@dataclass(frozen=True)
class Units:
    """A consistent unit system (length, mass, time); force = mass length / time^2."""

    length: str = "m"
    mass: str = "kg"
    time: str = "s"

    @classmethod
    def parse(cls, spec, where=""):
        """From 'SI', 'mm-t-s', ... or a table {length, mass, time}."""
        if spec is None:
            return cls()
        if isinstance(spec, str):
            key = spec.strip().lower()
            if key not in SYSTEMS:
                raise NNMInputError(f"{where}unknown units {spec!r}; known systems: "
                                    f"{', '.join(['SI'] + [s for s in SYSTEMS if s != 'si'])}, "
                                    f"or a table {{length, mass, time}}")
            return cls(*SYSTEMS[key])
        if isinstance(spec, dict):
            extra = set(spec) - {"length", "mass", "time"}
            if extra:
                raise NNMInputError(f"{where}[units] has unknown key(s) {', '.join(sorted(extra))}; "
                                    f"known: length, mass, time")
            u = cls(str(spec.get("length", "m")), str(spec.get("mass", "kg")), str(spec.get("time", "s")))
            for kind, table, value in (("length", LENGTH, u.length), ("mass", MASS, u.mass), ("time", TIME, u.time)):
                if value not in table:
                    raise NNMInputError(f"{where}unknown {kind} unit {value!r}; known: {', '.join(table)}")
            return u
        raise NNMInputError(f"{where}units must be a name (e.g. 'SI', 'mm-t-s') or a table, got {spec!r}")

    @property
    def is_si(self):
        return (self.length, self.mass, self.time) == ("m", "kg", "s")

    @property
    def L(self):
        return LENGTH[self.length]

    @property
    def energy(self):
        """Joules per energy unit (mass length^2 / time^2)."""
        return MASS[self.mass] * LENGTH[self.length] ** 2 / TIME[self.time] ** 2

    def __str__(self):
        for name, sysu in SYSTEMS.items():
            if sysu == (self.length, self.mass, self.time):
                return "SI" if name == "si" else name
        return f"{self.length}-{self.mass}-{self.time}"

    def dof_scale(self, rotations):
        """Metres (or radians) per file unit of each DOF: L for translations, 1 for rotations."""
        return np.where(np.asarray(rotations, dtype=bool), 1.0, self.L)

    def to_si(self, M, K, rotations):
        """(M, K) in SI from file units; ``rotations`` (n,) bool tells rotations from translations."""
        if self.is_si:
            return M, K
        s = 1.0 / self.dof_scale(rotations)

        def convert(A, factor):
            if sp.issparse(A):
                D = sp.diags(s)
                return (D @ A @ D).tocsr() * factor
            return np.asarray(A, dtype=float) * np.outer(s, s) * factor

        return convert(M, MASS[self.mass] * self.L ** 2), convert(K, self.energy)

    def coefficient_scale(self, rotation):
        """Factor taking a force-law coefficient c_p (d^p term) from file units to SI: E / s^(p+1)."""
        s = 1.0 if rotation else self.L
        return lambda p: self.energy / s ** (p + 1)
