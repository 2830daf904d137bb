"""Frequency-energy plots (FEP) with matplotlib: frequency (Hz) against energy (J, log axis)."""
from __future__ import annotations

import numpy as np


def plot_fep(branches, ax=None, path=None, title=None):
    """Draw the FEP of one or several branches; stable points filled, unstable points hollow.

    branches : Branch or list of Branch.  ax : matplotlib Axes (created if None).
    path : if given, the figure is saved there (PNG, PDF, ... by extension).  Returns the Axes.
    """
    import matplotlib
    if ax is None and path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    if not isinstance(branches, (list, tuple)):
        branches = [branches]
    if ax is None:
        fig, ax = plt.subplots(figsize=(7, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, b in enumerate(branches):
        c = colors[j % len(colors)]
        label = b.name or f"NNM {b.mode}"
        ax.plot(b.energy, b.frequency_hz, "-", color=c, lw=1.0, alpha=0.6)
        st = b.stable
        ax.plot(b.energy[st], b.frequency_hz[st], "o", ms=3.5, color=c, label=f"{label} stable")
        if np.any(~st):
            ax.plot(b.energy[~st], b.frequency_hz[~st], "o", ms=4, mfc="none", color=c, label=f"{label} unstable")
        for e in b.events:
            if e["kind"] == "fold":
                ax.plot(e["energy"], e["frequency_hz"], "x", color="k", ms=6)
    ax.set_xscale("log")
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency (Hz)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120)
    return ax
