"""Amplitude-frequency plot of forced responses over NNM backbones, with the energy-balance prediction
of their resonance peaks (matplotlib)."""
from __future__ import annotations

import numpy as np

from .forced import backbone_amplitude, peak_of_series

__all__ = ["plot_forced"]


def plot_forced(responses, dof, backbones=(), predictions=(), ax=None, path=None, title=None, scale=1.0,
                unit="m", samples=256):
    """Peak displacement at ``dof`` against frequency (Hz).

    responses : ForcedResponse or list of them: solid where stable, dashed where unstable, folds marked x.
    backbones : Branch or list: the conservative NNMs (peak displacement of each orbit), black.
    predictions : EnergyBalance or list: for each response whose force is a multiple of the prediction's
        force pattern, the predicted resonance peak (star, same colour), and the energy-balance curve is
        not drawn (it lies on the backbone).
    scale, unit : amplitudes are multiplied by ``scale`` and labelled ``unit`` (e.g. 1e3, "mm").
    ax : Axes (created if None); path : save the figure there.  Returns the Axes.
    """
    import matplotlib
    if ax is None and path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    def as_list(x):
        if x is None:
            return []
        return list(x) if isinstance(x, (list, tuple)) else [x]

    responses, backbones, predictions = as_list(responses), as_list(backbones), as_list(predictions)
    if ax is None:
        _, ax = plt.subplots(figsize=(7, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for j, r in enumerate(responses):
        c = colors[j % len(colors)]
        k = r.dof_index(dof)
        a = r.amplitude(k) * scale
        f = r.frequency_hz
        label = r.name or f"|F| = {np.linalg.norm(r.force):.3g} N"
        st = np.asarray(r.stable, dtype=bool)
        cuts = [0, *(np.flatnonzero(np.diff(st.astype(int)) != 0) + 1), len(st)]
        seen = set()
        for s0, s1 in zip(cuts[:-1], cuts[1:]):            # runs of one stability, joined to the next run
            kind = bool(st[s0])
            ax.plot(f[s0:s1 + 1], a[s0:s1 + 1], "-" if kind else "--", color=c, lw=1.4 if kind else 1.0,
                    label=None if kind in seen else (label if kind else f"{label} (unstable)"))
            seen.add(kind)
        if r.folds:
            fa = [peak_of_series(r.basis, fd["coefficients"][:, k][None])[0] * scale for fd in r.folds]
            ax.plot(r.fold_frequencies_hz, fa, "x", color=c, ms=7, mew=1.5)
        for p in predictions:
            try:
                s = p.scale_of(r.force)
            except Exception:
                continue
            pk = p.at_scale(s, k)
            if pk is not None:
                ax.plot(pk["frequency_hz"], pk["amplitude"] * scale, "*", color=c, ms=11, mec="k", mew=0.6,
                        label=f"{label}: energy balance")
    for b in backbones:
        amp = backbone_amplitude(b, responses[0].dof_index(dof) if responses else int(dof), samples) * scale
        ax.plot(b.frequency_hz, amp, "k-", lw=1.0, alpha=0.8, label=b.name or f"NNM {b.mode} backbone")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"peak displacement ({unit})")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    if path is not None:
        ax.figure.tight_layout()
        ax.figure.savefig(path, dpi=120)
    return ax
