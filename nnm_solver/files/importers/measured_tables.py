"""Measured records from CSV tables and MATLAB .mat files (measured.py holds the ``Measurement`` record).

CSV (``read_csv_measurement``): ``#`` comment lines, a header row (or, before numbers, the last comment
line, as ``numpy.savetxt(header=...)`` writes it), one row per sample; the first column is
the axis, named ``time``/``t`` or ``frequency``/``freq``/``f``; units in brackets after each name
(``time (s), node 14 uz (g), force [N]``); a pair of columns ``X re``, ``X im`` is one complex channel X.
A column without a unit is kept as written, quantity ``unknown``.  Separators: comma, semicolon or tab.

.mat (``read_mat_measurement``, v5 or v7.3): an axis ``t``/``time`` (s) or ``f``/``freq``/``frequency``
(Hz) -- or ``fs`` (Hz) / ``dt`` (s) for a time record starting at 0 -- and ``data`` (N x channels, or one
vector), else every numeric vector of the axis' length is a channel named after its variable; optional
cell arrays ``labels`` and ``units`` (one per channel, or one unit for all).
"""
from __future__ import annotations

import csv
import re

import numpy as np

from ...errors import NNMFileError, NNMInputError
from .common import existing
from .measured import build
from .measured_units import SI, SignalUnit, parse_unit

__all__ = ["read_csv_measurement", "read_mat_measurement"]


def _axis_kind(name, where):
    n = name.strip().lower()
    if n in ("t", "time"):
        return "time"
    if n in ("f", "freq", "frequency"):
        return "frequency"
    raise NNMFileError(f"{where}the first column is {name!r}; name it time (s) or frequency (Hz)")


def _split_unit(cell):
    m = re.fullmatch(r"\s*(.*?)\s*[\(\[]\s*([^\)\]]*)\s*[\)\]]\s*", cell)
    return (m.group(1), m.group(2)) if m else (cell.strip(), "")


def file_unit(text, where):
    """parse_unit for a unit stated in a file: an unknown unit is a bad file (NNMFileError, one line)."""
    try:
        return parse_unit(text, where)
    except NNMFileError:
        raise
    except NNMInputError as exc:
        raise NNMFileError(str(exc)) from None


def _axis_unit(kind, unit, where):
    if not unit:
        return SignalUnit(kind, SI[kind], 1.0)
    u = file_unit(unit, where)
    if u.quantity != kind:
        raise NNMFileError(f"{where}the {kind} axis is in {unit!r}, a unit of {u.quantity}")
    return u


def _numeric(line):
    try:
        [float(c) for c in re.split(r"[,;\t]", line)]
    except ValueError:
        return False
    return True


def read_csv_measurement(path):
    """Measurement from a CSV table (module doc)."""
    path = existing(path, "measured data")
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (UnicodeDecodeError, OSError) as exc:
        raise NNMFileError(f"{path}: not a readable text (CSV) file ({exc.__class__.__name__})") from None
    rows = [(i + 1, s) for i, s in enumerate(lines) if s.strip() and not s.lstrip().startswith("#")]
    comments = [(i + 1, s.lstrip()[1:]) for i, s in enumerate(lines) if s.lstrip().startswith("#")]
    if rows and comments and comments[-1][0] < rows[0][0] and _numeric(rows[0][1]):
        rows.insert(0, comments[-1])          # the header as numpy.savetxt writes it: the last comment line
    if len(rows) < 3:
        raise NNMFileError(f"{path}: a CSV record needs a header row and at least 2 data rows")
    first = rows[0][1]
    sep = max((",", ";", "\t"), key=first.count)
    table = [(no, next(csv.reader([s], delimiter=sep))) for no, s in rows]
    header = [c.strip() for c in table[0][1]]
    if len(header) < 2:
        raise NNMFileError(f"{path}: the header has {len(header)} column(s); give the axis and at least one channel")
    values = np.empty((len(table) - 1, len(header)))
    for r, (no, cells) in enumerate(table[1:]):
        if len(cells) != len(header):
            raise NNMFileError(f"{path} line {no}: {len(cells)} values for {len(header)} columns")
        for c, cell in enumerate(cells):
            try:
                values[r, c] = float(cell)
            except ValueError:
                raise NNMFileError(f"{path} line {no}: {cell.strip()!r} in column {header[c]!r} is not a number") \
                    from None
    where = f"{path}: "
    axis_name, axis_unit = _split_unit(header[0])
    kind = _axis_kind(axis_name, where)
    au = _axis_unit(kind, axis_unit, where)
    cols, names, units, stated = [], [], [], []
    parts = [_split_unit(h) for h in header[1:]]
    c = 0
    while c < len(parts):
        name, unit = parts[c]
        col = values[:, c + 1]
        base = re.sub(r"\s+(re|real)$", "", name, flags=re.I)
        if base != name and c + 1 < len(parts) and re.sub(r"\s+(im|imag)$", "", parts[c + 1][0], flags=re.I) == base:
            col, name, c = col + 1j * values[:, c + 2], base, c + 1
        c += 1
        u = file_unit(unit, f"{where}column {name!r}: ")
        if u.quantity in ("time", "frequency"):
            raise NNMFileError(f"{where}column {name!r} is in {unit!r}, a unit of {u.quantity}; only the first "
                               f"column is the axis")
        cols.append(col)
        names.append(name)
        units.append(u)
        stated.append(unit or "not stated")
    return build(kind, values[:, 0] * au.factor, cols, names, units, stated, path)


def _mat_strings(value):
    from .matlab import strings_of

    return strings_of(value)


def read_mat_measurement(path):
    """Measurement from a MATLAB .mat file, v5 or v7.3 (module doc)."""
    from .matlab import read_mat

    path = existing(path, "measured data")
    data = read_mat(path)
    where = f"{path}: "

    def vector(key):
        v = np.asarray(data[key])
        return v.ravel() if v.ndim <= 1 or min(v.shape) == 1 else None

    keys = {k.lower(): k for k in data}
    axis_key = next((keys[k] for k in ("t", "time", "f", "freq", "frequency") if k in keys), None)
    matrix = np.asarray(data[keys["data"]]) if "data" in keys else None
    special = {axis_key, keys.get("labels"), keys.get("units"), keys.get("fs"), keys.get("dt"), keys.get("data")}
    if axis_key is None:
        if not {"fs", "dt"} & set(keys):
            raise NNMFileError(f"{where}no axis: give a variable t or time (s), f or frequency (Hz), or fs (Hz) / "
                               f"dt (s)")
        if matrix is not None:
            n = len(matrix) if matrix.ndim == 1 or matrix.shape[0] >= matrix.shape[1] else matrix.shape[1]
        else:
            lengths = {len(vector(k)) for k in data if k not in special and vector(k) is not None}
            if len(lengths) != 1:
                raise NNMFileError(f"{where}with fs / dt the channels must be vectors of one length (found "
                                   f"{sorted(lengths) or 'none'}), or a matrix data")
            n = lengths.pop()
        step = np.ravel(data[keys["dt"]])[0] if "dt" in keys else 1.0 / np.ravel(data[keys["fs"]])[0]
        if not (np.isfinite(step) and step > 0):
            raise NNMFileError(f"{where}fs / dt must be positive")
        kind, axis = "time", np.arange(n) * float(step)
    else:
        kind = _axis_kind(axis_key, where)
        axis = vector(axis_key)
        if axis is None or not np.issubdtype(axis.dtype, np.number):
            raise NNMFileError(f"{where}{axis_key} must be a numeric vector")
        axis = axis.astype(float)
    n = len(axis)
    if matrix is not None:
        m = matrix.reshape(-1, 1) if matrix.ndim == 1 else matrix
        m = m.T if m.shape[0] != n and m.shape[1] == n else m
        if m.ndim != 2 or m.shape[0] != n:
            raise NNMFileError(f"{where}data has shape {matrix.shape}, the axis {n} samples")
        cols = [m[:, j] for j in range(m.shape[1])]
        names = _mat_strings(data[keys["labels"]]) if "labels" in keys else [f"channel {j + 1}" for j in
                                                                              range(len(cols))]
    else:
        names = [k for k in data if k not in special and vector(k) is not None and len(vector(k)) == n
                 and np.issubdtype(vector(k).dtype, np.number)]
        cols = [vector(k) for k in names]
        if "labels" in keys:
            names = _mat_strings(data[keys["labels"]])
    if not cols:
        raise NNMFileError(f"{where}no channel: give data (N x channels) or vectors as long as {axis_key}")
    if len(names) != len(cols):
        raise NNMFileError(f"{where}{len(names)} labels for {len(cols)} channels")
    stated = _mat_strings(data[keys["units"]]) if "units" in keys else [""] * len(cols)
    stated = stated * len(cols) if len(stated) == 1 else stated
    if len(stated) != len(cols):
        raise NNMFileError(f"{where}{len(stated)} units for {len(cols)} channels")
    units = [file_unit(u, f"{where}channel {nm!r}: ") for u, nm in zip(stated, names)]
    return build(kind, axis, [np.asarray(c) for c in cols], names, units, [u or "not stated" for u in stated], path)
