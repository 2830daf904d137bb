"""The restoring force surface and its stiffness curve as in the seed's Fig. 7 (matplotlib)."""
from __future__ import annotations

import numpy as np

from .settings import IDENTIFICATION


def plot_rfs(surface, law=None, path=None, band=0.05, title=None):
    """Left: f_r (N) over relative displacement (m) and velocity (m/s), a 3-D scatter coloured by force.
    Right: the stiffness curve (|velocity| < band x its peak) with the elastic part g(x) + f0 of ``law``
    (a FittedLaw) over it.  Saved to ``path`` (PNG, PDF, ... by extension) if given; returns the figure."""
    import matplotlib
    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    v = surface.valid
    x, xd, f = surface.displacement[v], surface.velocity[v], surface.force[v]
    step = max(1, len(x) // IDENTIFICATION.max_surface_points)
    fig = plt.figure(figsize=(11, 4.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.scatter(x[::step], xd[::step], f[::step], c=f[::step], s=1, cmap="viridis")
    ax.set_xlabel("relative displacement (m)")
    ax.set_ylabel("relative velocity (m/s)")
    ax.set_zlabel("restoring force (N)")
    ax.set_title("restoring force surface")
    ax2 = fig.add_subplot(1, 2, 2)
    xs, fs = surface.stiffness_curve(band)
    ax2.plot(xs, fs, ".", ms=2, color="tab:blue", label=f"|velocity| < {band:g} x peak")
    if law is not None:
        grid = np.linspace(np.min(x), np.max(x), 400)
        label = {"cubic": f"k x + k3 x^3: k = {law.k:.4g} N/m, k3 = {law.k3 or 0.0:.4g} N/m^3",
                 "piecewise_linear": "piecewise linear: k = " + ", ".join(f"{k:.4g}" for k in law.stiffnesses)
                 + " N/m"}.get(law.kind, f"{law.kind} fit")
        ax2.plot(grid, law.elastic_force(grid) + law.offset, "-", color="tab:red", lw=1.5, label=label)
        ax2.plot(grid, law.k * grid + law.offset, "--", color="0.4", lw=1.0, label="linear part k x")
    ax2.set_xlabel("relative displacement (m)")
    ax2.set_ylabel("restoring force (N)")
    ax2.set_title("stiffness curve (zero-velocity section)")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
