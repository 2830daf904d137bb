"""From a periodic orbit x(t) to an animated, coloured mesh (GLB with morph targets).

The orbit, sampled uniformly over one period T, is written as a Fourier series
    x(t) = c_0 + sum_{k=1..H} a_k cos(k w t) + b_k sin(k w t),   w = 2 pi / T,
so every harmonic the solver found is kept (not only the linear mode shape).  Mapped to
the mesh, each a_k, b_k becomes a morph target (vertex displacements, m); the animation
samples the weights  A cos(k w t), A sin(k w t)  (A: display amplification) over one
display period.  Vertex colours show the peak displacement magnitude over the period.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from nnm_solver import fourier_coefficients

from .glb import build_glb

#: harmonics whose largest vertex amplitude is below this fraction of the largest are dropped
HARMONIC_CUTOFF = 1e-4


def fourier_fit(t, x, period, n_harm=15):
    """Real Fourier coefficients of samples x (S, n) at uniform times t (S,) s over one period.

    Returns (orders (2H+1,), coeffs (2H+1, n)): rows are c_0, a_1, b_1, a_2, b_2, ...;
    ``orders`` gives the harmonic number k of each row; H = min(n_harm, (S - 1) // 2).  The
    coefficients are the solver's (``fourier_coefficients``: x = c_0 + sum Re(c_k exp(i k w t)),
    so a_k = Re c_k, b_k = -Im c_k).  A last sample at t[0] + T (a repeat
    of the first) is dropped.
    """
    t = np.asarray(t, dtype=float).reshape(-1)
    x = np.asarray(x, dtype=float).reshape(len(t), -1)
    period = float(period)
    if len(t) > 2 and abs(t[-1] - t[0] - period) < 1e-9 * period:
        t, x = t[:-1], x[:-1]
    dt = np.diff(t)
    if len(t) < 3 or np.ptp(dt) > 1e-6 * period or abs(len(t) * dt.mean() - period) > 1e-6 * period:
        raise ValueError(f"fourier_fit needs samples uniform over one period ({period:.4g} s), "
                         f"got {len(t)} samples from {t[0]:.4g} to {t[-1]:.4g} s")
    H = int(max(1, min(n_harm, (len(t) - 1) // 2)))
    c = fourier_coefficients(x, H)                                   # phases measured from t[0]
    c *= np.exp(-2j * np.pi * np.arange(H + 1) * t[0] / period)[:, None]
    orders = np.concatenate([[0], np.repeat(np.arange(1, H + 1), 2)])
    coeffs = np.empty((2 * H + 1, x.shape[1]))
    coeffs[0] = c[0].real
    coeffs[1::2] = c[1:].real
    coeffs[2::2] = -c[1:].imag
    return orders, coeffs


@dataclass
class OrbitAnimation:
    """Mesh motion of one orbit, ready to be turned into GLBs.

    base : (V, 3) m, rest vertices plus the mean displacement c_0 (amplified).
    shapes : (T, V, 3) m, physical (not amplified) vertex displacement of each kept
    harmonic row; orders : (T,) harmonic number of each shape; cos_sin : (T,) 0 for cos, 1 for sin.
    peak : (V,) m, peak displacement magnitude of each vertex over the period.
    peak_max : m, largest of them; peak_vertex : its index.  period : s (physical).
    """

    vertices: np.ndarray
    faces: np.ndarray
    mean: np.ndarray
    shapes: np.ndarray
    orders: np.ndarray
    cos_sin: np.ndarray
    peak: np.ndarray
    peak_max: float
    peak_vertex: int
    period: float

    def weights(self, phase, amplification):
        """Morph weights (len(phase), T) at orbit phases (fraction of a period, 0..1)."""
        theta = 2 * np.pi * np.atleast_1d(np.asarray(phase, dtype=float))
        ang = theta[:, None] * self.orders[None, :]
        return amplification * np.where(self.cos_sin[None, :] == 0, np.cos(ang), np.sin(ang))

    def displacement(self, phase):
        """Physical vertex displacements (k, V, 3) m at the given phases (fractions of a period)."""
        W = self.weights(phase, 1.0)
        return self.mean[None] + np.tensordot(W, self.shapes, axes=(1, 0))

    def colors(self, cmap="jet"):
        """Per-vertex RGB uint8 (V, 3): colour map of peak displacement / largest peak."""
        import matplotlib
        scale = self.peak_max if self.peak_max > 0 else 1.0
        rgba = matplotlib.colormaps[cmap](np.clip(self.peak / scale, 0, 1))
        return (rgba[:, :3] * 255).astype(np.uint8)

    def glb(self, amplification, display_period=2.0, keyframes=None, playing=True, phase=0.0):
        """GLB bytes: animated over ``display_period`` s of screen time, or frozen at ``phase``."""
        base = self.vertices + amplification * self.mean
        if len(self.shapes) == 0:
            return build_glb(base, self.faces, self.colors())
        if not playing:
            w0 = self.weights(phase, amplification)[0]
            return build_glb(base, self.faces, self.colors(), targets=self.shapes, default_weights=w0)
        if keyframes is None:
            keyframes = int(np.clip(8 * int(self.orders.max()), 48, 240))
        ph = np.linspace(0.0, 1.0, keyframes + 1)
        return build_glb(base, self.faces, self.colors(), targets=self.shapes,
                         times=ph * display_period, weights=self.weights(ph, amplification),
                         default_weights=self.weights(0.0, amplification)[0])


def orbit_animation(vertices, faces, displacements, t, x, period, n_harm=15, check_frames=96):
    """Build an OrbitAnimation from orbit samples.

    vertices (V, 3) m, faces (F, 3); displacements: callable mapping model coordinates
    (k, n) to vertex displacements (k, V, 3) m (e.g. DisplayMesh.displacements);
    t (S,) s and x (S, n) m: the orbit over one period ``period`` s.
    """
    orders, coeffs = fourier_fit(t, x, period, n_harm)
    U = np.asarray(displacements(coeffs), dtype=float)            # (2H+1, V, 3)
    mean = U[0]
    shapes, kept_orders, cs = U[1:], orders[1:], np.tile([0, 1], (len(orders) - 1) // 2)
    if len(shapes):
        amp = np.sqrt((shapes ** 2).sum(axis=2)).max(axis=1)      # (2H,)
        by_order = {k: amp[kept_orders == k].max() for k in np.unique(kept_orders)}
        top = max(by_order.values())
        keep = np.array([top > 0 and by_order[k] >= HARMONIC_CUTOFF * top for k in kept_orders])
        shapes, kept_orders, cs = shapes[keep], kept_orders[keep], cs[keep]
    anim = OrbitAnimation(vertices=np.asarray(vertices, dtype=float), faces=np.asarray(faces),
                          mean=mean, shapes=shapes, orders=kept_orders, cos_sin=cs,
                          peak=np.zeros(len(vertices)), peak_max=0.0, peak_vertex=0,
                          period=float(period))
    ph = np.arange(check_frames) / check_frames
    mag = np.sqrt((anim.displacement(ph) ** 2).sum(axis=2))       # (k, V)
    anim.peak = mag.max(axis=0)
    anim.peak_vertex = int(np.argmax(anim.peak))
    anim.peak_max = float(anim.peak[anim.peak_vertex])
    return anim


class MeshMapper:
    """Vertex displacements from model coordinates, with the map kept as float32 (n, 3V):
    one fast product per call (DisplayMesh.displacements converts the map at every call).
    A sparse map (a large FE model's, scipy.sparse) stays sparse: float32 CSR (3V, n), one sparse product."""

    def __init__(self, mesh):
        self.nv = len(mesh.vertices)
        D = mesh.displacement_map
        self.sparse = sp.issparse(D)
        if self.sparse:
            self.D = sp.csr_matrix(D, dtype=np.float32)
        else:
            self.Dt = np.ascontiguousarray(np.asarray(D, dtype=np.float32).T)

    def __call__(self, x):
        x = np.asarray(x, dtype=np.float32)
        if self.sparse:
            u = np.asarray(self.D @ x.T, dtype=float).T
        else:
            u = (x @ self.Dt).astype(float)
        return u.reshape(x.shape[:-1] + (self.nv, 3))


def format_length(value):
    """A length in m with a readable unit (nm .. m)."""
    v = abs(float(value))
    for unit, f in (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6), ("nm", 1e-9)):
        if v >= f or unit == "nm":
            return f"{value / f:.3g} {unit}"
    return f"{value:.3g} m"
