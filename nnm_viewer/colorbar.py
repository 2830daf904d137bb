"""The colour bar of the 3D view: peak displacement over the period, 0 (blue) to the largest (red),
in the unit that suits it (the colours of animation.OrbitAnimation.colors)."""
from __future__ import annotations

import numpy as np

from .info import length_unit

#: size (px) of the colour bar image in the control panel
COLORBAR_SIZE = (320, 74)


_CACHE: dict = {}


def colorbar_image(peak, cmap="jet", size=COLORBAR_SIZE):
    """RGB image (H, W, 3) uint8 of a horizontal colour bar from 0 to ``peak`` m (the true peak
    displacement of the shown orbit, not amplified), labelled in m, mm, µm or nm (cached: every tab
    showing the same orbit shares the picture)."""
    key = (float(f"{peak:.6g}"), cmap, tuple(size))
    img = _CACHE.get(key)
    if img is None:
        if len(_CACHE) > 64:
            _CACHE.clear()
        img = _CACHE[key] = _render(key[0], cmap, size)
    return img


def _render(peak, cmap, size):
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    scale, unit = length_unit([peak]) if peak > 0 else (1.0, "m")
    dpi = 100
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi, facecolor="white")
    FigureCanvasAgg(fig)
    cax = fig.add_axes([0.05, 0.52, 0.90, 0.26])
    sm = matplotlib.cm.ScalarMappable(norm=matplotlib.colors.Normalize(0.0, max(peak * scale, 1e-300)), cmap=cmap)
    cb = fig.colorbar(sm, cax=cax, orientation="horizontal")
    cb.ax.tick_params(labelsize=7, length=2, pad=1)
    cb.set_label(f"peak displacement over the period ({unit})", fontsize=7, labelpad=1)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
