"""Measured signals in: UFF 58 (``uff58``), CSV and MATLAB .mat time series and frequency functions, as one record.

A ``Measurement`` holds one axis (time t (s), or frequency (Hz)) and its channels as columns of ``data``
(N, channels), converted to SI (g -> m/s^2, mm -> m, lbf -> N, g/N -> m/s^2/N), with per channel its
label, quantity, SI unit, the unit the file stated, and the node and direction it was measured at when the
file says.  ``nnm.rfs`` takes a time record and channel names, ``nnm.fit_backbone`` a frequency record of
peak amplitudes; ``record.channel("node 14 uz")`` gives one channel as a 1-D array.

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
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import NNMFileError, NNMInputError
from .common import direction_name, existing, node_key
from .measured_units import SI, SignalUnit, parse_unit

__all__ = ["Measurement", "read_csv_measurement", "read_mat_measurement", "parse_channel_label"]

KINDS = ("time", "frequency")
_LABEL = re.compile(r"^\s*(?:node\s+)?([+-]?\d+)\s*[:\s]\s*([+-]?)\s*(ux|uy|uz|rx|ry|rz|x|y|z|[1-6])\s*$", re.I)


def parse_channel_label(label):
    """(node, direction, sign) of a channel named like a DOF ('node 14 uz', '14 z', '14:-z'), else (None, None, 1)."""
    m = _LABEL.match(str(label))
    if not m:
        return None, None, 1
    return node_key(m.group(1)), direction_name(m.group(3).lower()), -1 if m.group(2) == "-" else 1


@dataclass(frozen=True, eq=False)
class Measurement:
    """Measured signals on one axis, in SI (module doc).

    kind : ``"time"`` (axis t, s; strictly increasing) or ``"frequency"`` (axis f, Hz; increasing for FRFs, in
    any order for measured backbone points).  data (N, channels),
    real, or complex for frequency response functions.  Per channel: ``labels`` (``"node 14 uz"`` when the
    file gives node and direction, else the file's name), ``quantities`` (displacement, velocity,
    acceleration, force, receptance, mobility, accelerance or unknown), ``units`` (the SI unit of
    the values held), ``file_units`` (the unit the file stated, and where from), ``nodes`` and ``directions``
    (ux..rz; None when not stated; a negative direction in the file has flipped the signal's sign),
    ``references`` (the excitation point of an FRF, '' otherwise).  ``sampling`` : sample rate (Hz) of a
    time record, frequency step (Hz) of a frequency record, 0 when the axis is not uniform and increasing.  ``source`` : file.
    """

    kind: str
    axis: np.ndarray
    data: np.ndarray
    labels: tuple
    quantities: tuple
    units: tuple
    file_units: tuple
    nodes: tuple
    directions: tuple
    references: tuple
    sampling: float
    source: str

    def __post_init__(self):
        where = f"{self.source}: " if self.source else ""
        if self.kind not in KINDS:
            raise NNMInputError(f"{where}measurement kind {self.kind!r} is not one of {', '.join(KINDS)}")
        ax = np.asarray(self.axis, dtype=float)
        if ax.ndim != 1 or len(ax) < 2 or not np.all(np.isfinite(ax)):
            raise NNMFileError(f"{where}the {self.kind} axis must be at least 2 finite values")
        if self.kind == "time" and not np.all(np.diff(ax) > 0):
            raise NNMFileError(f"{where}the time axis is not strictly increasing (sample "
                               f"{int(np.argmin(np.diff(ax) > 0)) + 2}); sort the record")
        if self.kind == "frequency" and not np.all(ax >= 0):
            raise NNMFileError(f"{where}the frequency axis has negative values ({ax.min():g} Hz)")
        data = np.asarray(self.data)
        if data.ndim != 2 or data.shape[0] != len(ax) or data.shape[1] < 1:
            raise NNMFileError(f"{where}data of shape {data.shape} does not fit {len(ax)} samples of the {self.kind} "
                               f"axis (expected ({len(ax)}, channels))")
        c = data.shape[1]
        for name in ("labels", "quantities", "units", "file_units", "nodes", "directions", "references"):
            if len(getattr(self, name)) != c:
                raise NNMInputError(f"{where}{len(getattr(self, name))} {name} for {c} channels")
        if len(set(self.labels)) != c:
            dup = next(s for s in self.labels if list(self.labels).count(s) > 1)
            raise NNMFileError(f"{where}channel {dup!r} appears twice; channel labels must be unique")
        if self.kind == "time" and np.iscomplexobj(data):
            raise NNMFileError(f"{where}a time record holds real values (complex channels belong to frequency "
                               f"functions)")
        if not np.all(np.isfinite(data)):
            i, j = np.argwhere(~np.isfinite(data))[0]
            raise NNMFileError(f"{where}channel {self.labels[j]!r} has a NaN or infinite value at sample {i + 1}")
        ax.setflags(write=False)
        data = data.copy() if data is self.data else data
        data.setflags(write=False)
        object.__setattr__(self, "axis", ax)
        object.__setattr__(self, "data", data)

    def __len__(self):
        return len(self.axis)

    @property
    def n_channels(self):
        return self.data.shape[1]

    @property
    def t(self):
        """Sample times (s) of a time record."""
        if self.kind != "time":
            raise NNMInputError(f"{self.source}: a frequency record has no time axis (its axis: frequency_hz)")
        return self.axis

    @property
    def frequency_hz(self):
        """Frequencies (Hz) of a frequency record."""
        if self.kind != "frequency":
            raise NNMInputError(f"{self.source}: a time record has no frequency axis (its axis: t)")
        return self.axis

    def index(self, key):
        """0-based channel index of ``key``: an index, a label, 'node 14 uz' / '14 z', or (node, direction)."""
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool):
            if not 0 <= key < self.n_channels:
                raise NNMInputError(f"{self.source}: channel {key} is not a channel (0..{self.n_channels - 1})")
            return int(key)
        if isinstance(key, str) and key in self.labels:
            return self.labels.index(key)
        node, direction = (key if isinstance(key, tuple) and len(key) == 2 else parse_channel_label(key)[:2])
        if node is not None:
            node, direction = node_key(node), direction_name(direction)
            if f"node {node} {direction}" in self.labels:        # the response, before a force at the same DOF
                return self.labels.index(f"node {node} {direction}")
            for j, (n, d) in enumerate(zip(self.nodes, self.directions)):
                if n == node and d == direction:
                    return j
        raise NNMInputError(f"{self.source}: no channel {key!r}; channels: {', '.join(self.labels[:8])}"
                            f"{' ...' if self.n_channels > 8 else ''}")

    def channel(self, key):
        """One channel's values (N,) in SI (``units[index(key)]``)."""
        return self.data[:, self.index(key)]

    def describe(self):
        """One line per channel: label, quantity, SI unit and the unit the file stated."""
        head = (f"{self.source}: {self.kind} record, {len(self)} samples, {self.axis[0]:.6g} .. {self.axis[-1]:.6g} "
                f"{'s' if self.kind == 'time' else 'Hz'}, {self.n_channels} channel(s)")
        rows = [f"  {j}: {lab} - {q} in {u or '(as written)'} (file: {fu})" for j, (lab, q, u, fu) in
                enumerate(zip(self.labels, self.quantities, self.units, self.file_units))]
        return "\n".join([head] + rows)


def uniform_step(axis):
    """The axis' constant step, or 0 when its steps differ by more than 1e-6 relative."""
    d = np.diff(axis)
    step = (axis[-1] - axis[0]) / (len(axis) - 1)
    return float(step) if step > 0 and np.max(np.abs(d - step)) <= 1e-6 * step else 0.0


def build(kind, axis, columns, names, units, file_units, source, references=None):
    """A Measurement from raw columns (file units) and each channel's SignalUnit: converted to SI, labels parsed."""
    nodes, directions, labels, data = [], [], [], []
    for col, name, u in zip(columns, names, units):
        force = re.search(r"\s+force$", str(name).strip())           # 'node 4 uz force': a force at a DOF
        node, direction, sign = parse_channel_label(str(name).strip()[:force.start()] if force else name)
        nodes.append(node)
        directions.append(direction)
        labels.append(f"node {node} {direction}{' force' if force else ''}" if node is not None else str(name).strip())
        data.append(sign * u.factor * np.asarray(col))
    step = uniform_step(np.asarray(axis, dtype=float))
    return Measurement(kind=kind, axis=np.asarray(axis, dtype=float), data=np.column_stack(data),
                       labels=tuple(labels), quantities=tuple(u.quantity for u in units),
                       units=tuple(u.si for u in units), file_units=tuple(file_units), nodes=tuple(nodes),
                       directions=tuple(directions), references=tuple(references or [""] * len(names)),
                       sampling=(1.0 / step if kind == "time" else step) if step else 0.0, source=str(source))


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
    from .matlab import _strings

    return _strings(value)


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
