r"""A computed forced response: the periodic responses to f(t) = force cos(omega t) along a frequency range.

One row per converged orbit: its frequency (Hz) and its physical Fourier coefficients X (N_b, n) (m) on the
forced basis (``orbits/forced_hb.py``: "full" = mean, cos and sin of 1..H; "odd" = cos and sin of the odd
harmonics), x(t) = sum_j X[j] c_j(omega t), t = 0 at a crest of the force.  Amplitudes, phases, orbits and
the peak are computed from them; the stability columns come from the continuation (``driver/forced.py``).
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from ..orbits.forced_hb import ForcedBasis

__all__ = ["ForcedResponse", "FORCED_STATUSES", "STABILITY_METHODS", "backbone_amplitude", "peak_of_samples"]

#: why a forced-response continuation stopped
FORCED_STATUSES = {
    "done": "the end of the frequency range was reached (last point exactly at it)",
    "max_points": "max_points orbits were computed before the end of the range",
    "left_range": "the curve turned back and left the range at its start (e.g. an isola or a closed curve)",
    "failed": "the continuation could not converge a step even at the smallest step length",
    "cancelled": "stopped by the caller",
}

#: how the stability column was computed: "hill" (Floquet multipliers by Hill's method with damping),
#: "fold" (the sign of det dR/dx: saddle-node instabilities only), "none" (not computed: all True)
STABILITY_METHODS = ("hill", "fold", "none")


class ForcedResponse:
    """Periodic responses of a model to ``force`` cos(omega t) (N), one row per converged orbit.

    Columns: frequency_hz (N,) Hz; coefficients (N, N_b, n) physical Fourier coefficients (m) on the
    ``basis``; stable (N,) bool; floquet (N, 2n) complex Floquet multipliers (NaN unless
    stability == "hill"); fold_sign (N,) int, the sign of det dR/dx at fixed frequency (-1: unstable
    between two folds, module ``orbits/forced_hb.py``).  folds: list of dicts (index: the fold lies
    between rows index-1 and index; frequency_hz; coefficients (N_b, n)), located by the continuation.
    force (n,) N; damping (n,) modal damping ratios zeta_k (mode k at index k-1); damping_matrix (n, n)
    or None; harmonics, basis ("full" / "odd"), samples (AFT), condensed, stability (STABILITY_METHODS);
    status (FORCED_STATUSES) and message; name; settings: dict of the other arguments used.

    ``amplitude(dof)`` peak |x_dof(t)| over the period (m); ``phase(dof)`` phase of the fundamental relative
    to the force (rad, x_1(t) = |a_1| cos(omega t + phase): about -pi/2 at phase resonance);
    ``orbit(i)`` (t, x, v); ``peak(dof)`` the resonance peak.  ``dof``: an index or a DOF label.
    """

    def __init__(self, model, force, frequency_hz, coefficients, *, harmonics, basis="full", samples=None,
                 damping=None, damping_matrix=None, floquet=None, stable=None, fold_sign=None, folds=None,
                 status="done", message="", name="", condensed=False, stability="none", settings=None):
        self.model = model
        n = model.n
        self.force = np.asarray(force, dtype=float).reshape(n)
        self.harmonics = int(harmonics)
        self.basis_kind = str(basis)
        self.samples = None if samples is None else int(samples)
        self.basis = ForcedBasis(self.harmonics, self.basis_kind, self.samples)
        self.frequency_hz = np.asarray(frequency_hz, dtype=float).reshape(-1)
        N = len(self.frequency_hz)
        self.coefficients = np.asarray(coefficients, dtype=float).reshape(N, len(self.basis), n)
        self.damping = np.zeros(n) if damping is None else np.asarray(damping, dtype=float).reshape(n)
        self.damping_matrix = None if damping_matrix is None else np.asarray(damping_matrix, dtype=float)
        self.floquet = (np.full((N, 2 * n), np.nan, dtype=complex) if floquet is None
                        else np.asarray(floquet, dtype=complex).reshape(N, 2 * n))
        self.stable = np.ones(N, dtype=bool) if stable is None else np.asarray(stable, dtype=bool).reshape(N)
        self.fold_sign = np.ones(N, dtype=int) if fold_sign is None else np.asarray(fold_sign, dtype=int).reshape(N)
        self.folds = [dict(f) for f in (folds or [])]
        self.status = str(status)
        self.message = str(message)
        self.name = str(name)
        self.condensed = bool(condensed)
        self.stability = str(stability)
        self.settings = dict(settings or {})

    # ------------------------------------------------------------------ basics
    def __len__(self):
        return len(self.frequency_hz)

    def __repr__(self):
        rng = (f"{self.frequency_hz.min():.6g}..{self.frequency_hz.max():.6g} Hz" if len(self) else "empty")
        return (f"ForcedResponse({self.name + ', ' if self.name else ''}points={len(self)}, {rng}, "
                f"folds={len(self.folds)}, status={self.status!r})")

    @property
    def period(self):
        """Periods (N,) s."""
        return 1.0 / self.frequency_hz

    @property
    def fold_frequencies_hz(self):
        """Frequencies (Hz) of the located folds, in the order met along the curve."""
        return np.array([f["frequency_hz"] for f in self.folds], dtype=float)

    def dof_index(self, dof):
        """The 0-based index of ``dof`` (an index, or one of the model's DOF labels)."""
        n = self.model.n
        if isinstance(dof, str):
            labels = self.model.dof_labels or []
            if dof not in labels:
                raise NNMInputError(f"no DOF labelled {dof!r} in the model (labels: model.dof_labels)")
            return labels.index(dof)
        if not isinstance(dof, (int, np.integer)) or isinstance(dof, bool) or not -n <= dof < n:
            raise NNMInputError(f"dof {dof!r} is out of range: the model has DOFs 0..{n - 1}")
        return int(dof) % n

    def check_index(self, i):
        if not isinstance(i, (int, np.integer)) or isinstance(i, bool) or not -len(self) <= i < len(self):
            raise NNMInputError(f"point index {i!r} is out of range: the response has {len(self)} points")
        return int(i) % len(self)

    # ------------------------------------------------------------------ orbits
    def orbit(self, i, samples=256):
        """Orbit of point i: (t (samples,) s, x, v (samples, n) m, m/s), t = k T / samples (t = 0: force crest)."""
        i = self.check_index(i)
        samples = int(samples)
        if samples < 2:
            raise NNMInputError("samples must be at least 2")
        w = 2 * np.pi * self.frequency_hz[i]
        theta = 2 * np.pi * np.arange(samples) / samples
        X = self.coefficients[i]
        return theta / w, self.basis.functions(theta) @ X, w * (self.basis.derivatives(theta) @ X)

    def motion(self, i, samples=256):
        t, x, _ = self.orbit(i, samples)
        return t, x

    def amplitude(self, dof):
        """Peak displacement max_t |x_dof(t)| over the period (N,) m, from the Fourier series (sampled, then
        refined by Newton on dx/dt = 0)."""
        return peak_of_series(self.basis, self.coefficients[:, :, self.dof_index(dof)])

    def harmonic_amplitudes(self, dof):
        """Amplitudes (N, H + 1) of harmonics 0..H at ``dof`` (m; column 0: |mean|)."""
        X = self.coefficients[:, :, self.dof_index(dof)]
        out = np.zeros((len(self), self.harmonics + 1))
        for j, h in enumerate(self.basis.h):
            out[:, h] += X[:, j] ** 2
        return np.sqrt(out)

    def phase(self, dof):
        """Phase (N,) rad of the fundamental at ``dof`` relative to the force: x_1(t) = |a_1| cos(omega t + phase),
        unwrapped along the curve (about 0 below a resonance, -pi/2 at phase resonance, -pi above, at a
        driving point)."""
        X = self.coefficients[:, :, self.dof_index(dof)]
        c1 = self.basis.cos1
        ph = np.angle(X[:, c1] - 1j * X[:, c1 + 1])
        return np.unwrap(ph) if len(ph) else ph

    def phase_resonance(self, dof, phase=-np.pi / 2):
        """The points where the fundamental at ``dof`` lags the force by 90 degrees (``phase``): a list of
        dict(index (fractional row), frequency_hz, amplitude (m)), linear interpolation between the two rows
        bracketing each crossing of the unwrapped phase (the phase-resonance criterion of a test)."""
        ph = self.phase(dof)
        a = self.amplitude(dof)
        out = []
        for j in range(len(ph) - 1):
            d0, d1 = ph[j] - phase, ph[j + 1] - phase
            if d0 == 0 or d0 * d1 < 0:
                w = d0 / (d0 - d1)
                f = (1 - w) * self.frequency_hz[j] + w * self.frequency_hz[j + 1]
                amp = (1 - w) * a[j] + w * a[j + 1]
                out.append(dict(index=float(j + w), frequency_hz=float(f), amplitude=float(amp)))
        return out

    def peak(self, dof):
        """The resonance peak at ``dof``: dict(index, frequency_hz, amplitude) at the largest amplitude,
        refined by a parabola through the neighbouring points (in their chord length)."""
        if not len(self):
            raise NNMInputError("the forced response is empty")
        a = self.amplitude(dof)
        f = self.frequency_hz
        k = int(np.argmax(a))
        out = dict(index=k, frequency_hz=float(f[k]), amplitude=float(a[k]))
        if 0 < k < len(a) - 1:
            sl = slice(k - 1, k + 2)
            fa, aa = f[sl] / f[k], a[sl] / a[k]
            t = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(fa), np.diff(aa)))])
            ca, cf = np.polyfit(t, aa, 2), np.polyfit(t, fa, 2)
            if ca[0] < 0:
                ts = float(np.clip(-ca[1] / (2 * ca[0]), t[0], t[-1]))
                out.update(frequency_hz=float(np.polyval(cf, ts) * f[k]), amplitude=float(np.polyval(ca, ts) * a[k]))
        return out

    def subset(self, index):
        """ForcedResponse of the rows ``index`` (slice, index array or mask); the folds are kept."""
        return ForcedResponse(self.model, self.force, self.frequency_hz[index], self.coefficients[index],
                              harmonics=self.harmonics, basis=self.basis_kind, samples=self.samples,
                              damping=self.damping, damping_matrix=self.damping_matrix, floquet=self.floquet[index],
                              stable=self.stable[index], fold_sign=self.fold_sign[index], folds=self.folds,
                              status=self.status, message=self.message, name=self.name, condensed=self.condensed,
                              stability=self.stability, settings=self.settings)


def peak_of_series(basis, X, samples=None, newton=6):
    """max_theta |x(theta)| (N,) of the series x = sum_j X[:, j] c_j(theta), X (N, N_b)."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    S = int(samples or max(64, 16 * basis.harmonics))
    theta = 2 * np.pi * np.arange(S) / S
    x = X @ basis.functions(theta).T
    k = np.argmax(np.abs(x), axis=1)
    th = theta[k]
    h = basis.h.astype(float)
    for _ in range(newton):   # x'(th) = 0: x'' from the basis (c_j'' = -h^2 c_j)
        d1 = np.einsum("ij,ij->i", X, basis.derivatives(th))
        d2 = -np.einsum("ij,ij->i", X, basis.functions(th) * h * h)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(d2 != 0, d1 / d2, 0.0)
        th = th - np.clip(step, -2 * np.pi / S, 2 * np.pi / S)
    best = np.abs(np.einsum("ij,ij->i", X, basis.functions(th)))
    return np.maximum(best, np.abs(x).max(axis=1))


def peak_of_samples(x):
    """max |x| (...) of uniform periodic samples x (S, ...) over one period, refined by a parabola through the
    largest sample and its two neighbours (exact to O(h^3) for a smooth signal)."""
    x = np.abs(np.asarray(x, dtype=float))
    S = len(x)
    k = np.argmax(x, axis=0)
    idx = np.indices(k.shape)
    idx = tuple(idx)                                  # x[(k, *idx)]: Python 3.10 has no starred index
    y0, y1, y2 = x[((k - 1) % S,) + idx], x[(k,) + idx], x[((k + 1) % S,) + idx]
    den = y0 - 2 * y1 + y2
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(den < 0, 0.5 * (y0 - y2) / den, 0.0)
    return np.maximum(y1 - 0.25 * (y0 - y2) * d, y1)


def backbone_amplitude(branch, dof, samples=256):
    """Peak displacement max_t |x_dof(t)| (N,) m of every orbit of an NNM ``branch`` (a Branch), dof an index."""
    return np.array([peak_of_samples(branch.orbit(i, samples)[1][:, dof]) for i in range(len(branch))])
