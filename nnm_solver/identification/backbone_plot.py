"""Backbones of the model beside measured points (matplotlib): amplitude-frequency or frequency-energy axes."""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError

AXES = ("amplitude", "energy")


def measured_points(measured):
    """(amplitude (m), frequency (Hz)) of measured points: a pair of arrays, or a frequency Measurement with one
    channel (peak amplitudes, ``nnm.read_measured``)."""
    from ..files.importers.measured import Measurement

    if isinstance(measured, Measurement):
        if measured.kind != "frequency" or measured.n_channels != 1:
            raise NNMInputError(f"{measured.source}: measured backbone points are one channel of amplitudes against "
                                f"frequency ({measured.kind} record with {measured.n_channels} channels)")
        return np.abs(measured.data[:, 0]), measured.frequency_hz
    try:
        amp, freq = (np.asarray(v, dtype=float).ravel() for v in measured)
    except (TypeError, ValueError):
        raise NNMInputError("measured points: give (amplitude, frequency_hz) arrays or a frequency record") from None
    if len(amp) != len(freq) or not len(amp):
        raise NNMInputError(f"measured points: {len(amp)} amplitudes for {len(freq)} frequencies")
    return amp, freq


def energy_at_amplitude(branch_amplitude, branch_energy, amplitude):
    """Energy (J) where a branch whose points have peak amplitudes ``branch_amplitude`` (m) at some DOF and
    energies ``branch_energy`` (J) reaches each of ``amplitude`` (m): log-log interpolation on the first part of
    the branch where the amplitude grows; NaN outside it (the model's amplitude-energy relation)."""
    a, e = np.asarray(branch_amplitude, dtype=float), np.asarray(branch_energy, dtype=float)
    keep = (a > 0) & (e > 0)
    a, e = a[keep], e[keep]
    amplitude = np.atleast_1d(np.asarray(amplitude, dtype=float))
    out = np.full(len(amplitude), np.nan)
    if len(a) < 2:
        return out
    stop = int(np.argmax(np.diff(a) <= 0)) + 1 if np.any(np.diff(a) <= 0) else len(a)
    a, e = a[:stop], e[:stop]
    inside = (amplitude >= a[0]) & (amplitude <= a[-1])
    out[inside] = np.exp(np.interp(np.log(amplitude[inside]), np.log(a), np.log(e)))
    return out


def energy_of_amplitude(branch, dof, amplitude):
    """Energy (J) on ``branch`` where its peak amplitude at ``dof`` (``amplitude_backbone``) equals each of
    ``amplitude`` (m); NaN outside the branch (``energy_at_amplitude``)."""
    from ..files import amplitude_backbone

    return energy_at_amplitude(amplitude_backbone(branch, dof).amplitude, branch.energy, amplitude)


def plot_backbone(branches, dof, measured=None, *, axis="amplitude", ax=None, scale=1.0, unit="m",
                  measured_label="measured", path=None, title=None):
    """Backbones of ``branches`` (a Branch or a list: nominal, identified, ...) at DOF ``dof`` (0-based) with
    measured points (amplitude (m), frequency (Hz)) over them.

    axis="amplitude": peak amplitude (times ``scale``, in ``unit``) against frequency, the test engineer's plot;
    axis="energy": the FEP (frequency against energy, log scale), each measured point placed at the energy the
    FIRST branch has at its amplitude (the model's amplitude-energy relation; points beyond the branch are left
    out and counted in the legend).  Returns the axes; saved to ``path`` if given."""
    import matplotlib
    if path is not None and ax is None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from ..files import amplitude_backbone
    from ..results.branch import Branch

    if axis not in AXES:
        raise NNMInputError(f"plot_backbone: axis {axis!r} is not one of {', '.join(AXES)}")
    branches = [branches] if isinstance(branches, Branch) else list(branches)
    if not branches or not all(isinstance(b, Branch) for b in branches):
        raise NNMInputError("plot_backbone: give a Branch or a list of Branches")
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    for b in branches:
        if axis == "amplitude":
            bb = amplitude_backbone(b, dof)
            ax.plot(bb.frequency_hz, scale * bb.amplitude, "-", lw=1.5, label=b.name or f"NNM {b.mode}")
        else:
            ax.plot(b.energy, b.frequency_hz, "-", lw=1.5, label=b.name or f"NNM {b.mode}")
    if measured is not None:
        amp, freq = measured_points(measured)
        if axis == "amplitude":
            ax.plot(freq, scale * amp, "o", mfc="none", color="k", ms=5, label=measured_label)
        else:
            e = energy_of_amplitude(branches[0], dof, amp)
            out = int(np.sum(~np.isfinite(e)))
            ax.plot(e[np.isfinite(e)], freq[np.isfinite(e)], "o", mfc="none", color="k", ms=5,
                    label=f"{measured_label} (energy from the first branch's amplitude"
                          f"{f'; {out} beyond it' if out else ''})")
    if axis == "amplitude":
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel(f"peak amplitude ({unit})")
    else:
        ax.set_xscale("log")
        ax.set_xlabel("energy (J)")
        ax.set_ylabel("frequency (Hz)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=110)
    return ax
