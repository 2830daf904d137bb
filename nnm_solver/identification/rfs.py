r"""The restoring force surface (RFS) of a connection from two measured accelerations (seed §4.1.3).

Newton's second law at the point on one side of a connection (seed eq. 20-21, with a measured force):

    m_c x''_c(t) + f_r(x_rel, x'_rel) = F(t)   =>   f_r = F - m_c x''_c         (N)

where x_rel = x_c - x_o is the relative displacement of the connection (m), obtained, as in the paper, by
integrating the two accelerations x''_c ("acceleration", the side whose mass is m_c) and x''_o
("acceleration_other") twice.  Plotted against (x_rel, x'_rel) the restoring force is the surface of
Fig. 7; its zero-velocity section is the stiffness curve, and a law such as  f_r = k x + k3 x^3  (eq. 22)
fitted to it (``RestoringForceSurface.fit``, rfs_fit.py) is the connection's nonlinear spring.  f_r is the
force of the connection alone only when m_c is held by nothing else (otherwise the other forces on the
point add to it: the paper's caveat).

Integration (``integrate``): cumulative Simpson (error O((w dt)^4), 5e-5 at 20 samples a period, where
the trapezoid rule's O((w dt)^2) would be 0.8 %), then the drift removed from the velocity and again from
the displacement: the best straight line (the unknown initial value and a constant acceleration offset of
the sensors), then a zero-phase 4th-order Butterworth high-pass (scipy ``sosfiltfilt``) at
``highpass_hz``, which removes the random walk that integrated sensor noise leaves below it.  By default
the cut-off is a fifth of the dominant frequency of the relative velocity; the response above 2.5 times
the cut-off passes within 0.1 % (|H|^2 = 1 / (1 + (fc / f)^8)).  The filter's start-up at both ends is
left out of the fits and plots (``valid``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NNMInputError, finite_number
from .settings import IDENTIFICATION

__all__ = ["RestoringForceSurface", "rfs", "integrate", "dominant_frequency", "HIGHPASS_FRACTION"]

#: an alias of settings.py's IDENTIFICATION.highpass_fraction (the code reads that)
HIGHPASS_FRACTION = IDENTIFICATION.highpass_fraction


def _signal(name, values, n=None):
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise NNMInputError(f"rfs: {name} must be an array of numbers") from None
    if a.ndim != 1:
        raise NNMInputError(f"rfs: {name} must be one-dimensional (one value per sample), got shape {a.shape}")
    if n is not None and len(a) != n:
        raise NNMInputError(f"rfs: {name} has {len(a)} samples, t has {n}; give one value per time sample")
    if not np.all(np.isfinite(a)):
        raise NNMInputError(f"rfs: {name} contains NaN or infinite values (sample {int(np.argmin(np.isfinite(a)))}); "
                            f"cut the record or fill the gap")
    return a


def _time(t):
    t = _signal("t", t)
    if len(t) < IDENTIFICATION.min_samples:
        raise NNMInputError(f"rfs: {len(t)} samples are too few; give at least {IDENTIFICATION.min_samples} "
                            f"(a record of many cycles)")
    dt = np.diff(t)
    step = (t[-1] - t[0]) / (len(t) - 1)
    if not np.all(dt > 0):
        raise NNMInputError(f"rfs: t is not strictly increasing (sample {int(np.argmin(dt > 0)) + 1}); sort the record")
    if np.max(np.abs(dt - step)) > 1e-3 * step:
        raise NNMInputError(f"rfs: t is not uniformly sampled (steps from {dt.min():.6g} to {dt.max():.6g} s); "
                            f"resample the record at a constant rate")
    return t, step


def dominant_frequency(y, dt, min_cycles=5):
    """Frequency (Hz) of the largest peak of |FFT(y)| above ``min_cycles`` cycles per record."""
    spec = np.abs(np.fft.rfft(y - np.mean(y)))
    f = np.fft.rfftfreq(len(y), dt)
    keep = f >= min_cycles / (len(y) * dt)
    if not np.any(keep) or not np.any(spec[keep] > 0):
        return 0.0
    return float(f[keep][np.argmax(spec[keep])])


def _detrend(y, t):
    return y - np.polyval(np.polyfit(t - t[0], y, 1), t - t[0])


def _highpass(y, fc, dt):
    from scipy.signal import butter, sosfiltfilt

    sos = butter(4, fc, "highpass", fs=1.0 / dt, output="sos")
    pad = int(min(len(y) - 1, np.ceil(3.0 / (fc * dt))))
    return sosfiltfilt(sos, y, padtype="odd", padlen=pad)


def integrate(t, a, highpass_hz):
    """(velocity, displacement) of the acceleration samples ``a`` (m/s^2) at uniform times ``t`` (s):
    cumulative Simpson, the best line removed, and a high-pass at ``highpass_hz`` (0: none) after each
    integration (module doc)."""
    from scipy.integrate import cumulative_simpson

    dt = t[1] - t[0]
    out = []
    y = a
    for _ in range(2):
        y = _detrend(cumulative_simpson(y, x=t, initial=0.0), t)
        if highpass_hz > 0:
            y = _highpass(y, highpass_hz, dt)
        out.append(y)
    return out[0], out[1]


@dataclass(frozen=True, eq=False)
class RestoringForceSurface:
    """A connection's restoring force against its relative displacement and velocity (seed Fig. 7).

    t (s), displacement x_rel (m), velocity x'_rel (m/s) and force f_r = F - m_c x''_c (N), one value per
    sample; ``valid`` marks the samples away from the integration filter's start-up at both ends (the
    fits and plots use those); ``mass`` m_c (kg), ``highpass_hz`` the drift filter's cut-off (Hz, 0: none).
    """

    t: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    force: np.ndarray
    valid: np.ndarray
    mass: float
    highpass_hz: float

    def fit(self, law="cubic", **options):
        """Least-squares fit of a force law to the surface: ``"cubic"`` (f = k x + k3 x^3, eq. 22),
        ``"linear"``, ``"polynomial"`` (``powers=(1, 2, 3)``) or ``"piecewise_linear"`` (slopes k0, k1, ...
        past breakpoints d1 < ...; ``breakpoints=[...]`` given or ``n_breakpoints=1`` found), each plus a
        viscous term c x' and a constant offset.  Returns a ``FittedLaw`` (rfs_fit.py)."""
        from .rfs_fit import fit_law

        v = self.valid
        return fit_law(law, self.displacement[v], self.velocity[v], self.force[v], **options)

    def stiffness_curve(self, band=0.05):
        """The zero-velocity section (x_rel (m), f_r (N)): the valid samples with |x'_rel| < band max|x'_rel|,
        sorted by displacement (the right plots of Fig. 7)."""
        band = finite_number(band, "rfs stiffness_curve band")
        if not 0 < band <= 1:
            raise NNMInputError(f"rfs stiffness_curve band {band} must be in (0, 1] (fraction of the peak velocity)")
        x, v, f = self.displacement[self.valid], self.velocity[self.valid], self.force[self.valid]
        pick = np.abs(v) < band * np.max(np.abs(v))
        order = np.argsort(x[pick])
        return x[pick][order], f[pick][order]

    def damping_curve(self, band=0.05):
        """The zero-displacement section (x'_rel (m/s), f_r (N)), sorted by velocity."""
        band = finite_number(band, "rfs damping_curve band")
        if not 0 < band <= 1:
            raise NNMInputError(f"rfs damping_curve band {band} must be in (0, 1] (fraction of the peak displacement)")
        x, v, f = self.displacement[self.valid], self.velocity[self.valid], self.force[self.valid]
        pick = np.abs(x) < band * np.max(np.abs(x))
        order = np.argsort(v[pick])
        return v[pick][order], f[pick][order]

    def plot(self, law=None, path=None, band=0.05, title=None):
        """Fig. 7 of the seed: the surface (left) and the stiffness curve with ``law`` (a FittedLaw) drawn over
        it (right).  Saved to ``path`` if given; returns the figure (rfs_plot.py)."""
        from .rfs_plot import plot_rfs

        return plot_rfs(self, law=law, path=path, band=band, title=title)


def _from_record(t, acceleration, acceleration_other, force):
    """(t, a, a_other, force) as arrays: from a Measurement's channels when t is one, else unchanged."""
    from ..files.importers.measured import Measurement

    if not isinstance(t, Measurement):
        return t, acceleration, acceleration_other, force
    if t.kind != "time":
        raise NNMInputError(f"rfs: {t.source} is a frequency record; the restoring force surface needs time series")
    out = []
    for name, key in (("acceleration", acceleration), ("acceleration_other", acceleration_other), ("force", force)):
        if key is None:
            out.append(None)
            continue
        j = t.index(key)
        q, need = t.quantities[j], "force" if name == "force" else "acceleration"
        if q not in (need, "unknown"):
            raise NNMInputError(f"rfs: {name} channel {t.labels[j]!r} of {t.source} is a {q}, not {need}")
        out.append(t.data[:, j].real)
    return (t.t, *out)


def rfs(t, acceleration, acceleration_other, mass, force=None, *, highpass_hz=None):
    """The restoring force surface of a connection (seed §4.1.3, eq. 20-21).

    t : (N,) uniformly sampled times (s).  acceleration : (N,) x''_c, measured at the connection's side of
    mass ``mass`` (m_c, kg); acceleration_other : (N,) x''_o, the other side (m/s^2).  force : optional (N,)
    external force on the point c (N; e.g. a shaker there), default none.  highpass_hz : drift filter's
    cut-off (Hz); default a fifth of the relative velocity's dominant frequency; 0 removes only the best
    straight line.  Returns a ``RestoringForceSurface`` with x_rel = x_c - x_o, x'_rel and f_r = F - m_c x''_c.

    A measured time record (``nnm.read_measured``) may stand for t: then acceleration, acceleration_other
    and force name its channels (index, label, ``"node 14 uz"`` or (node, direction)):
    ``rfs(record, "node 14 uz", "node 20 uz", mass)``.
    """
    t, acceleration, acceleration_other, force = _from_record(t, acceleration, acceleration_other, force)
    t, dt = _time(t)
    n = len(t)
    a = _signal("acceleration", acceleration, n)
    b = _signal("acceleration_other", acceleration_other, n)
    m = finite_number(mass, "rfs: mass")
    if not m > 0:
        raise NNMInputError(f"rfs: mass {m} must be positive (kg: the mass m_c at the measured side)")
    f_ext = np.zeros(n) if force is None else _signal("force", force, n)
    rel = a - b
    if not np.any(rel != rel[0]):
        raise NNMInputError("rfs: the two accelerations are equal at every sample; the connection does not deform "
                            "(check the channels)")
    fd = None
    if highpass_hz is None:
        fd = dominant_frequency(np.cumsum(rel) * dt, dt)
        if fd <= 0:
            raise NNMInputError("rfs: no dominant frequency in the relative motion; give highpass_hz")
        highpass_hz = IDENTIFICATION.highpass_fraction * fd
    fc = finite_number(highpass_hz, "rfs: highpass_hz")
    duration = t[-1] - t[0]
    if fc < 0 or fc >= 0.5 / dt:
        raise NNMInputError(f"rfs: highpass_hz {fc} must be in [0, {0.5 / dt:.6g}) Hz (0: no filter)")
    if 0 < fc < 10.0 / duration:
        raise NNMInputError(f"rfs: the record ({duration:.6g} s) is shorter than 10 periods of the drift filter's "
                            f"cut-off {fc:.6g} Hz; measure longer or give a higher highpass_hz")
    velocity, displacement = integrate(t, rel, fc)
    edge = min(2.0 / fc, 0.1 * duration) if fc > 0 else 0.05 * duration
    valid = (t >= t[0] + edge) & (t <= t[-1] - edge)
    return RestoringForceSurface(t=t, displacement=displacement, velocity=velocity, force=f_ext - m * a,
                                 valid=valid, mass=m, highpass_hz=fc)
