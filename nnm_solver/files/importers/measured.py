"""Measured signals in: UFF 58 (``uff58``), CSV and MATLAB .mat time series and frequency functions, as one record.

A ``Measurement`` holds one axis (time t (s), or frequency (Hz)) and its channels as columns of ``data``
(N, channels), converted to SI (g -> m/s^2, mm -> m, lbf -> N, g/N -> m/s^2/N), with per channel its
label, quantity, SI unit, the unit the file stated, and the node and direction it was measured at when the
file says.  ``nnm.rfs`` takes a time record and channel names, ``nnm.fit_backbone`` a frequency record of
peak amplitudes; ``record.channel("node 14 uz")`` gives one channel as a 1-D array.

The CSV and MATLAB readers are in measured_tables.py, ``read_measured`` (measured_read.py) picks one by suffix.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ...errors import NNMFileError, NNMInputError
from .common import direction_name, node_key

__all__ = ["Measurement", "parse_channel_label", "uniform_step", "build"]

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
