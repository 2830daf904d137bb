"""Nastran matrices: OUTPUT4 ``.op4`` files (ASCII or binary) and the matrices of an ``.op2``, read by pyNastran.

An optional extra: ``pip install "nnm[nastran]"`` (pyNastran).  Nastran writes the reduced matrices with DMAP
in a SOL 103 run, e.g. (docs/import.md)::

    ASSIGN OUTPUT4='model.op4', UNIT=30, FORMATTED     $ or UNFORMATTED for a binary file
    COMPILE SEMG
    ALTER 'KGG.*MGG.*KGGX.*'(,1)  $ (or after the a-set reduction, for KAA/MAA)
    OUTPUT4 KAA,MAA,,,//-1/30/-1/0/16 $ -1: rewind, 30: unit, -1 dense, 16 digits

The stiffness and mass are found by name (default KAA and MAA; ``stiffness = "KGG"``, ``mass = "MGG"`` for
others).  The a-set's DOF order is Nastran's: ascending grid ID, then component 1..6 (T1, T2, T3, R1, R2,
R3), so a DOF map follows from the bulk data's ASET/ASET1 cards (``dof_map = "model.bdf"``, read here) or
from a text file of 'grid component' lines (``dof_map = "dofs.txt"``, common.py); components 1..6 are the
directions ux..rz.  Symmetric forms (6) are stored whole by OUTPUT4; a triangle is mirrored.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...errors import NNMFileError, NNMInputError
from .common import DIRECTIONS, DofMap, existing

EXTRA = 'pip install "nnm[nastran]" (pyNastran)'
SUFFIXES = (".op4", ".op2")
#: default matrix names: the a-set stiffness and mass
DEFAULT_NAMES = ("KAA", "MAA")

__all__ = ["read_nastran", "load_nastran_model", "read_aset_map", "SUFFIXES", "DEFAULT_NAMES"]


def _matrices(path):
    """{NAME: matrix} of an .op4 or .op2 file (dense arrays or scipy.sparse)."""
    try:
        import pyNastran  # noqa: F401
    except ImportError as exc:
        raise NNMInputError(f"{path}: reading Nastran files needs the optional package pyNastran: {EXTRA} "
                            f"({exc})") from None
    import logging

    quiet = logging.getLogger("nnm.nastran")
    quiet.setLevel(logging.ERROR)
    try:
        if path.suffix.lower() == ".op2":
            from pyNastran.op2.op2 import OP2

            op2 = OP2(log=quiet, debug=False)
            op2.read_op2(str(path), skip_undefined_matrices=False)
            found = op2.matrices
        else:
            from pyNastran.op4.op4 import read_op4

            with _fixed_width_op4(path) as readable:
                found = read_op4(str(readable), precision="double", log=quiet)
    except NNMFileError:
        raise
    except Exception as exc:           # pyNastran raises many kinds on a damaged or foreign file
        kind = "OUTPUT2 (.op2)" if path.suffix.lower() == ".op2" else "OUTPUT4 (.op4)"
        msg = str(exc).splitlines()[0] if str(exc) else ""
        raise NNMFileError(f"{path}: not a readable Nastran {kind} file ({exc.__class__.__name__}: {msg[:120]})") from None
    return {str(k).strip().upper(): getattr(v, "data", v) for k, v in found.items()}


#: a value of a FORMATTED OUTPUT4 file: mantissa, then an exponent with its E (E-05, E-306) or without it
#: (Fortran's E23.16 drops the E of a three-digit exponent: 1.0000000000000000-305)
_VALUE = re.compile(r"([+-]?\d\.\d+)(?:E([+-]\d{3})|([+-]\d{3}))(?![\d.])", re.IGNORECASE)
_SMALLEST = 1e-99


def _three_digit(match, path):
    """The 23-character field of a value with a three-digit exponent: 0 below 1e-99 (an entry that small is a
    round-off zero of the matrix), else a one-line error."""
    value = float(f"{match.group(1)}E{match.group(2) or match.group(3)}")
    if abs(value) >= _SMALLEST:
        raise NNMFileError(f"{path}: value {match.group(0)} is beyond the range of a FORMATTED OUTPUT4 field; "
                           f"write the matrices UNFORMATTED (binary)")
    # the field is 23 characters: ' 1.0000000000000000-305' (the match is 22 of them), '-1.0000000000000000-305'
    # or '1.0000000000000000E-305' (23), '-1.0000000000000000E-305' (24: one too many)
    return f"{0.0:23.16E}"[-min(len(match.group(0)), 23):]


class _fixed_width_op4:
    """Context manager: the path of a FORMATTED .op4 pyNastran can read.  Values below 1e-99 have three-digit
    exponents that do not fit the 23-character fields of 1P,3E23.16 (Nastran writes 1.0000000000000000-305, some
    writers 1.0000000000000000E-305, which overflows the field when negative and confuses pyNastran's reader);
    they are written as 0 into a temporary copy, read, and the copy deleted.  Binary files and files without such values are read as they are."""

    def __init__(self, path):
        self.path, self.copy = path, None

    def __enter__(self):
        with open(self.path, "rb") as fh:
            head = fh.read(4096)
        if b"\0" in head:                                   # binary (UNFORMATTED): ints hold zero bytes
            return self.path
        try:
            text = self.path.read_text()
        except UnicodeDecodeError:
            return self.path
        if not _VALUE.search(text):
            return self.path
        import tempfile

        fixed = _VALUE.sub(lambda m: _three_digit(m, self.path), text)
        fd, name = tempfile.mkstemp(suffix=".op4")
        with open(fd, "w") as fh:
            fh.write(fixed)
        self.copy = Path(name)
        return self.copy

    def __exit__(self, *exc):
        if self.copy is not None:
            self.copy.unlink(missing_ok=True)
        return False


def _square(A, name, path):
    if sp.issparse(A):
        A = sp.csr_matrix(A)
    else:
        A = np.asarray(A)
    if np.iscomplexobj(A.data if sp.issparse(A) else A):
        raise NNMFileError(f"{path}: matrix {name} is complex; give the real stiffness and mass")
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise NNMFileError(f"{path}: matrix {name} is {A.shape[0]}x{A.shape[1]}, not square")
    A = A.astype(float)
    lower = sp.tril(A, -1).nnz if sp.issparse(A) else np.count_nonzero(np.tril(A, -1))
    upper = sp.triu(A, 1).nnz if sp.issparse(A) else np.count_nonzero(np.triu(A, 1))
    if (lower == 0) != (upper == 0):          # one triangle stored: mirror it
        A = A + (A.T - (sp.diags(A.diagonal()) if sp.issparse(A) else np.diag(np.diag(A))))
    return A


def read_nastran(path, stiffness=DEFAULT_NAMES[0], mass=DEFAULT_NAMES[1]):
    """(M, K) of a Nastran .op4/.op2 file, the matrices named ``mass`` and ``stiffness`` (case-insensitive)."""
    path = existing(path, "Nastran matrix file")
    if path.suffix.lower() not in SUFFIXES:
        raise NNMInputError(f"{path}: Nastran matrices are read from {' or '.join(SUFFIXES)} files")
    found = _matrices(path)
    out = []
    for name in (str(mass).upper(), str(stiffness).upper()):
        if name not in found:
            raise NNMFileError(f"{path}: no matrix {name} (the file holds {', '.join(sorted(found)) or 'none'}); "
                               f"name them with stiffness = \"...\" and mass = \"...\"")
        out.append(_square(found[name], name, path))
    M, K = out
    if M.shape != K.shape:
        raise NNMFileError(f"{path}: {mass} is {M.shape[0]}x{M.shape[0]} but {stiffness} is {K.shape[0]}x{K.shape[0]}")
    return M, K


_FIELD = re.compile(r"\s*,\s*")


def _bulk_cards(text):
    """(name, fields) of each small-field or free-field bulk data card, continuations joined.  The card's first field
    keeps its place when blank ('' : an XSET1's blank component, e.g. 'QSET1,,1001,THRU,1003'); the other blank
    fields are dropped."""
    cards = []
    for raw in text.splitlines():
        line = raw.split("$")[0].rstrip()
        if not line.strip():
            continue
        if "," in line:
            fields = _FIELD.split(line.strip())
        else:
            fields = [line[i:i + 8].strip() for i in range(0, min(len(line), 72), 8)]
        head = fields[0]
        if head.startswith("+") or head == "" or head.startswith("*"):
            if cards:
                cards[-1][1].extend(f for f in fields[1:] if f != "")
            continue
        cards.append((head.upper(), fields[1:2] + [f for f in fields[2:] if f != ""]))
    return cards


def _set_dofs(name, fields):
    """{(id, component)} of an ASET/ASET1/QSET/QSET1 card; component 0 is a scalar point (SPOINT)."""
    if name.endswith("1"):                                  # XSET1 C G1 G2 ... | C G1 THRU G2
        comps, ids = fields[0], fields[1:]
        if len(ids) == 3 and ids[1].upper() == "THRU":
            ids = range(int(ids[0]), int(ids[2]) + 1)
        return {(int(g), int(c)) for g in ids for c in comps}
    return {(int(g), int(c)) for g, cs in zip(fields[::2], fields[1::2]) for c in cs}   # XSET G C [G C ...]


def read_aset_map(path):
    """DofMap of the a-set from the bulk data's ASET/ASET1 and QSET/QSET1 cards, in Nastran's a-set order
    (ascending grid or scalar point ID, then component).  ASET1 C G1 G2 ... (or G1 THRU G2); ASET G C [G C ...];
    QSET/QSET1 alike for a superelement's modal coordinates (the q-set is part of the a-set).  A grid's
    components 1..6 are ux..rz (in its displacement system CD); a scalar point (SPOINT, component 0 or blank) is
    "modal" when it is in the q-set, else "scalar" (labels 'spoint 1001 modal')."""
    path = existing(path, "Nastran bulk data file")
    try:
        text = path.read_text(errors="strict")
    except UnicodeDecodeError:
        raise NNMFileError(f"{path}: not a text (bulk data) file") from None
    aset, qset = set(), set()
    try:
        for name, fields in _bulk_cards(text):
            if name in ("ASET", "ASET1", "QSET", "QSET1"):
                if name.endswith("1") and fields and fields[0] == "":   # a blank component: a scalar point's 0
                    fields = ["0"] + fields[1:]
                (qset if name.startswith("Q") else aset).update(_set_dofs(name, fields))
    except (ValueError, IndexError):
        raise NNMFileError(f"{path}: an ASET/QSET card is not 'ASET1, components, grid, ...' or 'ASET, grid, "
                           f"components, ...'") from None
    if not aset and not qset:
        raise NNMFileError(f"{path}: no ASET, ASET1, QSET or QSET1 card; the DOF map of KAA needs the a-set (or "
                           f"give a text file of 'grid component' lines)")
    dofs = aset | qset
    if any(not 0 <= c <= 6 for _, c in dofs):
        raise NNMFileError(f"{path}: ASET/QSET components must be digits 1..6 (0 for a scalar point)")
    scalar = {g for g, c in dofs if c == 0}
    if scalar & {g for g, c in dofs if c != 0}:
        g = min(scalar & {g for g, c in dofs if c != 0})
        raise NNMFileError(f"{path}: ID {g} is given as a scalar point (component 0) and as a grid (components 1..6)")
    return DofMap([(g, ("modal" if (g, c) in qset else "scalar") if c == 0 else DIRECTIONS[c - 1])
                   for g, c in sorted(dofs)])


def dof_map_of(path, n, where=""):
    """The DofMap named by ``dof_map`` of a description: a bulk data file (.bdf, .dat, .blk, .nas: ASET cards)
    or a text file of 'grid component' lines; its length must be n."""
    from .common import read_dof_map_file

    path = Path(path)
    bulk = path.suffix.lower() in (".bdf", ".dat", ".blk", ".nas", ".bulk")
    dmap = read_aset_map(path) if bulk else read_dof_map_file(path, where)
    if len(dmap) != n:
        raise NNMFileError(f"{path}: {len(dmap)} DOFs listed, the matrices have {n}")
    return dmap


def read_nastran_table(mt, folder, where):
    """(M, K, dof_map or None, "nastran", []) of a description's [matrices] table with format = "nastran"."""
    extra = sorted(set(mt) - {"format", "file", "stiffness", "mass", "dof_map"})
    if extra:
        raise NNMInputError(f"{where}: unknown key(s) {', '.join(extra)} for Nastran matrices (file, stiffness, "
                            f"mass, dof_map)")
    if "file" not in mt:
        raise NNMInputError(f"{where}: Nastran matrices need file = \"model.op4\" (or .op2); stiffness and mass "
                            f"name the matrices in it (default KAA, MAA)")
    M, K = read_nastran(existing(folder / str(mt["file"]), f"{where} file"), str(mt.get("stiffness", DEFAULT_NAMES[0])),
                        str(mt.get("mass", DEFAULT_NAMES[1])))
    dmap = None if "dof_map" not in mt else dof_map_of(folder / str(mt["dof_map"]), M.shape[0], f"{where} dof_map: ")
    return M, K, dmap, "nastran", []


def load_nastran_model(path, name=None):
    """Linear Model of the KAA, MAA matrices of a Nastran .op4/.op2 file (no springs: give them, other matrix
    names and a DOF map in a model description file)."""
    from ...model.model import Model

    M, K = read_nastran(path)
    try:
        return Model(M, K, [], name=name or Path(path).stem, info={"source": Path(path).name, "format": "nastran"})
    except NNMInputError as exc:
        raise NNMFileError(f"{path}: {exc}") from None
