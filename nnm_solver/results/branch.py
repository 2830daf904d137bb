"""A computed NNM branch: one row per converged periodic orbit (a Point), plus tools to look at the orbits."""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from ..stability.floquet import detect_events, events_of_rows
from ..fourier import fourier_amplitudes
from ..model.reduction import mac
from ..model.scaling import cubic_scaling
from .multipliers import floquet_columns, multipliers_of
from .rescaled import energy_factor, scaled_event, scaled_message
from .point import PhysicalColumns, Point
from .settings import settings_from_dict
from .stops import STOP_STATUSES
from .tongues import TongueRecord

__all__ = ["Branch", "Point", "STATUSES"]

#: why a branch stopped (stops.py documents each)
STATUSES = STOP_STATUSES


class Branch:
    """NNM branch of a model (columns have one row per converged point).

    energy (N,) J, frequency_hz (N,) Hz, period (N,) s, x0, v0 (N, n) initial state (m, m/s) of
    each orbit (t = 0 at the phase condition), floquet (N, 2n) complex multipliers (largest modulus
    first; a Ritz branch's (N, 2r): those of its Ritz system, ``multipliers_of``, multipliers.py), stable (N,) bool, coefficients (N, N_b, n) Fourier coefficients (m) of harmonic-balance
    branches (None otherwise), labels (N,) str ("backbone" / "tongue k:1"), events: list of dicts
    (kind, index, energy, frequency_hz, detail; located events also x0, v0, period), tongues: the
    tongues passed by a ``tongues="skip"`` continuation (dicts: ratio, order, partner_mode, entry_energy,
    entry_frequency_hz, ...).  freq_error (N,) estimated relative frequency error of each point (NaN where
    not estimated, e.g. files written before it existed); steps (N,) int, the time steps per period of each
    shooting point (0: settings.steps_per_period; a branch refined with freq_tol has several);
    fundamental_share (N,) the fraction of each orbit's modal amplitude in its fundamental harmonic (NaN where
    not measured): a tongue's partner shows as it falls.
    status: one of STATUSES; message: why it stopped.
    settings: the method's typed settings (settings.py; a plain dict is converted).
    """

    def __init__(self, model, mode, energy, frequency_hz, period, x0, v0, floquet=None, stable=None,
                 events=None, status="done", message="", settings=None, name="", coefficients=None, labels=None,
                 tongues=None, freq_error=None, steps=None, fundamental_share=None):
        self.model = model
        self.mode = int(mode)
        self.settings = settings_from_dict(settings)
        self.status = str(status)
        self.message = str(message)
        self.name = str(name)
        self._set_columns(energy, frequency_hz, period, x0, v0, floquet, stable, coefficients, labels, freq_error,
                          steps, fundamental_share)
        self.events = list(detect_events(self.energy, self.frequency_hz, self.floquet, self.stable)
                           if events is None else events)
        self.tongues = [TongueRecord.from_mapping(t) for t in (tongues or [])]

    def _set_columns(self, energy, frequency_hz, period, x0, v0, floquet, stable, coefficients, labels=None,
                     freq_error=None, steps=None, fundamental_share=None, physical=None):
        """physical : the PhysicalColumns of x0, v0 and coefficients (then those three are not read), or None."""
        n = self.model.n
        self.energy = np.asarray(energy, dtype=float).reshape(-1)
        N = len(self.energy)
        self.frequency_hz = np.asarray(frequency_hz, dtype=float).reshape(N)
        self.period = np.asarray(period, dtype=float).reshape(N)
        self._physical = PhysicalColumns(n, x0, v0, coefficients) if physical is None else physical
        if len(self._physical) != N:
            raise ValueError(f"x0 has {len(self._physical)} rows, energy {N}")
        self.floquet = floquet_columns(floquet, N, n, self.settings,
                                       width=getattr(self, "floquet", np.zeros((0, 2 * n))).shape[1])
        self.stable = np.ones(N, dtype=bool) if stable is None else np.asarray(stable, dtype=bool).reshape(N)
        self.labels = (np.full(N, "backbone", dtype=object) if labels is None
                       else np.asarray([str(x) for x in np.asarray(labels, dtype=object).reshape(N)], dtype=object))
        self.freq_error = (np.full(N, np.nan) if freq_error is None
                           else np.asarray(freq_error, dtype=float).reshape(N))
        self.steps = np.zeros(N, dtype=int) if steps is None else np.asarray(steps, dtype=int).reshape(N)
        self.fundamental_share = (np.full(N, np.nan) if fundamental_share is None
                                  else np.asarray(fundamental_share, dtype=float).reshape(N))

    # ------------------------------------------------------------------ building from points
    @classmethod
    def from_points(cls, model, mode, points, settings=None, status="done", message="", name="", events=None,
                    tongues=None):
        """Branch whose rows are ``points`` (a sequence of Point); events: located events (events.py),
        or None to bracket them from the rows (floquet.detect_events)."""
        b = cls(model, mode, [], [], [], [], [], settings=settings, status=status, message=message, name=name,
                tongues=tongues)
        b.extend(points)
        if events is not None:
            b.events = sorted(events, key=lambda e: (e["index"], e["energy"]))
        return b

    def extend(self, points):
        """Append rows (Points) in place; the events are recomputed."""
        points = list(points)
        if not points:
            return self

        def col(key, shape=(), dtype=float):
            return np.array([getattr(p, key) for p in points], dtype=dtype).reshape((len(points),) + shape)

        # (x0, v0 and coefficients mapped from the points' modal states when first read: PhysicalColumns)
        self._set_columns(np.r_[self.energy, col("energy")], np.r_[self.frequency_hz, col("frequency_hz")],
                          np.r_[self.period, col("period")], None, None,
                          np.vstack([self.floquet, col("floquet", (-1,), complex)]) if len(self)
                          else col("floquet", (-1,), complex),
                          np.r_[self.stable, col("stable", dtype=bool)], None,
                          np.r_[self.labels, col("label", dtype=object)], np.r_[self.freq_error, col("freq_error")],
                          np.r_[self.steps, col("steps", dtype=int)],
                          np.r_[self.fundamental_share, col("fundamental_share")],
                          physical=self._physical.appended(points))
        self.events = detect_events(self.energy, self.frequency_hz, self.floquet, self.stable)
        return self

    @property
    def x0(self):
        """(N, n) initial displacements (m)."""
        return self._physical.arrays()[0]

    @property
    def v0(self):
        """(N, n) initial velocities (m/s)."""
        return self._physical.arrays()[1]

    @property
    def coefficients(self):
        """(N, N_b, n) Fourier coefficients (m) of a harmonic-balance branch, else None."""
        return self._physical.arrays()[2]

    @property
    def stability_known(self):
        """(N,) bool: whether each point's stability was computed (its Floquet multipliers are; with floquet off,
        e.g. harmonic balance of a large model by default, ``stable`` is True for want of a test, not a finding)."""
        mu = np.asarray(self.floquet)
        if mu.ndim < 2 or mu.shape[1] == 0:
            return np.zeros(len(self.energy), dtype=bool)
        return ~np.all(np.isnan(mu), axis=1)

    @property
    def multipliers_of(self):
        """Whose Floquet multipliers ``floquet`` holds: 'model' (the model's 2n) or 'ritz' (the 2r of the Ritz
        system a Ritz-basis harmonic balance solved: the modes below settings.cutoff_hz and the residual vectors;
        results/multipliers.py)."""
        return multipliers_of(self.settings)

    def point(self, i):
        """Row i as a Point."""
        i = self.check_index(i)
        return Point(float(self.energy[i]), float(self.frequency_hz[i]), float(self.period[i]), self.x0[i].copy(),
                     self.v0[i].copy(), self.floquet[i].copy(), bool(self.stable[i]),
                     coefficients=None if self.coefficients is None else self.coefficients[i].copy(),
                     label=str(self.labels[i]), freq_error=float(self.freq_error[i]), steps=int(self.steps[i]),
                     fundamental_share=float(self.fundamental_share[i]))

    @property
    def hb_coefficients(self):
        """Fourier coefficients (N, N_b, n) of a harmonic-balance branch (first-release name of
        ``coefficients``)."""
        return self.coefficients

    def __len__(self):
        return len(self.energy)

    def __repr__(self):
        return (f"Branch(mode={self.mode}, points={len(self)}, "
                f"energy={self.energy.min() if len(self) else 0:.3g}..{self.energy.max() if len(self) else 0:.3g} J, "
                f"status={self.status!r})")

    # ------------------------------------------------------------------ selection
    def pick(self, what, item):
        """One of the branch's ``events`` or ``tongues`` (``what``), given as the dict itself or its index."""
        items = getattr(self, what)
        if isinstance(item, (int, np.integer)) and not isinstance(item, bool):
            if not -len(items) <= item < len(items):
                raise NNMInputError(f"{what[:-1]} {item} is out of range: the branch lists {len(items)} {what}")
            return items[int(item)]
        if not isinstance(item, (dict, TongueRecord)):
            raise NNMInputError(f"give one of branch.{what} (a record) or its index, got {type(item).__name__}")
        return item

    def check_index(self, i):
        """Validate a point index (negative counts from the end); returns it in 0..N-1."""
        if not isinstance(i, (int, np.integer)) or isinstance(i, bool) or not -len(self) <= i < len(self):
            raise NNMInputError(f"point index {i!r} is out of range: the branch has {len(self)} points")
        return int(i) % len(self)

    def subset(self, index):
        """Branch made of the rows ``index`` (slice, index array or boolean mask), with the events that lie between
        them (floquet.events_of_rows: the located ones kept; bracketed again for rows out of order)."""
        events = events_of_rows(self.events, np.arange(len(self))[index])
        return Branch(self.model, self.mode, self.energy[index], self.frequency_hz[index], self.period[index],
                      self.x0[index], self.v0[index], self.floquet[index], self.stable[index], events, self.status,
                      self.message, self.settings, self.name,
                      None if self.coefficients is None else self.coefficients[index], self.labels[index],
                      self.tongues, self.freq_error[index], self.steps[index], self.fundamental_share[index])

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

        # (the orbit scaled as a whole: harmonic balance's coefficients too, which motion() and orbit() use; x0 =
        # the coefficients' orbit at t = 0, linear in them)
        c = energy_factor(self.model, lerp(self.x0), lerp(self.v0), lerp(self.energy))
        x0, v0 = c * lerp(self.x0), c * lerp(self.v0)
        near = j if w < 0.5 else k
        return Branch(self.model, self.mode, [self.model.energy(x0, v0)], [lerp(self.frequency_hz)],
                      [lerp(self.period)], x0[None], v0[None], self.floquet[near][None],
                      [self.stable[near]], [], self.status, f"interpolated at index {s:.3f}", self.settings,
                      self.name, None if self.coefficients is None else c * lerp(self.coefficients)[None],
                      [self.labels[near]], None, [lerp(self.freq_error)], [self.steps[near]],
                      [lerp(self.fundamental_share)])

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

    def reference_motion(self, i, samples=256, rtol=1e-9, max_steps=None):
        """The orbit of point i integrated by scipy's DOP853 from its stored state over its stored period,
        with no compiled kernel (orbits/reference.py): (t (samples,) s, x (samples, n) m).  It agrees with
        ``motion(i)`` to the branch's discretisation error (a shooting branch's motion is the discrete
        orbit of its own integrator); half-period shooting branches are integrated over T/2 and continued
        by their symmetry, like ``motion``.  ``max_steps``: RuntimeError, before integrating, if that would
        take more steps (an explicit method on a model with very high modal frequencies)."""
        from ..model.modal import modal_system
        from ..orbits.reference import reference_orbit
        i = self.check_index(i)
        x, _ = reference_orbit(modal_system(self.model), self.x0[i], self.v0[i], self.period[i], samples,
                               bool(getattr(self.settings, "symmetric", False)), rtol, max_steps)
        return np.arange(int(samples)) * self.period[i] / int(samples), x

    def velocity(self, i, samples=256):
        """Velocities (samples, n) m/s along the orbit of point i, at the times of motion()."""
        return self.orbit(i, samples)[2]

    def orbit(self, i, samples=256):
        """Orbit of point i: (t (samples,) s, x, v (samples, n) m, m/s), t = k T / samples.

        Rebuilt by the branch's method (``settings.orbit``): shooting branches re-integrate the
        discrete orbit with their own Newmark step (half a period when half-period shooting was used)
        and resample it by Fourier interpolation, which reproduces the converged orbit even when it
        is strongly unstable; harmonic-balance branches evaluate their Fourier series.
        """
        i = self.check_index(i)
        samples = int(samples)
        if samples < 2:
            raise NNMInputError("samples must be at least 2")
        try:
            x, v = self.settings.orbit(self, i, samples)
        except RuntimeError as exc:
            raise RuntimeError(f"point {i}: {exc}") from None
        return np.arange(samples) * self.period[i] / samples, x, v

    def coefficients_at(self, i):
        """Fourier coefficients (N_b, n) m of point i of a harmonic-balance branch (stored, or
        recomputed for branches of first-release files)."""
        i = self.check_index(i)
        if self.coefficients is not None:
            return self.coefficients[i]
        from ..model.modal import modal_system
        from ..orbits.harmonic_balance import recover_coefficients
        s = self.settings
        return recover_coefficients(modal_system(self.model), self.mode - 1, s.hb_basis(), self.x0[i], self.v0[i],
                                    self.period[i], s.tol)

    def harmonics(self, i, n=15):
        """Fourier amplitudes (n+1, n_dof) of the orbit of point i: row k = harmonic k (k=0: mean), m."""
        n = int(n)
        if n < 1:
            raise NNMInputError("n (number of harmonics) must be at least 1")
        samples = max(256, 4 * (n + 1))
        return fourier_amplitudes(self.motion(i, samples)[1], n)

    def mac_to_linear(self, i):
        """Mass-weighted MAC (n_modes,) of the NNM shape x0 of point i with each linear mode
        (index k-1: mode k): (phi_k^T M x0)^2 / ((phi_k^T M phi_k)(x0^T M x0))."""
        i = self.check_index(i)
        _, shapes = self.model.linear_modes()
        return mac(self.x0[i], shapes, self.model.M)[0]

    # ------------------------------------------------------------------ scaling
    def scaled(self, factor):
        """The branch of the same model with every k3 multiplied by ``factor`` (> 0).

        Exact for cubic springs (scaling.py): frequencies and multipliers unchanged, displacements
        and velocities / sqrt(factor), energies / factor.  Every stored orbit is scaled so: the points', the
        located events' (x0, v0, energy) and the tongue records' (entry and inside orbits, entry and exit
        energies), so switch_branch and continue_tongue start from orbits of the scaled model; settings.energy_max
        (J) / factor too.  The message is free text written for the branch as computed: it is kept, with a note
        that the branch was scaled (its energies are those before the scaling).
        """
        sc = cubic_scaling(factor)
        el = self.model.elements
        if len(el) and not el.cubic_only:
            raise NNMInputError("the scaling law holds for cubic springs only; compute the branch of the scaled model")
        events = [scaled_event(e, sc) for e in self.events]
        settings = self.settings.replace(k3_factor=self.settings.k3_factor * sc.ratio,
                                         energy_max=self.settings.energy_max * sc.energy)
        return Branch(self.model.scaled(sc.ratio), self.mode, self.energy * sc.energy, self.frequency_hz,
                      self.period, self.x0 * sc.amplitude, self.v0 * sc.amplitude, self.floquet, self.stable, events,
                      self.status, scaled_message(self.message, sc), settings, self.name,
                      None if self.coefficients is None else self.coefficients * sc.amplitude, self.labels,
                      [t.scaled(sc.amplitude, sc.energy) for t in self.tongues], self.freq_error,
                      self.steps, self.fundamental_share)
