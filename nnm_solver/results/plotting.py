"""Frequency-energy plots (FEP) with matplotlib: frequency (Hz) against energy (J, log axis)."""
from __future__ import annotations

import numpy as np


#: FEP markers of located events by kind: (matplotlib marker, colour)
EVENT_MARKERS = {"fold": ("x", "k"), "branch_point": ("s", "tab:red"), "period_doubling": ("D", "tab:purple"),
                 "torus": ("^", "tab:green")}
#: markers of the points off the backbone, one per label in order of appearance ('tongue 3:1', 'tongue 5:1', ...)
OFF_BACKBONE_MARKERS = ("*", "P", "X", "h")
#: their colour: another than the branch's, the same in every plot and in the viewer
OFF_BACKBONE_COLOR = "tab:orange"
#: branch colours in order: none of the colours that mean something on the plot (the orange of the points off the
#: backbone, the black / red / purple / green of the event markers; matplotlib's default cycle drew the second branch orange)
BRANCH_COLORS = ("tab:blue", "tab:brown", "tab:cyan", "tab:pink", "tab:olive", "navy", "tab:gray", "teal")


def off_backbone(branch):
    """[(label, boolean mask of the rows)] of the points of ``branch`` that are not on the backbone family: its
    ``labels`` other than 'backbone' ('tongue 3:1', ...), in order of appearance; [] for a backbone."""
    labels = np.asarray([str(x) for x in getattr(branch, "labels", [])], dtype=object)
    if len(labels) != len(branch.energy):
        return []
    return [(lab, labels == lab) for lab in dict.fromkeys(labels) if lab != "backbone"]


def mark_off_backbone(ax, energy, y, branch, name=None, ms=9):
    """Draw the points of ``branch`` off its backbone over its curve (energy, y: the plotted coordinates), one
    marker per label in OFF_BACKBONE_COLOR (filled: stable, hollow: unstable, as the branch's points), with the
    label in the legend ('NNM 19: tongue 3:1 (off the backbone)')."""
    energy, y = np.asarray(energy), np.asarray(y)
    stable = np.asarray(branch.stable, dtype=bool)
    for k, (label, mask) in enumerate(off_backbone(branch)):
        marker = OFF_BACKBONE_MARKERS[k % len(OFF_BACKBONE_MARKERS)]
        text = f"{name + ': ' if name else ''}{label} (off the backbone)"
        for part, fill in ((mask & stable, OFF_BACKBONE_COLOR), (mask & ~stable, "white")):
            if part.any():
                ax.plot(energy[part], y[part], marker, ms=ms, color=OFF_BACKBONE_COLOR, mfc=fill, mec=OFF_BACKBONE_COLOR
                        if fill == "white" else "k", mew=0.8, zorder=3, label=text)
                text = None


def plot_fep(branches, ax=None, path=None, title=None):
    """Draw the FEP of one or several branches; stable points filled, unstable points hollow, the points off the
    backbone (a tongue's, ``branch.labels``) marked and named in the legend (``mark_off_backbone``).

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
    colors = BRANCH_COLORS
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
        mark_off_backbone(ax, b.energy, b.frequency_hz, b, name=label if len(branches) > 1 else None)
        for e in b.events:
            marker, colour = EVENT_MARKERS.get(e["kind"], ("o", "k"))
            label = e["kind"].replace("_", " ")
            ax.plot(e["energy"], e["frequency_hz"], marker, color=colour, ms=7, mfc="none", mew=1.5, zorder=5,
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
    name before ':'); unstable points hollow; the points off the backbone marked (``mark_off_backbone``).
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
        mark_off_backbone(ax, b.energy, change, b, name=label, ms=6)
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
