"""A measured backbone on the FEP panel (``nnm-view FILE --measured backbone.csv``, docs/testlab.md).

The file (CSV, UFF 58 or .mat, read by ``nnm_solver.read_measured``) holds peak amplitudes (m, converted from
the file's unit) of one DOF against frequency (Hz), e.g. from phase-resonance testing or a resonance decay.
Energy is not measured: each point is drawn at the energy the selected branch has at that amplitude, the
branch's amplitude at the DOF being |x0[dof]| (its orbits start at rest, x0 is their extreme) at the view's k3
factor (amplitudes scale as sqrt(energy) under the cubic scaling law).  The record is read once at start-up
and never changed: sessions read it without a lock.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import nnm_solver
from nnm_solver.identification.backbone_plot import energy_at_amplitude


@dataclass(frozen=True, eq=False)
class MeasuredBackbone:
    """amplitude (N,) m and frequency (N,) Hz of measured points at model DOF ``dof`` (0-based); label for
    the legend; source file."""

    amplitude: np.ndarray
    frequency: np.ndarray
    dof: int
    label: str
    source: str


def _dof_index(model, dof):
    labels = list(model.dof_labels or [])
    if isinstance(dof, str) and dof.strip().lstrip("-").isdigit():
        dof = int(dof)
    if isinstance(dof, int):
        if not 0 <= dof < model.n:
            raise nnm_solver.NNMInputError(f"--measured-dof {dof} is not a DOF of the model (0..{model.n - 1})")
        return dof
    if dof in labels:
        return labels.index(dof)
    raise nnm_solver.NNMInputError(f"--measured-dof {dof!r} is neither a 0-based DOF index nor a DOF label of "
                                   f"the model")


def load_measured(path, model, dof=None):
    """MeasuredBackbone of a measured file for ``model``: its only channel (or the one labelled like a DOF of
    the model); the DOF from ``dof`` (index or label) or from the channel's label.  One-line NNMInputError."""
    record = nnm_solver.read_measured(path)
    if record.kind != "frequency":
        raise nnm_solver.NNMInputError(f"{path}: a time record; a measured backbone is peak amplitude against "
                                       f"frequency (first column frequency (Hz))")
    labels = list(model.dof_labels or [])
    if record.n_channels == 1:
        j = 0
    else:
        hits = [k for k, lab in enumerate(record.labels) if lab in labels]
        if len(hits) != 1:
            raise nnm_solver.NNMInputError(f"{path}: {record.n_channels} channels; give a file with one amplitude "
                                           f"channel")
        j = hits[0]
    if record.quantities[j] not in ("displacement", "unknown"):
        raise nnm_solver.NNMInputError(f"{path}: channel {record.labels[j]!r} is a {record.quantities[j]}; a "
                                       f"backbone's amplitudes are displacements (m, mm ...)")
    if dof is None:
        if record.labels[j] not in labels:
            raise nnm_solver.NNMInputError(f"{path}: channel {record.labels[j]!r} names no DOF of the model; "
                                           f"give --measured-dof (0-based index or DOF label)")
        dof = record.labels[j]
    k = _dof_index(model, dof)
    amp = np.abs(record.data[:, j]).astype(float)
    return MeasuredBackbone(amplitude=amp, frequency=np.asarray(record.frequency_hz, dtype=float), dof=k,
                            label=f"measured ({len(amp)} points)",
                            source=str(path))


def branch_amplitude(branch, dof):
    """Peak amplitude (m) at ``dof`` of each point of ``branch``: |x0[dof]| for orbits starting at rest, else
    None (not drawn: its x0 is not an extreme of the motion)."""
    v0 = np.asarray(getattr(branch, "v0", None) if getattr(branch, "v0", None) is not None else [np.nan])
    if not np.all(v0 == 0.0):
        return None
    return np.abs(np.asarray(branch.x0)[:, dof])


def on_fep(measured, branch, series_energy, file_energy):
    """(energy J, frequency Hz) of the measured points on the FEP of ``branch`` drawn with energies
    ``series_energy`` (the view's k3 factor) where the file says ``file_energy``; points beyond the branch
    are dropped.  None when the branch cannot place them."""
    amp = branch_amplitude(branch, measured.dof)
    if amp is None or len(amp) < 2 or len(series_energy) != len(amp):
        return None
    shown = amp * np.sqrt(np.asarray(series_energy) / np.maximum(np.asarray(file_energy), 1e-300))
    e = energy_at_amplitude(shown, series_energy, measured.amplitude)
    keep = np.isfinite(e)
    return e[keep], measured.frequency[keep]
