"""Frequency-energy plots (FEP) with matplotlib: frequency (Hz) against energy (J, log axis)."""
from __future__ import annotations

import numpy as np


#: FEP markers of located events by kind: (matplotlib marker, colour)
EVENT_MARKERS = {"fold": ("x", "k"), "branch_point": ("s", "tab:red"), "period_doubling": ("D", "tab:purple"),
                 "torus": ("^", "tab:green")}


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
    seen = set()
    for j, b in enumerate(branches):
        c = colors[j % len(colors)]
        label = b.name or f"NNM {b.mode}"
        ax.plot(b.energy, b.frequency_hz, "-", color=c, lw=1.0, alpha=0.6)
        st = b.stable
        known = not np.all(np.isnan(np.asarray(b.floquet))) if len(b.energy) else True
        ax.plot(b.energy[st], b.frequency_hz[st], "o", ms=3.5, color=c,
                label=f"{label} stable" if known else f"{label} (stability not computed)")
        if np.any(~st):
            ax.plot(b.energy[~st], b.frequency_hz[~st], "o", ms=4, mfc="none", color=c, label=f"{label} unstable")
        for e in b.events:
            marker, colour = EVENT_MARKERS.get(e["kind"], ("o", "k"))
            label = e["kind"].replace("_", " ")
            ax.plot(e["energy"], e["frequency_hz"], marker, color=colour, ms=7, mfc="none", mew=1.5,
                    label=label if label not in seen else None)
            seen.add(label)
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


def plot_atlas(branches, ax=None, path=None, title=None):
    """One FEP of many branches (a sweep's atlas): relative frequency change (%) against energy (J).

    The change of each branch is taken from the linear frequency of its mode on its own model
    (``branch.model``, the variant's model for ``sweep`` / ``load_sweep`` branches), as the method
    computes it (shooting: the Newmark-discretised linear period at the branch's steps per period),
    so the curves start at 0 %.  One colour per mode, one line style per variant (the part of the
    name before ':'); unstable points hollow.
    branches : list of Branch.  ax, path, title : as in ``plot_fep``.  Returns the Axes.
    """
    import matplotlib
    if ax is None and path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    if not isinstance(branches, (list, tuple)):
        branches = [branches]
    branches = [b for b in branches if len(b)]
    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 5))
    linear = {}

    def f_linear(b):
        key = (id(b.model.M), id(b.model.K))
        if key not in linear:
            linear[key] = (b.model, b.model.linear_modes()[0])   # the model is kept so that id() stays unique
        f = linear[key][1][b.mode - 1]
        spp = b.settings.get("steps_per_period") if getattr(b.settings, "method", "") == "shooting" else None
        if spp:
            from ..orbits.shooting import discrete_linear_period
            f = 1.0 / discrete_linear_period(2 * np.pi * f, int(spp), b.settings.get("integrator", "newmark"))
        return f

    modes = sorted({b.mode for b in branches})
    variants = list(dict.fromkeys(b.name.split(":")[0] if ":" in b.name else "" for b in branches))
    cmap = plt.get_cmap("tab20" if len(modes) > 10 else "tab10")
    styles = ["-", "--", ":", "-."]
    branches = sorted(branches, key=lambda b: (variants.index(b.name.split(":")[0] if ":" in b.name else ""), b.mode))
    for b in branches:
        c = cmap(modes.index(b.mode) % cmap.N)
        variant = b.name.split(":")[0] if ":" in b.name else ""
        ls = styles[variants.index(variant) % len(styles)]
        change = 100.0 * (b.frequency_hz / f_linear(b) - 1.0)
        label = f"{variant + ': ' if len(variants) > 1 else ''}NNM {b.mode}"
        ax.plot(b.energy, change, ls, color=c, lw=1.2, label=label)
        st = np.asarray(b.stable, dtype=bool)
        if np.any(~st):
            ax.plot(b.energy[~st], change[~st], "o", ms=3, mfc="none", color=c)
    ax.set_xscale("log")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("energy (J)")
    ax.set_ylabel("frequency change from linear (%)")
    ax.grid(True, which="both", alpha=0.3)
    if branches:
        ax.legend(fontsize=7, ncol=1 + len(branches) // 16, loc="center left", bbox_to_anchor=(1.01, 0.5))
    if title:
        ax.set_title(title)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120, bbox_inches="tight")
    return ax
