"""The picked orbit as an animated GIF (teaching, reports): the deformed mesh over one period,
projected as seen from a chosen direction, coloured like the 3D view (peak displacement over the
period) with its colour bar.

Drawn with matplotlib (a PolyCollection per frame, faces sorted back to front) and written by
matplotlib's animation machinery with its Pillow writer: no encoder of our own.
"""
from __future__ import annotations

import os
import tempfile

import numpy as np

from .animation import format_length
from .info import length_unit

#: frames per period, frames per second and size (px) of the GIF
GIF_FRAMES = 24
GIF_FPS = 12
GIF_SIZE = (560, 420)
#: faces drawn at most (a larger mesh is drawn with every k-th face, the GIF stays cheap)
GIF_MAX_FACES = 20000


def view_basis(view_dir):
    """(right, up, forward) unit vectors of a camera looking along ``view_dir`` (z up; y up when the
    camera looks along z)."""
    f = np.asarray(view_dir, dtype=float)
    f = f / max(np.linalg.norm(f), 1e-300)
    ref = np.array([0.0, 0.0, 1.0]) if abs(f[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
    r = np.cross(f, ref)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    return r, u, f


def colorbar_ticks(peak):
    """(scale, unit) for a colour bar from 0 to ``peak`` m, in m, mm, µm or nm."""
    return length_unit([peak]) if peak > 0 else (1.0, "m")


def orbit_gif(anim, amplification, view_dir, title="", frames=GIF_FRAMES, fps=GIF_FPS, size=GIF_SIZE,
              cmap="jet"):
    """GIF bytes of ``anim`` (animation.OrbitAnimation) over one period: vertices displaced by
    ``amplification`` x the physical motion, seen along ``view_dir`` (orthographic), faces coloured by
    peak displacement (as in the 3D view) with a colour bar in physical units."""
    import matplotlib
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    faces = np.asarray(anim.faces)
    if len(faces) > GIF_MAX_FACES:
        faces = faces[:: int(np.ceil(len(faces) / GIF_MAX_FACES))]
    r, u, f = view_basis(view_dir)
    phases = np.arange(int(frames)) / int(frames)
    verts = anim.vertices[None] + amplification * anim.displacement(phases)          # (k, V, 3)
    xy = np.stack([verts @ r, verts @ u], axis=-1)                                     # (k, V, 2)
    depth = (verts @ f)[:, faces].mean(axis=2)                                         # (k, F)
    scale = anim.peak_max if anim.peak_max > 0 else 1.0
    base = matplotlib.colormaps[cmap](np.clip(anim.peak[faces].mean(axis=1) / scale, 0, 1))[:, :3]

    def shaded(k):
        p = verts[k][faces]
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        return base * (0.55 + 0.45 * np.abs(n @ f))[:, None]

    dpi = 100
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi, facecolor="white")
    FigureCanvasAgg(fig)
    ax = fig.add_axes([0.02, 0.04, 0.80, 0.84])
    ax.set_aspect("equal")
    ax.set_axis_off()
    lo, hi = xy.reshape(-1, 2).min(axis=0), xy.reshape(-1, 2).max(axis=0)
    pad = 0.04 * float(max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    coll = PolyCollection([], edgecolors="none", antialiaseds=False)
    ax.add_collection(coll)
    fig.suptitle(title, fontsize=9)
    k_scale, unit = colorbar_ticks(anim.peak_max)
    cax = fig.add_axes([0.86, 0.12, 0.03, 0.70])
    sm = matplotlib.cm.ScalarMappable(norm=matplotlib.colors.Normalize(0.0, anim.peak_max * k_scale), cmap=cmap)
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label(f"peak displacement ({unit})", fontsize=8)
    cb.ax.tick_params(labelsize=7)
    stamp = ax.text(0.01, 0.01, "", transform=ax.transAxes, fontsize=8, color="#444444")

    def draw(k):
        order = np.argsort(-depth[k])                      # back to front (the camera looks along +f)
        coll.set_verts(xy[k][faces[order]])
        coll.set_facecolor(shaded(k)[order])
        stamp.set_text(f"t/T = {phases[k]:.2f}   displacements x{amplification:.3g}")
        return coll, stamp

    movie = FuncAnimation(fig, draw, frames=len(phases), blit=False)
    fd, path = tempfile.mkstemp(suffix=".gif", prefix="nnm-view-")
    os.close(fd)
    try:
        movie.save(path, writer=PillowWriter(fps=fps), dpi=dpi)
        with open(path, "rb") as fh:
            return fh.read()
    finally:
        os.unlink(path)


def gif_title(where, pd, peak):
    """Title line of the GIF: branch and point, frequency, energy, true peak displacement."""
    return f"{where}\nf = {pd.frequency:.5g} Hz, E = {pd.energy:.4g} J, peak {format_length(peak)}"
