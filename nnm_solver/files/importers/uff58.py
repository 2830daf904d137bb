"""UFF data set 58 (function at nodal DOF) in and out, through the optional ``pyuff``.

``read_uff58(path)``: every data set 58 of the file (or the 0-based ``sets`` among them), all on one axis, as
one ``Measurement``.  Time records: abscissa type 17 (time) or function type 1 (time response); otherwise a
frequency record (FRFs: function type 4, complex).  Each data set is one channel: response node and direction
(``node 14 uz``, a force ``node 14 uz force``; a negative direction, e.g. -3 for -Z, flips the sign so that the channel is along +uz), the
reference node of an FRF, and its unit:

1. the ordinate's unit label when it is one ``parse_unit`` knows (``g``, ``mm/s^2``, ``m/s^2/N`` ...);
2. else the ordinate's specific data type (8 displacement, 11 velocity, 12 acceleration, 13 force) in the
   file's units of data set 164 (its length and force factors; SI when the file has no 164);
3. a label that names another quantity than the data type is refused (one line).

``write_uff58(path, record)`` writes a Measurement back: a data set 164 (SI) and one 58 per channel, in SI
with unit labels; written next to the target and renamed over it when complete.
"""
from __future__ import annotations

import numpy as np

from ...errors import NNMFileError, NNMInputError
from .common import DIRECTIONS, existing
from .measured import Measurement, build, uniform_step
from .measured_units import UFF_TYPES, SignalUnit, parse_unit, uff_quantity, unit_from_uff

__all__ = ["read_uff58", "write_uff58"]

_SPEC = {q: k for k, q in UFF_TYPES.items()}
_FRF_OF = {"receptance": "displacement", "mobility": "velocity", "accelerance": "acceleration"}


def _pyuff():
    from ..exports import _pyuff as load

    return load()


def _sets(path):
    pyuff = _pyuff()
    try:
        found = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exceptions (and others) for malformed files
        raise NNMFileError(f"{path}: not a readable UFF file ({exc.__class__.__name__}: "
                           f"{str(exc).splitlines()[0] if str(exc) else 'malformed'})") from None
    return [found] if isinstance(found, dict) else list(found)


def _channel_unit(s, length, force, where):
    """(SignalUnit, stated) of one data set 58 (module doc)."""
    quantity = uff_quantity(s.get("ordinate_spec_data_type", 0), s.get("orddenom_spec_data_type", 0))
    label = str(s.get("ordinate_axis_units_lab", "") or "").strip()
    if label.upper() in ("", "NONE"):
        label = ""
    try:
        u = parse_unit(label, where) if label else None
    except NNMInputError:
        u = None
    if u is not None and u.quantity != "unknown":
        if quantity != "unknown" and u.quantity != quantity:
            raise NNMFileError(f"{where}unit label {label!r} is a unit of {u.quantity}, the data type says "
                               f"{quantity}")
        return u, label
    stated = "SI (no unit label, no data set 164)" if length is None else \
        f"file units of data set 164 (length factor {length:g}, force factor {force:g})"
    if quantity == "unknown":
        return SignalUnit("unknown", "", 1.0), f"{label or 'no unit'} (data type {s.get('ordinate_spec_data_type')})"
    return unit_from_uff(quantity, 1.0 if length is None else length, 1.0 if force is None else force), stated


def _where_label(node, direction):
    d = abs(int(direction))
    return (int(node), DIRECTIONS[d - 1] if 1 <= d <= 6 else None, -1.0 if int(direction) < 0 else 1.0)


def read_uff58(path, sets=None):
    """Measurement of the data sets 58 of a UFF file (module doc); ``sets``: 0-based indices among them."""
    path = existing(path, "measured data")
    everything = _sets(path)
    units164 = next((s for s in everything if s.get("type") == 164), None)
    found = [s for s in everything if s.get("type") == 58]
    if not found:
        kinds = sorted({str(s.get("type")) for s in everything})
        raise NNMFileError(f"{path}: no UFF data set 58 (function at nodal DOF) in the file"
                           f"{' (data sets: ' + ', '.join(kinds) + ')' if kinds else ' (not a UFF file?)'}")
    if sets is not None:
        bad = [i for i in sets if not 0 <= int(i) < len(found)]
        if bad:
            raise NNMInputError(f"{path}: sets {bad} out of range: the file has {len(found)} data sets 58 (0-based)")
        found = [found[int(i)] for i in sets]
    length = force = None
    if units164 is not None:
        length, force = float(units164.get("length", 1.0)), float(units164.get("force", 1.0))
        if not (length > 0 and force > 0):
            raise NNMFileError(f"{path}: data set 164 has unit factors length {length}, force {force}: not positive")
    first = found[0]
    kinds = ["time" if (int(s.get("abscissa_spec_data_type", 0)) == 17 or
                        (int(s.get("abscissa_spec_data_type", 0)) != 18 and int(s.get("func_type", 0)) == 1))
             else "frequency" for s in found]
    if len(set(kinds)) > 1:
        j = kinds.index(kinds[-1] if kinds[0] == "time" else "time")
        raise NNMFileError(f"{path}: data set 58 number {j + 1} is a {kinds[j]} function, number 1 a {kinds[0]} "
                           f"function; read them separately with sets=[...]")
    kind = kinds[0]
    ax_label = str(first.get("abscissa_axis_units_lab", "") or "").strip()
    try:
        ax_unit = parse_unit(ax_label) if ax_label and ax_label.upper() != "NONE" else None
    except NNMInputError:
        ax_unit = None
    ax_factor = ax_unit.factor if ax_unit is not None and ax_unit.quantity == kind else 1.0
    axis = np.asarray(first["x"], dtype=float)
    cols, names, units, stated, refs = [], [], [], [], []
    for j, s in enumerate(found):
        where = f"{path}: data set 58 number {j + 1}: "
        x, y = np.asarray(s.get("x", []), dtype=float), np.asarray(s.get("data", []))
        if len(x) != len(axis) or len(y) != len(axis) or not np.allclose(x, axis, rtol=1e-9, atol=0.0):
            raise NNMFileError(f"{where}its {len(x)} abscissa values differ from data set 1's {len(axis)}; all "
                               f"channels of one record share the axis (choose with sets=[...])")
        node, direction, sign = _where_label(s.get("rsp_node", 0), s.get("rsp_dir", 0))
        u, st = _channel_unit(s, length, force, where)
        cols.append(sign * y)
        suffix = " force" if u.quantity == "force" else ""        # a driving point: force and response at one DOF
        names.append(f"node {node} {direction}{suffix}" if direction else
                     (str(s.get("id1", "")).strip() or f"set {j + 1}"))
        units.append(u)
        stated.append(st)
        rn, rd, _ = _where_label(s.get("ref_node", 0), s.get("ref_dir", 0))
        refs.append(f"node {rn} {rd}" if rd and u.quantity in _FRF_OF else "")
    if len(set(names)) != len(names):
        dup = next(nm for nm in names if names.count(nm) > 1)
        raise NNMFileError(f"{path}: two data sets 58 at {dup} (several references or load cases?); choose the "
                           f"channels with sets=[...]")
    return build(kind, axis * ax_factor, cols, names, units, stated, path, references=refs)


def _direction_number(direction):
    return DIRECTIONS.index(direction) + 1 if direction in DIRECTIONS else 0


def write_uff58(path, record):
    """Write a Measurement as UFF: data set 164 (SI) and one data set 58 per channel, values in SI (module doc).
    Channels without a node are numbered 1, 2, ... in order.  Returns the path."""
    from pathlib import Path

    from ..exports import _write_uff

    if not isinstance(record, Measurement):
        raise NNMInputError(f"write_uff58 needs an nnm Measurement, got {type(record).__name__}")
    pyuff = _pyuff()
    step = uniform_step(record.axis)
    time = record.kind == "time"
    sets = [pyuff.prepare_164(units_code=1, units_description="SI", temp_mode=2, length=1.0, force=1.0, temp=1.0,
                              temp_offset=273.15)]
    for j in range(record.n_channels):
        q = record.quantities[j]
        node = record.nodes[j] if isinstance(record.nodes[j], int) else j + 1
        ref = record.references[j].split() if record.references[j] else []
        y = np.ascontiguousarray(record.data[:, j])
        complex_ = np.iscomplexobj(y)
        sets.append(pyuff.prepare_58(
            binary=0, id1=record.labels[j][:80], id2=f"{q} ({record.units[j] or 'as written'})"[:80],
            id3=f"from {Path(record.source).name}"[:80] if record.source else "nnm", id4="", id5="nnm",
            func_type=1 if time else (4 if q in _FRF_OF else 0), ver_num=0, load_case_id=0, rsp_ent_name="nnm",
            rsp_node=int(node), rsp_dir=_direction_number(record.directions[j]), ref_ent_name="nnm",
            ref_node=int(ref[1]) if len(ref) == 3 and ref[1].lstrip("-").isdigit() else 0,
            ref_dir=_direction_number(ref[2]) if len(ref) == 3 else 0, ord_data_type=6 if complex_ else 4,
            num_pts=len(record), abscissa_spacing=1 if step else 0, abscissa_min=float(record.axis[0]),
            abscissa_inc=float(step), z_axis_value=0.0, abscissa_spec_data_type=17 if time else 18,
            abscissa_len_unit_exp=0, abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
            abscissa_axis_units_lab="s" if time else "Hz",
            ordinate_spec_data_type=_SPEC.get(_FRF_OF.get(q, q), 0),
            ordinate_len_unit_exp=1 if q not in ("force", "unknown") else 0,
            ordinate_force_unit_exp=1 if q == "force" else (-1 if q in _FRF_OF else 0), ordinate_temp_unit_exp=0,
            ordinate_axis_units_lab=record.units[j], orddenom_spec_data_type=13 if q in _FRF_OF else 0,
            orddenom_len_unit_exp=0, orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0,
            orddenom_axis_units_lab="N" if q in _FRF_OF else "", z_axis_spec_data_type=0, z_axis_len_unit_exp=0,
            z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0, z_axis_axis_units_lab="", data=y,
            x=np.ascontiguousarray(record.axis)))
    _write_uff(path, pyuff, sets)
    return Path(path)
