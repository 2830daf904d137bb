r"""The backbone's skeleton: the NNM family by harmonic balance condensed onto the elements, stepped in
the followed mode's modal amplitude (the stepping: amplitude_family.py).

The skeleton is the family of orbits whose fundamental component in the followed mode r is a cos(w t)
(a in sqrt(kg) m, mass-normalised modal coordinates), for a rising geometrically: at each a the
condensed harmonic-balance equations (orbits/condensed_hb.py, s.harmonics odd harmonics, n_s N_b + 1
unknowns whatever the model size) are solved by Newton's method from the secant predictor.  Fixing the
modal amplitude, not the arclength, is what makes it a skeleton: a narrow k:1 tongue (where k w crosses
a partner's w_p) is a thin band in a, so the steps land on both sides of it on the family, and the few
points that land inside (their energy raised by the partner's share) are recognised because their energy
lies above the family's later points and are left out.  Stepping in a ends where

* the energy reaches the reach asked for (``end = "reach"``);
* the energy turns back for s.peak_run steps while a grows and no partner grows, or the family folds back
  in a with no partner in the orbit and its energy growing at a finite rate with a up to the fold (so the
  energy folds there too): the family's energy maximum (a softening family approaching a saddle),
  ``energy_peak``: no backbone at higher energy (``end = "peak"``);
* the frequency jumps (a step of the smallest size still moves it much more than the trend) or Newton
  fails at the smallest step: the family met an internal resonance it does not pass smoothly; jumps of
  1-20 % in amplitude are tried (from the one-harmonic guide's orbits first, family_guide.py; then ``s.jumps``:
  accepted on the family's frequency trend with its fundamental share kept; ``gaps`` records them, with the
  moves onto the backbone's sheet where the stepping had slid onto a tongue's), and where none lands the family
  ends there (``end = "locked"`` or ``"stuck"``; ``message`` names the resonance and the partner); so too
  where other modes' higher harmonics take more than 1 - s.share_min of the orbit (velocity-weighted: a partner
  takes the orbit over) or where the energy turns back while a partner grows.

Where the full branch (any method, any number of harmonics) leaves the family at a tongue, the skeleton's
orbits above (``family_orbit``) are the first guesses from which the branch's own method finds the backbone
beyond it (jumps.py).  Its frequency at
each energy (``frequency_at``) is what labels a branch's points (labels.py).

The skeleton's frequencies differ from the branch's by the truncation to s.harmonics harmonics
(the Paris-like aircraft's mode 20: below 1e-6 at 1 J) and by the branch's own discretisation.
"""
from __future__ import annotations

import math
import threading
import weakref

import numpy as np

from ..errors import NNMInputError
from .amplitude_family import solve_at_amplitude, family_share, amplitude_family
from .cubic_piece import cubic, cubic_root
from .settings import SkeletonSettings

__all__ = ["Skeleton", "skeleton", "skeleton_of", "compute_skeleton", "amplitude_family"]





_cache = weakref.WeakKeyDictionary()
_lock = threading.Lock()


class Skeleton:
    """The backbone family of one mode (module docstring): energies E (J, rising), frequencies f (Hz),
    modal amplitudes a and the condensed orbits u of its points, with the blips inside narrow tongues left
    out.  prob : the CondensedHBProblem; end / message : how the family ended; energy_peak : its energy
    maximum (J) when it turned back (no backbone above it), else None; partner : (k, 1-based mode) of the
    k:1 internal resonance that ended it ((1, 0) when none did)."""

    def __init__(self, prob, a, E, f, us, end, message, gaps, partner, mode, settings=SkeletonSettings()):
        s = self.settings = settings
        self.problem, self.mode = prob, int(mode)
        self.partner = (int(partner[0]), int(partner[1]))
        self.gaps = gaps
        self.end, self.message = end, message
        E = np.asarray(E, dtype=float)
        n = len(E)
        if end == "peak" and n:               # a turned-back family: up to its peak (among the points on the family)
            shares = np.array([family_share(prob, u) for u in us])
            n = int(np.argmax(np.where(shares >= s.peak_share, E, -np.inf))) + 1
        keep, lowest = [], math.inf
        for i in range(n - 1, -1, -1):           # a point inside a tongue lies above the family's later points
            if E[i] < lowest:
                keep.append(i)
                lowest = E[i]
        keep = keep[::-1]
        #: the intervals between kept points with points left out between them (interpolated linearly)
        self._gaps = np.diff(keep) > 1 if len(keep) > 1 else np.zeros(0, dtype=bool)
        self.energy_peak = float(E[n - 1]) if end == "peak" and n else None
        self.energy = E[keep]
        self.frequency_hz = np.asarray(f, dtype=float)[keep]
        self.amplitude = np.asarray(a, dtype=float)[keep]
        self.orbits = [us[i] for i in keep]
        self.blips = n - len(keep)            # points left out below the end: inside narrow tongues
        starts = {float(g[1]) for g in gaps if g[3] == "sheet"}
        self._starts = np.array([float(E0) in starts for E0 in self.energy], dtype=bool)   # the first points of new sheets
        #: energies (J) where the stepping moved onto the backbone's sheet beyond a tongue it had slid onto
        #: (family_guide.py), among the points kept: below each, back to the tongue's entry, the skeleton's points
        #: are the tongue's sheet
        self.sheet_starts = [float(E0) for E0 in self.energy[self._starts]]
        self._interp = None
        self._lnE = np.log(self.energy)       # ln E and ln f of the points (the labels read them at every point)
        self._lnf = np.log(self.frequency_hz)
        self._shares = None
        self._log_f = {}                      # E -> log_frequency(E), for the energies the labels ask for again
        self._pieces = {}                     # (sheet's first index, piece) -> its two cubics (frequency_at)
        self._lower = None                    # the problem with two harmonics fewer (_truncation_of)
        self._truncation = np.full(len(self.energy), np.nan)
        self._estimated = np.zeros(len(self.energy), dtype=bool)

    def _truncation_of(self, i):
        """Estimated relative frequency error of point i from the truncation of the harmonics: the change of its
        frequency with two harmonics fewer (the same modal amplitude), an upper estimate; NaN where not estimated.
        Computed when first asked (a solve per point: half the skeleton's cost if done for every point, while the
        labels ask only at the branch's energies outside the linear regime) and kept."""
        if not self._estimated[i]:
            from ..orbits.condensed_hb import CondensedHBProblem
            from ..orbits.hb_basis import HBBasis
            prob = self.problem
            step = 2 if prob.basis.kind == "odd" else 1
            if prob.basis.harmonics > step:
                if self._lower is None:
                    self._lower = CondensedHBProblem(prob.sys, prob.r, HBBasis(prob.basis.harmonics - step,
                                                                               prob.basis.kind), prob.lin)
                u = self.orbits[i]
                v = solve_at_amplitude(self._lower, self._lower.from_family(prob, u))
                self._truncation[i] = abs(v[-1] / u[-1] - 1.0) if v is not None else np.nan
            self._estimated[i] = True
        return self._truncation[i]

    def truncation_at(self, E):
        """Estimated relative frequency error (truncation of the harmonics) of the skeleton at energy E (J): the
        largest of its two neighbouring points' (NaN outside its range or where not estimated)."""
        if not self.covers(E):
            return float("nan")
        j = self._pair(E)[0]
        pair = np.array([self._truncation_of(j), self._truncation_of(j + 1)])
        return float(np.nanmax(pair)) if np.any(np.isfinite(pair)) else float("nan")

    def _pair(self, E):
        """(j, t): E (J) lies at t between points j and j + 1 in log E.  Just below a sheet start (between it and
        the point before it, down by at most the sheet's first interval), the pair is the start and the point after it
        (t < 0): the backbone's sheet extends a little below where the stepping met it (sheet_start stops where it
        is no longer nearer the guide than the tongue's sheet), and the point before is the tongue's sheet."""
        x, lnE = self._lnE, math.log(E)
        j = min(max(int(np.searchsorted(x, lnE)) - 1, 0), len(x) - 2)
        if (j + 2 < len(x) and self._starts[j + 1] and E < self.energy[j + 1]
                and lnE >= 2 * x[j + 1] - x[j + 2]):      # at most one of its first intervals below
            j += 1
        return j, (lnE - x[j]) / (x[j + 1] - x[j])

    def frequency_at(self, E):
        """Skeleton frequency (Hz) at energy E (J) on the sheet it lies on (_pair); NaN outside its range.  Each sheet
        is a parametric cubic spline (ln E and f against the chord length in (ln a, ln E)), solved for ln E: smooth
        in that parameter also where f(E) is steep (next to a saddle, where dE/da vanishes).  Measured between points up
        to 0.5 % apart in frequency (amplitude_family.DLNF_MAX): 3e-7 on the 2-DOF benchmark, 7e-9 on NLvib's example
        04 (a monotone PCHIP in ln E, used before, gave 9e-7 and 3e-7 with points 0.2 % apart)."""
        if not self.covers(E):
            return float("nan")
        if self._interp is None:
            self._interp = self._sheets()
        j, t = self._pair(E)
        sheet = self._interp.get(j)
        # linear in ln E across a gap left by the points dropped inside a tongue (blips), where a spline swings (by
        # 3e-3 on the aircraft's mode 20 between 4.07 and 4.96 J, against 3e-4 for the line)
        gap = bool(self._gaps[j])
        if sheet is None or self._interp.get(j + 1) is not sheet or gap:
            return float((1 - t) * self.frequency_hz[j] + t * self.frequency_hz[j + 1])
        lo, c, lnE, f = sheet
        x = math.log(E)
        if t < 0:                                   # just below a sheet's start: extrapolated along it
            return float(f(c[0] + t * (c[1] - c[0])))
        i = j - lo                                  # the spline piece between points j and j + 1
        a, b = float(c[i]), float(c[i + 1])
        piece = self._pieces.get((lo, i))
        if piece is None:
            piece = self._pieces[(lo, i)] = (lnE.c[:, i].tolist(), f.c[:, i].tolist())
        pl, pf = piece                              # its cubics in s - a
        ga, gb = cubic(pl, 0.0) - x, cubic(pl, b - a) - x
        if ga == 0.0:
            return cubic(pf, 0.0)
        if ga * gb > 0:                             # no sign change (a spline wiggle at round-off): linear
            return float((1 - t) * self.frequency_hz[j] + t * self.frequency_hz[j + 1])
        return cubic(pf, cubic_root(pl, x, b - a, ga, gb, 1e-14 * max(1.0, abs(b))))

    def _sheets(self):
        """{point index: (first index, chord parameters, spline of ln E, spline of f)} of each sheet (the points
        between sheet starts) with at least two points."""
        from scipy.interpolate import CubicSpline
        cuts = [0] + [int(i) for i in np.flatnonzero(self._starts)] + [len(self.energy)]
        out = {}
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            if hi - lo < 2:
                continue
            la, lE = np.log(self.amplitude[lo:hi]), np.log(self.energy[lo:hi])
            c = np.r_[0.0, np.cumsum(np.hypot(np.diff(la), np.diff(lE)))]
            kind = "not-a-knot" if hi - lo >= 4 else "natural"
            sheet = (lo, c, CubicSpline(c, lE, bc_type=kind), CubicSpline(c, self.frequency_hz[lo:hi], bc_type=kind))
            out.update({i: sheet for i in range(lo, hi)})
        return out

    def share_at(self, E):
        """Fundamental share (content.fundamental_share: the fraction of the modal orbit's harmonic
        amplitudes in its fundamental) of the family's orbit at energy E (J), interpolated between its two
        neighbouring points in log E; NaN outside its range."""
        from .content import fundamental_share, harmonic_label
        if not self.covers(E):
            return float("nan")
        if self._shares is None:
            self._shares = np.full(len(self.energy), np.nan)
        j, t = self._pair(E)
        for i in (j, j + 1):
            if not np.isfinite(self._shares[i]):
                self._shares[i] = fundamental_share(harmonic_label(self.problem.modal_orbit(self.orbits[i]))[3])
        return float((1 - t) * self._shares[j] + t * self._shares[j + 1])

    def interpolation_error(self, E):
        """Estimated relative error of ``frequency_at`` at energy E (J) from the spacing of the skeleton's points: the
        change of the secant slope d ln f / d ln E between the interval holding E and its neighbours, times the
        interval's length / 8 (the error of a line through two points of a curve of that curvature).  Measured on
        the aircraft's mode 10 at one harmonic near its energy maximum (points 10 % apart in energy): estimated
        2.3e-4 where the interpolated frequency was 2.1e-4 off the family's orbit at that energy."""
        if not self.covers(E):
            return float("nan")
        x, y = self._lnE, self._lnf
        j = int(np.clip(np.searchsorted(x, math.log(E)) - 1, 0, len(x) - 2))
        h = np.diff(x)
        with np.errstate(divide="ignore", invalid="ignore"):
            slopes = np.where(h > 0, np.diff(y) / np.where(h > 0, h, 1.0), 0.0)
        change = max([abs(slopes[i] - slopes[j]) for i in (j - 1, j + 1) if 0 <= i < len(slopes)], default=0.0)
        return float(change * h[j] / 8)

    def slope(self, E1, E2):
        """d ln f / d ln E of the family between energies E1 and E2 (J): the secant of its points' frequencies
        interpolated linearly in ln E (no spline: robust where its points are far apart, next to the tongues whose
        points it left out); NaN outside its range."""
        if not (self.covers(E1) and self.covers(E2)) or E1 == E2:
            return float("nan")
        x, y = self._lnE, self._lnf
        a, b = np.interp(math.log(E1), x, y), np.interp(math.log(E2), x, y)
        return float((b - a) / (math.log(E2) - math.log(E1)))

    def log_frequency(self, E):
        """ln f of the family at energy E (J) interpolated linearly in ln E between its points (``slope``'s)."""
        v = self._log_f.get(E)
        if v is None:           # (the lock test asks for the run's energies at every point: each once)
            if len(self._log_f) > 4096:
                self._log_f.clear()
            v = self._log_f[E] = np.interp(math.log(E), self._lnE, self._lnf)
        return v

    def covers(self, E):
        return len(self.energy) >= 2 and self.energy[0] <= E <= self.energy[-1]

    def _interpolated(self, E):
        j, t = self._pair(E)
        return (1 - t) * self.orbits[j] + t * self.orbits[j + 1]

    def family_orbit(self, system, E, settings, tol):
        """(problem, u): the skeleton's orbit at energy E (J), corrected on the energy level set (condensed
        HB with s.harmonics on the skeleton's modal system); None outside its range or where that
        does not converge.  A first guess for the branch's own method."""
        from .jumps import level_set
        if not self.covers(E):
            return None
        u, _ = level_set(self.problem, self._interpolated(E), settings, min(tol, 1e-9))
        return None if u is None else (self.problem, u)

    def frequency_of_orbit(self, E):
        """The frequency (Hz) of the skeleton's own orbit at energy E (J): its interpolated orbit corrected on the
        energy level set (a condensed harmonic-balance solve), moved along the family's slope to E; no interpolation
        error.  NaN outside its range or where that does not converge."""
        from ..continuation.engine import ContinuationSettings
        cs = ContinuationSettings(step=1.0, step_min=0.0, step_max=np.inf, max_iter=self.settings.fold_probe_iterations)
        found = self.family_orbit(self.problem.sys, E, cs, 1e-10)
        if found is None:
            return float("nan")
        prob, u = found
        E_u, f_u = float(prob.energy(u)), float(u[-1] * prob.w_r / (2 * math.pi))
        if not self.is_family(E_u, f_u):
            return float("nan")
        slope = self.slope(min(E, E_u) * (1 - 1e-3), max(E, E_u) * (1 + 1e-3))
        return f_u * math.exp(slope * math.log(E / E_u)) if math.isfinite(slope) else f_u

    def is_family(self, E, f, tol=1e-4):
        """Is the orbit of energy E (J) and frequency f (Hz) the skeleton's family: within tol + 2 x the interpolation
        error estimate of its interpolated frequency?  (A corrected orbit inside the gap the skeleton leaves at a
        tongue may converge onto the tongue's sheet: the soft 2-DOF chain's 3:1 at 0.075 J, 0.6 % off.)"""
        f_i, err = self.frequency_at(E), self.interpolation_error(E)
        return math.isfinite(f_i) and abs(f / f_i - 1.0) <= tol + 2 * (err if math.isfinite(err) else 0.0)


def compute_skeleton(system, mode, E_reach, settings=SkeletonSettings(), E_start=None):
    """The Skeleton of linear mode ``mode`` (1-based) of the ModalSystem ``system`` up to E_reach (J), with
    settings.harmonics (fewer where its condensed problem would exceed settings.max_unknowns).  E_start (J, default E_reach): the reach its first amplitude is chosen for (below)."""
    from ..orbits.condensed_hb import CondensedHBProblem
    from ..orbits.hb_basis import HBBasis
    s = settings
    r = int(mode) - 1
    kind, H = "odd" if system.elements.odd else "full", s.harmonics
    prob = CondensedHBProblem(system, r, HBBasis(H, kind))
    while prob.nb * prob.ns + 2 > s.max_unknowns and H > 3:       # (settings.max_unknowns: a large condensed problem)
        H -= 2
        prob = CondensedHBProblem(system, r, HBBasis(H, kind))
    # start in the linear regime: at most 1e-6 of the reach (E = w^2 a^2 / 2 for the linear mode), lower until
    # the frequency is the linear one to 1e-8 (also where Newton finds no orbit there: a reach far above the
    # family's end, e.g. 1e6 x a tongue's entry energy on the 2-DOF benchmark, puts 1e-6 of it beyond the family)
    a0 = math.sqrt(2e-6 * (E_reach if E_start is None else E_start)) / prob.w_r
    for _ in range(20):
        u = solve_at_amplitude(prob, prob.start(a0)[0])
        if u is not None and abs(u[-1] - 1.0) < 1e-8:
            break
        a0 /= 4
    # then raise it to where the frequency has moved by about start_shift (below, the stepping would only retrace
    # the linear mode, a third of its points on NLvib's examples; the labels ask the skeleton only beyond a shift of
    # 1e-3): the shift grows as a^2 (or faster) from the linear mode
    shift = abs(u[-1] - 1.0) if u is not None else 0.0
    if 0.0 < shift < s.start_shift / 10:
        a1 = a0 * min(math.sqrt(s.start_shift / shift), 1e3)
        v = solve_at_amplitude(prob, prob.start(a1)[0])
        if v is not None and abs(v[-1] - 1.0) <= 2 * s.start_shift:
            a0 = a1
    return Skeleton(prob, *amplitude_family(prob, E_reach, a0, s), mode, s)


def skeleton(model, mode, energy_max, system_of, settings=SkeletonSettings(), reach=None):
    """The Skeleton of linear mode ``mode`` (1-based) of ``model`` up to reach x energy_max (J; reach: default
    settings.reach), cached per model, mode and settings (a cached one that reaches far enough, or that ended, is
    reused).  system_of(model, mode, harmonics) gives the ModalSystem (every mode, or the Ritz basis for those
    harmonics for a large model; driver/api.py).  Whatever the reach, the stepping starts where a settings.reach x
    energy_max one starts, so a shorter reach (follow_reach: a branch that follows its tongues needs the skeleton
    only for its labels, up to its energy_max) gives the first points of the longer one, the same numbers."""
    if isinstance(settings, int):              # skeleton(..., harmonics) of earlier releases
        settings = SkeletonSettings(harmonics=settings)
    E_reach = (settings.reach if reach is None else reach) * energy_max
    with _lock:
        for (m, st, r), sk in _cache.get(model, {}).items():
            if m == mode and st == settings and (r >= E_reach or sk.end != "reach"):
                return sk
    sk = compute_skeleton(system_of(model, mode, settings.harmonics), mode, E_reach, settings,
                          E_start=settings.reach * energy_max)
    with _lock:
        _cache.setdefault(model, {})[(mode, settings, E_reach)] = sk
    return sk


def skeleton_of(model, mode, energy_max, system_of, settings=SkeletonSettings(), reach=None):
    """(Skeleton, "") of ``skeleton``, or (None, why) when it cannot be computed: the failure is reported (the
    branch's policy says it in its messages), not swallowed."""
    try:
        return skeleton(model, mode, energy_max, system_of, settings, reach), ""
    except (NNMInputError, np.linalg.LinAlgError, ValueError, RuntimeError) as exc:
        return None, f"the skeleton could not be computed: {exc}"
