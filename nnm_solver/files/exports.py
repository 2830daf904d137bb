"""Results out to the test lab: CSV tables, UFF 55 shapes / UFF 58 orbits (``pyuff``), amplitude backbones.

* ``export_csv(path, branch)``: one row per point -- energy (J), frequency (Hz), period (s), stable
  (True/False; ``unknown`` where the point's stability was not computed, ``branch.stability_known``), label (``branch.labels[i]`` when the branch has labels, else ``"backbone"``);
* ``export_uff(path, branch, points=None)``: one UFF 55 data set (data at nodes, normal-mode
  analysis type) per point: its mode shape x0 (the orbit's displacement at t = 0, m / rad), the
  point's frequency, NNM number and energy in the ID lines.  Nodes: the model's DOF map
  (``node 12 uz`` labels, 3 or 6 values per node); else the display mesh's vertices (3 values,
  vertex v = node v + 1); else one node per DOF (value in the first direction);
* ``export_uff_orbit(path, branch, point, dofs=None)``: UFF 58 time series (one period) per DOF;
* ``amplitude_backbone(branch, dof, kind)``: peak or first-harmonic amplitude at one DOF (or mesh
  vertex) against frequency, the way test engineers plot backbones; ``export_backbone_csv``.

pyuff is an optional extra (``pip install "nnm[io]"``).  Every file is written next to its target
and renamed over it when complete: bad input writes nothing.
"""
from __future__ import annotations

import csv
from contextlib import contextmanager
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..results.branch import Branch
from ..errors import NNMInputError
from ..fourier import fourier_coefficients, resample_periodic
from .h5file import atomic_file
from .importers.common import DofMap, direction_name

__all__ = ["export_csv", "export_uff", "export_uff_orbit", "amplitude_backbone", "export_backbone_csv",
           "Backbone", "BACKBONE_KINDS"]

#: amplitude definitions of a backbone
BACKBONE_KINDS = ("peak", "harmonic1")
CSV_COLUMNS = ("energy", "frequency", "period", "stable", "label")
_UFF_DIR = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}


# ---------------------------------------------------------------------- helpers
def _check_branch(branch):
    if not isinstance(branch, Branch):
        raise NNMInputError(f"expected an nnm_solver.Branch, got {type(branch).__name__}")
    if not len(branch):
        raise NNMInputError("the branch has no points; nothing to export")


@contextmanager
def _atomic_text(path, newline=None):
    """A text file opened next to ``path``, renamed over it when the block completes (h5file.atomic_file)."""
    with atomic_file(path) as tmp:
        with open(tmp, "w", newline=newline) as fh:
            yield fh, tmp


def _labels(branch):
    labels = getattr(branch, "labels", None)
    if labels is None:
        return ["backbone"] * len(branch)
    labels = [str(s) for s in labels]
    if len(labels) != len(branch):
        raise NNMInputError(f"branch.labels has {len(labels)} entries, the branch has {len(branch)} points")
    return labels


def _pyuff():
    try:
        import pyuff
    except ImportError:
        raise NNMInputError('UFF export needs the optional package pyuff: pip install "nnm[io]"') from None
    return pyuff


def _point_indices(branch, points):
    if points is None:
        return list(range(len(branch)))
    if isinstance(points, (int, np.integer)) and not isinstance(points, bool):
        points = [points]
    return [branch.check_index(i) for i in points]


def _known(branch, i):
    known = getattr(branch, "stability_known", None)
    return True if known is None else bool(known[i])


def _stable_text(branch, i):
    """The CSV cell of point i's stability: True, False, or unknown (its multipliers were not computed)."""
    return str(bool(branch.stable[i])) if _known(branch, i) else "unknown"


def _stability_word(branch, i):
    """stable, unstable, or stability unknown (a UFF data set's ID line)."""
    if not _known(branch, i):
        return "stability unknown"
    return "stable" if branch.stable[i] else "unstable"


# ---------------------------------------------------------------------- CSV
def export_csv(path, branch):
    """Write one row per point of ``branch``: energy (J), frequency (Hz), period (s), stable, label."""
    _check_branch(branch)
    labels = _labels(branch)
    with _atomic_text(path, newline="") as (fh, _):
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for i in range(len(branch)):
            w.writerow([repr(float(branch.energy[i])), repr(float(branch.frequency_hz[i])),
                        repr(float(branch.period[i])), _stable_text(branch, i), labels[i]])
    return Path(path)


# ---------------------------------------------------------------------- backbones
class Backbone(NamedTuple):
    """Amplitude-frequency backbone: frequency_hz (N,) Hz and amplitude (N,) m (or rad) of each point."""

    frequency_hz: np.ndarray
    amplitude: np.ndarray


def _coordinate(model, dof=None, vertex=None, direction="uz"):
    """(weights (n,), description) selecting one coordinate of the model or of its display mesh."""
    n = model.n
    if (dof is None) == (vertex is None):
        raise NNMInputError("give a dof (index, label or (node, direction)) or a mesh vertex, not both")
    if vertex is not None:
        if model.mesh is None:
            raise NNMInputError("the model has no display mesh; give a dof instead of a vertex")
        V = len(model.mesh.vertices)
        if isinstance(vertex, bool) or not isinstance(vertex, (int, np.integer)) or not 0 <= vertex < V:
            raise NNMInputError(f"vertex {vertex!r} is not a mesh vertex (0..{V - 1})")
        c = {"ux": 0, "uy": 1, "uz": 2}.get(direction_name(direction))
        if c is None:
            raise NNMInputError(f"a mesh vertex moves in ux, uy or uz, not {direction!r}")
        return model.mesh.map_rows([3 * int(vertex) + c])[0], \
            f"mesh vertex {vertex} {'xyz'[c]}"
    w = np.zeros(n)
    if isinstance(dof, (int, np.integer)) and not isinstance(dof, bool):
        if not 0 <= dof < n:
            raise NNMInputError(f"dof {dof} is not a DOF of the model (0..{n - 1})")
        w[int(dof)] = 1.0
        label = model.dof_labels[int(dof)] if model.dof_labels else f"DOF {int(dof)}"
        return w, label
    dmap = DofMap.from_labels(model.dof_labels)
    if isinstance(dof, str):
        s = dof.strip()
        if model.dof_labels and s in model.dof_labels:
            w[model.dof_labels.index(s)] = 1.0
            return w, s
        parts = s.replace(",", " ").split()
        if parts and parts[0].lower() == "node":
            parts = parts[1:]
        if len(parts) == 2 and dmap is not None:
            dof = tuple(parts)
        elif s.lstrip("-").isdigit():
            return _coordinate(model, int(s))
        else:
            raise NNMInputError(f"dof {dof!r} is neither a DOF index, a DOF label of the model, "
                                f"nor 'node direction' of its DOF map")
    if isinstance(dof, (tuple, list)) and len(dof) == 2:
        if dmap is None:
            raise NNMInputError("the model has no DOF map (node, direction); give a 0-based DOF index")
        j = dmap.index(dof[0], dof[1])
        w[j] = 1.0
        return w, model.dof_labels[j]
    raise NNMInputError(f"dof {dof!r} is neither a DOF index, a DOF label nor (node, direction)")


def amplitude_backbone(branch, dof=None, kind="peak", samples=256, *, vertex=None, direction="uz"):
    """Backbone (frequency_hz, amplitude) of ``branch`` at one coordinate.

    dof : 0-based DOF index, a DOF label (``"node 12 uz"``) or ``(node, direction)`` of the model's
    DOF map; or ``vertex`` (mesh vertex index) with ``direction`` (ux/uy/uz, or x/y/z).
    kind : ``"peak"`` -- max over the orbit of |x(t)| (the orbit from ``branch.motion``, resampled 4x
    by Fourier interpolation); ``"harmonic1"`` -- |a_1|, the amplitude of the first harmonic
    (``fourier_coefficients``).  Units of the coordinate (m, rad).
    """
    _check_branch(branch)
    if kind not in BACKBONE_KINDS:
        raise NNMInputError(f"kind {kind!r} is not one of {', '.join(BACKBONE_KINDS)}")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 8:
        raise NNMInputError(f"samples must be an integer >= 8, got {samples!r}")
    w, _ = _coordinate(branch.model, dof, vertex, direction)
    amp = np.empty(len(branch))
    for i in range(len(branch)):
        _, x = branch.motion(i, int(samples))
        y = x @ w
        if kind == "peak":
            amp[i] = np.max(np.abs(resample_periodic(y, 4 * int(samples))))
        else:
            amp[i] = np.abs(fourier_coefficients(y, 1)[1])
    return Backbone(branch.frequency_hz.copy(), amp)


def export_backbone_csv(path, branch, dof=None, kind="peak", samples=256, *, vertex=None, direction="uz"):
    """Write the backbone of ``amplitude_backbone`` as CSV: energy, frequency, amplitude, stable, label."""
    w, where = _coordinate(branch.model, dof, vertex, direction) if isinstance(branch, Branch) else (None, "")
    bb = amplitude_backbone(branch, dof, kind, samples, vertex=vertex, direction=direction)
    labels = _labels(branch)
    with _atomic_text(path, newline="") as (fh, _):
        fh.write(f"# {kind} amplitude at {where}; energy J, frequency Hz, amplitude m (rad)\n")
        wr = csv.writer(fh)
        wr.writerow(("energy", "frequency", "amplitude", "stable", "label"))
        for i in range(len(branch)):
            wr.writerow([repr(float(branch.energy[i])), repr(float(bb.frequency_hz[i])), repr(float(bb.amplitude[i])),
                         _stable_text(branch, i), labels[i]])
    return bb


# ---------------------------------------------------------------------- UFF
def uff_nodes(model):
    """How model coordinates become UFF nodes: (node numbers (N,), per-node values (N, k) from x (n,)), k = 3 or 6.

    Returns (node_nums, k, fn) with fn(x) -> (N, k) values.  Scalar points (a superelement's modal coordinates,
    'spoint 1001 modal') are not nodes of the shape and are left out."""
    dmap = DofMap.from_labels(model.dof_labels)
    if dmap is not None and any(d in _UFF_DIR for _, d in dmap.entries):
        physical = {nd for nd, d in dmap.entries if d in _UFF_DIR}
        nodes = [nd for nd in dmap.nodes if nd in physical]
        ints = all(isinstance(nd, int) for nd in nodes)
        nums = np.array(nodes if ints else range(1, len(nodes) + 1), dtype=np.int64)
        row = {nd: r for r, nd in enumerate(nodes)}
        k = 6 if any(d in ("rx", "ry", "rz") for _, d in dmap.entries) else 3
        pick = [(row[nd], _UFF_DIR[d] - 1, j) for j, (nd, d) in enumerate(dmap.entries) if d in _UFF_DIR and
                _UFF_DIR[d] <= k]
        r_idx = np.array([p[0] for p in pick]), np.array([p[1] for p in pick]), np.array([p[2] for p in pick])

        def values(x):
            out = np.zeros((len(nodes), k))
            out[r_idx[0], r_idx[1]] = x[r_idx[2]]
            return out

        return nums, k, values
    if model.mesh is not None:
        V = len(model.mesh.vertices)
        return np.arange(1, V + 1), 3, lambda x: model.mesh.displacements(x)
    n = model.n

    def per_dof(x):
        out = np.zeros((n, 3))
        out[:, 0] = x
        return out

    return np.arange(1, n + 1), 3, per_dof


def export_uff(path, branch, points=None):
    """Write one UFF 55 data set per point (all points, or the indices ``points``): its mode shape x0.

    Read back with ``pyuff.UFF(path).read_sets()``: node_nums, r1..r3 (r4..r6 with rotations),
    freq (Hz), mode_n (point index + 1), load_case (the NNM's linear mode number).
    """
    _check_branch(branch)
    pyuff = _pyuff()
    idx = _point_indices(branch, points)
    model = branch.model
    nums, k, values = uff_nodes(model)
    labels = _labels(branch)
    sets = []
    for i in idx:
        v = values(branch.x0[i])
        r = {f"r{c + 1}": v[:, c].astype(float) for c in range(k)}
        sets.append(pyuff.prepare_55(
            id1=f"NNM {branch.mode} of {model.name or 'model'}"[:80],
            id2=f"point {i + 1}: E = {branch.energy[i]:.6e} J, f = {branch.frequency_hz[i]:.6f} Hz, "
                f"{_stability_word(branch, i)}"[:80],
            id3="shape x0: displacement at t = 0 of the periodic orbit (m, rad)",
            id4=f"label: {labels[i]}"[:80], id5="nnm nonlinear normal mode",
            model_type=1, analysis_type=2, data_ch=3 if k == 6 else 2, spec_data_type=8, data_type=2,
            n_data_per_node=k, load_case=int(branch.mode), mode_n=int(i + 1),
            freq=float(branch.frequency_hz[i]), modal_m=0.0, modal_damp_vis=0.0, modal_damp_his=0.0,
            node_nums=nums, **r))
    _write_uff(path, pyuff, sets)
    return Path(path)


def _write_uff(path, pyuff, sets):
    with _atomic_text(path) as (_, tmp):
        pass_through = pyuff.UFF(tmp)
        try:
            pass_through.write_sets(sets, mode="overwrite")
        except Exception as exc:  # pyuff raises bare Exceptions
            raise NNMInputError(f"cannot write {path} as UFF ({exc})") from None


def export_uff_orbit(path, branch, point, dofs=None, samples=256):
    """Write the orbit of one point as UFF 58 time series (one period, ``samples`` values), one data set
    per DOF (all DOFs, or the indices ``dofs``); response node/direction from the DOF map when there is one."""
    _check_branch(branch)
    pyuff = _pyuff()
    i = branch.check_index(point)
    model = branch.model
    if dofs is None:
        dofs = range(model.n)
    dofs = [int(_coordinate(model, d)[0].argmax()) for d in dofs]
    t, x = branch.motion(i, int(samples))
    dmap = DofMap.from_labels(model.dof_labels)
    sets = []
    for j in dofs:
        node, direc = (j + 1, 1)
        if dmap is not None and isinstance(dmap.entries[j][0], int):
            node, direc = dmap.entries[j][0], _UFF_DIR.get(dmap.entries[j][1], 0)
        sets.append(pyuff.prepare_58(
            binary=0, id1=f"NNM {branch.mode} point {i} orbit"[:80],
            id2=f"E = {branch.energy[i]:.6e} J, f = {branch.frequency_hz[i]:.6f} Hz"[:80],
            id3=(model.dof_labels[j] if model.dof_labels else f"DOF {j}")[:80], id4="one period", id5="nnm",
            func_type=1, ver_num=0, load_case_id=int(branch.mode), rsp_ent_name="nnm", rsp_node=int(node),
            rsp_dir=int(direc), ref_ent_name="nnm", ref_node=0, ref_dir=0, ord_data_type=4,
            num_pts=len(t), abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=float(t[1] - t[0]),
            z_axis_value=0.0, abscissa_spec_data_type=17, abscissa_len_unit_exp=0, abscissa_force_unit_exp=0,
            abscissa_temp_unit_exp=0, abscissa_axis_units_lab="s", ordinate_spec_data_type=8,
            ordinate_len_unit_exp=1, ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0,
            ordinate_axis_units_lab="m", orddenom_spec_data_type=0, orddenom_len_unit_exp=0,
            orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0, orddenom_axis_units_lab="",
            z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
            z_axis_axis_units_lab="", data=np.ascontiguousarray(x[:, j]), x=np.ascontiguousarray(t)))
    _write_uff(path, pyuff, sets)
    return Path(path)
