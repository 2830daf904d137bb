"""A computed NNM branch: one row per converged periodic orbit, plus tools to look at the orbits."""
from __future__ import annotations

import numpy as np

from .errors import NNMInputError
from .floquet import detect_events
from .reduction import mac
from .shooting import modal_system


class Branch:
    """NNM branch of a model (columns have one row per converged point).

    energy (N,) J, frequency_hz (N,) Hz, period (N,) s, x0, v0 (N, n) initial state (m, m/s) of
    each orbit (t = 0 at the phase condition), floquet (N, 2n) complex multipliers (largest modulus first), stable (N,)
    bool, events: list of dicts (kind, index, energy, frequency_hz, detail).
    status: 'done' | 'max_points' | 'cancelled' | 'failed' | 'running'; message: why it stopped.
    settings: dict (steps_per_period, tol, symmetric, method, ...).
    """

    def __init__(self, model, mode, energy, frequency_hz, period, x0, v0, floquet=None, stable=None,
                 events=None, status="done", message="", settings=None, name=""):
        self.model = model
        self.mode = int(mode)
        self.energy = np.asarray(energy, dtype=float).reshape(-1)
        N = len(self.energy)
        self.frequency_hz = np.asarray(frequency_hz, dtype=float).reshape(N)
        self.period = np.asarray(period, dtype=float).reshape(N)
        self.x0 = np.asarray(x0, dtype=float).reshape(N, model.n)
        self.v0 = np.asarray(v0, dtype=float).reshape(N, model.n)
        self.floquet = (np.full((N, 2 * model.n), np.nan, dtype=complex) if floquet is None
                        else np.asarray(floquet, dtype=complex).reshape(N, 2 * model.n))
        self.stable = (np.ones(N, dtype=bool) if stable is None else np.asarray(stable, dtype=bool).reshape(N))
        if events is None:
            events = detect_events(self.energy, self.frequency_hz, self.floquet, self.stable)
        self.events = list(events)
        self.status = str(status)
        self.message = str(message)
        self.settings = dict(settings or {})
        self.name = str(name)

    def __len__(self):
        return len(self.energy)

    def __repr__(self):
        return (f"Branch(mode={self.mode}, points={len(self)}, "
                f"energy={self.energy.min() if len(self) else 0:.3g}..{self.energy.max() if len(self) else 0:.3g} J, "
                f"status={self.status!r})")

    # ------------------------------------------------------------------ selection
    def _check_index(self, i):
        if not isinstance(i, (int, np.integer)) or not -len(self) <= i < len(self):
            raise NNMInputError(f"point index {i!r} is out of range: the branch has {len(self)} points")
        return int(i) % len(self)

    def subset(self, index):
        """Branch made of the rows ``index`` (slice, index array or boolean mask)."""
        fl = self.floquet[index]
        return Branch(self.model, self.mode, self.energy[index], self.frequency_hz[index], self.period[index],
                      self.x0[index], self.v0[index], fl, self.stable[index], None, self.status,
                      self.message, self.settings, self.name)

    def interpolate(self, s):
        """One-point Branch at fractional index s in [0, N-1] (linear between neighbouring points)."""
        N = len(self)
        if N == 0:
            raise NNMInputError("the branch is empty")
        s = float(s)
        if not 0 <= s <= N - 1:
            raise NNMInputError(f"fractional index {s} is outside 0..{N - 1}")
        j = min(int(np.floor(s)), max(N - 2, 0))
        w = s - j if N > 1 else 0.0
        k = min(j + 1, N - 1)

        def lerp(a):
            return (1 - w) * a[j] + w * a[k]

        x0, v0 = _match_energy(self.model, lerp(self.x0), lerp(self.v0), lerp(self.energy))
        near = j if w < 0.5 else k
        return Branch(self.model, self.mode, [self.model.energy(x0, v0)], [lerp(self.frequency_hz)],
                      [lerp(self.period)], x0[None], v0[None], self.floquet[near][None],
                      [self.stable[near]], [], self.status, f"interpolated at index {s:.3f}", self.settings,
                      self.name)

    def at_energy(self, energy):
        """One-point Branch at energy (J): the first crossing of that energy along the branch."""
        E = self.energy
        for j in range(len(E) - 1):
            lo, hi = sorted((E[j], E[j + 1]))
            if lo <= energy <= hi:
                w = 0.0 if hi == lo else (energy - E[j]) / (E[j + 1] - E[j])
                return self.interpolate(j + w)
        if len(E) and energy == E[-1]:
            return self.interpolate(len(E) - 1)
        raise NNMInputError(f"energy {energy:.4g} J is outside the branch's range "
                            f"{E.min():.4g}..{E.max():.4g} J" if len(E) else "the branch is empty")

    # ------------------------------------------------------------------ orbits
    def motion(self, i, samples=256):
        """The periodic orbit of point i over one period: (t (samples,) s, x (samples, n) m)."""
        t, x, _ = self.orbit(i, samples)
        return t, x

    def velocity(self, i, samples=256):
        """Velocities (samples, n) m/s along the orbit of point i, at the times of motion()."""
        return self.orbit(i, samples)[2]

    def orbit(self, i, samples=256):
        """Orbit of point i: (t (samples,) s, x, v (samples, n) m, m/s), t = k T / samples.

        Shooting branches: the discrete orbit is re-integrated with the branch's own Newmark step
        (the one it converged with), over half a period when the branch used the half-period
        symmetry (the second half is -z(t)), then resampled to ``samples`` times by Fourier
        interpolation.  This reproduces the converged orbit even when it is strongly unstable.
        Harmonic-balance branches: the Fourier series itself.
        """
        i = self._check_index(i)
        samples = int(samples)
        if samples < 2:
            raise NNMInputError("samples must be at least 2")
        if self.settings.get("method") == "harmonic_balance":
            from .hb import hb_motion
            return hb_motion(self, i, samples)
        spp = int(self.settings.get("steps_per_period", 200))
        symmetric = bool(self.settings.get("symmetric", False)) and spp % 2 == 0
        ms = modal_system(self.model)
        T = self.period[i]
        nsteps = spp // 2 if symmetric else spp
        Q, V, ok = ms.orbit(ms.to_modal(self.x0[i]), ms.to_modal(self.v0[i]), T * nsteps / spp, nsteps)
        if not ok:
            raise RuntimeError(f"time integration of the orbit of point {i} failed")
        Q, V = Q[:-1], V[:-1]
        if symmetric:
            Q, V = np.concatenate([Q, -Q]), np.concatenate([V, -V])
        t = np.arange(samples) * T / samples
        return t, ms.to_physical(_resample(Q, samples)), ms.to_physical(_resample(V, samples))

    def harmonics(self, i, n=15):
        """Fourier amplitudes (n+1, n_dof) of the orbit of point i: row k = harmonic k (k=0: mean), m."""
        n = int(n)
        if n < 1:
            raise NNMInputError("n (number of harmonics) must be at least 1")
        samples = max(256, 4 * (n + 1))
        t, x = self.motion(i, samples)
        X = np.fft.rfft(x, axis=0) / samples
        amps = np.abs(X[: n + 1])
        amps[1:] *= 2.0
        return amps

    def mac_to_linear(self, i):
        """MAC (n_modes,) of the NNM shape x0 of point i with each linear mode shape (index k-1: mode k)."""
        i = self._check_index(i)
        _, shapes = self.model.linear_modes()
        return mac(self.x0[i], shapes)[0]

    # ------------------------------------------------------------------ scaling
    def scaled(self, factor):
        """The branch of the same model with every k3 multiplied by ``factor`` (> 0).

        Exact for cubic springs: frequencies unchanged, displacements and velocities / sqrt(factor),
        energies / factor, multipliers unchanged.
        """
        factor = float(factor)
        if not factor > 0 or not np.isfinite(factor):
            raise NNMInputError(f"scale factor must be a positive number, got {factor}")
        r = 1.0 / np.sqrt(factor)
        events = [dict(e, energy=e["energy"] / factor) for e in self.events]
        settings = dict(self.settings, k3_factor=self.settings.get("k3_factor", 1.0) * factor)
        return Branch(self.model.scaled(factor), self.mode, self.energy / factor, self.frequency_hz,
                      self.period, self.x0 * r, self.v0 * r, self.floquet, self.stable, events, self.status,
                      self.message, settings, self.name)


def _resample(X, samples):
    """Periodic samples X (N, n) on a uniform grid -> (samples, n) by Fourier interpolation."""
    N = len(X)
    if samples == N:
        return X
    F = np.fft.rfft(X, axis=0)
    m = samples // 2 + 1
    G = np.zeros((m, X.shape[1]), dtype=complex)
    k = min(m, len(F))
    G[:k] = F[:k]
    if samples % 2 == 0 and k == m and N > samples:
        G[-1] = G[-1].real  # the Nyquist term of a real signal
    if N % 2 == 0 and k == len(F) and samples > N:
        G[k - 1] *= 0.5     # split the old Nyquist term between +/- frequencies
    return np.fft.irfft(G, n=samples, axis=0) * (samples / N)


def _match_energy(model, x, v, energy):
    """Scale (x, v) by c > 0 so that its energy is ``energy``: E2 c^2 + E4 c^4 = energy."""
    e_tot = model.energy(x, v)
    d = model.spring_matrix @ x
    e4 = float(np.sum(0.25 * model.k3 * d ** 4))
    e2 = e_tot - e4
    if e2 <= 0 or energy <= 0:
        return x, v
    if abs(e4) < 1e-14 * e2:
        c2 = energy / e2
    else:
        disc = e2 * e2 + 4 * e4 * energy
        if disc < 0:
            return x, v
        c2 = (-e2 + np.sqrt(disc)) / (2 * e4)
    if not c2 > 0:
        return x, v
    c = np.sqrt(c2)
    return c * x, c * v
