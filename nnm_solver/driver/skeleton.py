r"""The backbone's skeleton: the NNM family by harmonic balance condensed onto the elements, stepped in
the followed mode's modal amplitude.

The skeleton is the family of orbits whose fundamental component in the followed mode r is a cos(w t)
(a in sqrt(kg) m, mass-normalised modal coordinates), for a rising geometrically: at each a the
condensed harmonic-balance equations (orbits/condensed_hb.py, SKELETON_HARMONICS odd harmonics, n_s N_b + 1
unknowns whatever the model size) are solved by Newton's method from the secant predictor.  Fixing the
modal amplitude, not the arclength, is what makes it a skeleton: a narrow k:1 tongue (where k w crosses
a partner's w_p) is a thin band in a, so the steps land on both sides of it on the family, and the few
points that land inside (their energy raised by the partner's share) are recognised because their energy
lies above the family's later points and are left out.  Stepping in a ends where

* the energy reaches the reach asked for (``end = "reach"``);
* the energy turns back for PEAK_RUN steps while a grows and no partner grows: the family's energy
  maximum (a softening family approaching a saddle), ``energy_peak``: no backbone at higher energy
  (``end = "peak"``);
* the frequency jumps (a step of the smallest size still moves it much more than the trend) or Newton
  fails at the smallest step: the family met an internal resonance it does not pass smoothly; jumps of
  1-20 % in amplitude are tried (``JUMPS``: accepted on the family's frequency trend with its fundamental
  share kept, ``gaps`` records them), and where none lands the family ends there (``end = "locked"`` or
  ``"stuck"``; ``message`` names the resonance and the partner); so too where other modes' higher
  harmonics take more than 1 - SHARE_MIN of the orbit (velocity-weighted: a partner takes the orbit over)
  or where the energy turns back while a partner grows.

Where the full branch (any method, any number of harmonics) enters a k:1 tongue with a partner mode of
frequency f_p, the resonance band is where k f(E) crosses f_p; the skeleton says at which energies the
family has left that band (``targets``), and its orbit there (``family_orbit``) is the first guess from
which the branch's own method finds the backbone beyond the tongue (tongue_skip.py).  Its frequency at
each energy (``frequency_at``) is what labels a branch's points (labels.py).

The skeleton's frequencies differ from the branch's by the truncation to SKELETON_HARMONICS harmonics
(the Paris-like aircraft's mode 20: below 1e-6 at 1 J) and by the branch's own discretisation.
"""
from __future__ import annotations

import math
import threading
import weakref

import numpy as np

__all__ = ["Skeleton", "skeleton", "amplitude_family"]

#: the skeleton is computed up to this multiple of the branch's energy_max
REACH = 10.0

#: the skeleton is at a k:1 band where k f is within this relative distance of the partner's frequency
ENTRY_BAND = 0.01

#: harmonics of the skeleton (odd ones for odd elements)
SKELETON_HARMONICS = 9

#: modal amplitude steps: largest and smallest ratio a_{i+1} / a_i, and the largest move of ln f in a step
STEP_MAX, STEP_MIN = 1.05, 1.0005
DLNF_MAX = 0.002

#: energy falling over this many steps in a row with at least PEAK_SHARE kept (_share): the family's energy
#: maximum (with less, a resonance)
PEAK_RUN, PEAK_SHARE = 3, 0.98

#: relative amplitude jumps tried where the family meets a resonance it does not pass smoothly
JUMPS = (0.01, 0.02, 0.05, 0.1, 0.2)
#: relative frequency shifts of the jumps' guesses (besides the trend's), the largest move accepted beyond the
#: trend's, and the fraction of the fundamental share a landing orbit keeps
JUMP_SHIFTS = (0.0, -0.005, 0.005, -0.01, -0.02)
JUMP_LIMIT, SHARE_KEPT = 0.02, 0.85

#: the family ends where other modes' higher harmonics take more than 1 - SHARE_MIN of the orbit (_share)
SHARE_MIN = 0.5

#: a step moving ln f by more than JUMP_FACTOR x the previous step's + JUMP_FLOOR is halved
JUMP_FACTOR, JUMP_FLOOR = 5.0, 2e-3

_cache = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def _newton(prob, u, tol=1e-10, iterations=30):
    """Solve the condensed HB equations at the fixed modal amplitude held in u (Newton on all the other
    unknowns); the solution or None."""
    nD = prob.nb * prob.ns
    free = np.r_[0:nD, nD + 1]
    u = u.copy()
    for _ in range(iterations):
        r, J = prob.jacobian(u)
        if prob.error(u, r) < tol:
            return u
        try:
            du = np.linalg.solve(J[:, free], -r)
        except np.linalg.LinAlgError:
            return None
        u[free] += du
        if not np.all(np.isfinite(u)) or u[-1] <= 0:
            return None
    return None


def _partner(prob, u):
    """(k, 1-based mode) of the strongest higher-harmonic (k >= 2) amplitude of another mode in the orbit u
    (velocity-weighted)."""
    A = np.abs(prob.amplitudes(u)[0]) * prob.basis.h[:, None]
    A[prob.basis.h == 1] = 0.0
    A[:, prob.r] = 0.0
    j, m = np.unravel_index(int(np.argmax(A)), A.shape)
    return int(prob.basis.h[j]), int(m) + 1


def _share(prob, u):
    """1 - the share of the other modes' higher harmonics (k >= 2) in the orbit u, velocity-weighted
    (sum (h_j A_jk)^2 over those / over all): what a partner mode takes from the followed one.  A change of
    shape at the fundamental, or the followed mode's own harmonics (an anharmonic orbit near a saddle), are
    the family's own."""
    A = prob.amplitudes(u)[0]
    h = prob.basis.h
    W = (h[:, None] * A) ** 2
    partner = W[h >= 2].sum() - W[h >= 2, prob.r].sum()
    return float(1.0 - partner / max(W.sum(), 1e-300))


def _jump(prob, pts, slope):
    """Past a resonance the family does not pass smoothly: from the last point, the amplitudes a (1 + delta),
    delta in JUMPS, the orbit scaled and its frequency moved along the trend ``slope`` = d ln f / d ln a
    (or by JUMP_SHIFTS); accepted when Newton converges onto an orbit whose frequency keeps the trend (within
    3 times the move expected + JUMP_LIMIT) and whose fundamental share is at least SHARE_KEPT of the last
    point's.  (a, E, f, u) or None."""
    a0, _, f0, u0 = pts[-1]
    nD = prob.nb * prob.ns
    share0 = _share(prob, u0)
    for delta in JUMPS:
        expected = slope * math.log(1 + delta)
        for shift in (expected,) + JUMP_SHIFTS:
            guess = u0.copy()
            guess[:nD] *= 1 + delta
            guess[-1] *= math.exp(shift)
            guess[nD] = a0 * (1 + delta) * prob.beta
            v = _newton(prob, guess, iterations=60)
            if v is None:
                continue
            f = v[-1] * prob.w_r / (2 * math.pi)
            if (abs(math.log(f / f0) - expected) <= 3 * abs(expected) + JUMP_LIMIT
                    and _share(prob, v) >= SHARE_KEPT * share0):
                return a0 * (1 + delta), prob.energy(v), f, v
    return None


def amplitude_family(prob, E_reach, a_start, max_jumps=20):
    """Step the condensed problem ``prob`` in its modal amplitude from a_start (sqrt(kg) m, linear regime)
    until the energy exceeds E_reach (J) or the family ends (module docstring).  Returns (a, E, f (Hz), u,
    end, message, gaps, partner) with the raw points (blips inside tongues included) as lists; gaps: the
    (E_before J, E_after J, a_after) of the resonances jumped; partner: (k, 1-based mode) of the k:1
    resonance that ended the family ((1, 0) when none did)."""
    u = _newton(prob, prob.start(a_start)[0])
    if u is None:
        return [], [], [], [], "stuck", "no harmonic-balance solution at the linear mode", [], (1, 0)
    pts = [(a_start, prob.energy(u), u[-1] * prob.w_r / (2 * math.pi), u)]
    ratio, dlnf_prev, falls = STEP_MAX, 0.0, 0
    end, message, gaps = "reach", "", []
    partner = (1, 0)                   # (k, 1-based mode) of the resonance that ends the family
    nD = prob.nb * prob.ns
    def resonance(v, what):
        """The family met a resonance at the last point: jump it (True) or end the family (False)."""
        nonlocal end, message, ratio, falls, partner
        a0, E0, f0, u0 = pts[-1]
        base = [p for p in pts if math.log(a0 / p[0]) <= 0.3]     # the trend over the last 30 % in amplitude
        slope = math.log(f0 / base[0][2]) / math.log(a0 / base[0][0]) if base[0] is not pts[-1] else 0.0
        jumped = _jump(prob, pts, slope) if len(gaps) < max_jumps else None
        if jumped is not None:
            gaps.append((E0, jumped[1], jumped[0]))
            pts.append(jumped)
            ratio, falls = STEP_MAX, 0
            return True
        k, p = partner = _partner(prob, u0 if v is None else v)
        end = "stuck" if v is None else "locked"
        message = (f"the family ends at E = {E0:.4g} J, f = {f0:.5g} Hz: {what} (a {k}:1 internal resonance with "
                   f"mode {p}) and no jump of up to {100 * JUMPS[-1]:g} % in amplitude passes it")
        return False

    while len(pts) < 3000:
        a0, _, f0, u0 = pts[-1]
        a = a0 * ratio
        guess = u0.copy()
        if len(pts) > 1:               # secant predictor in ln a
            a1, u1 = pts[-2][0], pts[-2][3]
            guess = u0 + (u0 - u1) * (math.log(ratio) / math.log(a0 / a1))
        guess[nD] = a * prob.beta
        v = _newton(prob, guess)
        dlnf = math.log(v[-1] * prob.w_r / (2 * math.pi) / f0) if v is not None else math.inf
        if v is None or abs(dlnf) > JUMP_FACTOR * abs(dlnf_prev) + JUMP_FLOOR:
            if ratio > STEP_MIN:
                ratio = 1 + (ratio - 1) / 2
                continue
            what = "no solution at a larger amplitude" if v is None else f"its frequency jumps by {100 * dlnf:.2g} %"
            if resonance(v, what):
                continue
            break
        E = prob.energy(v)
        pts.append((a, E, f0 * math.exp(dlnf), v))
        dlnf_prev = dlnf
        # the next step: grown by half, at most STEP_MAX, and moving the frequency by about DLNF_MAX at most
        # (the interpolation in energy between points stays at 1e-5 where f(E) is steep, e.g. near a saddle)
        ratio = min(STEP_MAX, 1 + (ratio - 1) * min(1.5, DLNF_MAX / max(abs(dlnf), 1e-300)))
        ratio = max(ratio, STEP_MIN)
        share = _share(prob, v)
        # the energy falling while no partner grows (the points inside a narrow tongue are not the family's: their
        # energy rises above it and falls back, with the partner's share)
        falls = falls + 1 if E < pts[-2][1] and share >= PEAK_SHARE and _share(prob, pts[-2][3]) >= PEAK_SHARE else 0
        if falls >= PEAK_RUN:
            end, message = "peak", "the family's energy turns back: its maximum"
            break
        if E > E_reach and falls == 0:
            break
        if share < SHARE_MIN:
            pts.pop()                  # a partner takes the orbit over: jump from the last point before
            landed = gaps[-1][2] if gaps else 0.0
            if pts[-1][0] > landed and resonance(v, "a partner mode takes the orbit over"):
                continue
            if not message:
                k, p = partner = _partner(prob, v)
                end, message = "locked", (f"the family passes into a {k}:1 internal resonance with mode {p} at E = "
                                          f"{pts[-1][1]:.4g} J, f = {pts[-1][2]:.5g} Hz: that mode takes over "
                                          f"more than {1 - SHARE_MIN:.0%} of the orbit")
            break
    a, E, f, us = (list(c) for c in zip(*pts))
    return a, E, f, us, end, message, gaps, partner


class Skeleton:
    """The backbone family of one mode (module docstring): energies E (J, rising), frequencies f (Hz),
    modal amplitudes a and the condensed orbits u of its points, with the blips inside narrow tongues left
    out.  prob : the CondensedHBProblem; end / message : how the family ended; energy_peak : its energy
    maximum (J) when it turned back (no backbone above it), else None; partner : (k, 1-based mode) of the
    k:1 internal resonance that ended it ((1, 0) when none did)."""

    def __init__(self, prob, a, E, f, us, end, message, gaps, partner, mode):
        self.problem, self.mode = prob, int(mode)
        self.partner = (int(partner[0]), int(partner[1]))
        self.gaps = gaps
        self.end, self.message = end, message
        E = np.asarray(E, dtype=float)
        n = len(E)
        if end == "peak" and n:               # a turned-back family: up to its peak (among the points on the family)
            shares = np.array([_share(prob, u) for u in us])
            n = int(np.argmax(np.where(shares >= PEAK_SHARE, E, -np.inf))) + 1
        keep, lowest = [], math.inf
        for i in range(n - 1, -1, -1):           # a point inside a tongue lies above the family's later points
            if E[i] < lowest:
                keep.append(i)
                lowest = E[i]
        keep = keep[::-1]
        self.energy_peak = float(E[n - 1]) if end == "peak" and n else None
        self.energy = E[keep]
        self.frequency_hz = np.asarray(f, dtype=float)[keep]
        self.amplitude = np.asarray(a, dtype=float)[keep]
        self.orbits = [us[i] for i in keep]
        self.blips = n - len(keep)            # points left out below the end: inside narrow tongues
        self._interp = None
        self._shares = None
        self.truncation = self._truncation()

    def _truncation(self):
        """Estimated relative frequency error of each point from the truncation of the harmonics: the change of
        its frequency with two harmonics fewer (the same modal amplitude), an upper estimate."""
        from ..orbits.condensed_hb import CondensedHBProblem
        from ..orbits.hb_basis import HBBasis
        prob = self.problem
        step = 2 if prob.basis.kind == "odd" else 1
        if prob.basis.harmonics <= step:
            return np.full(len(self.energy), np.nan)
        lower = CondensedHBProblem(prob.sys, prob.r, HBBasis(prob.basis.harmonics - step, prob.basis.kind), prob.lin)
        out = []
        for u in self.orbits:
            v = _newton(lower, lower.from_family(prob, u))
            out.append(abs(v[-1] / u[-1] - 1.0) if v is not None else np.nan)
        return np.asarray(out)

    def truncation_at(self, E):
        """Estimated relative frequency error (truncation of the harmonics) of the skeleton at energy E (J): the
        largest of its two neighbouring points' (NaN outside its range or where not estimated)."""
        if not self.covers(E):
            return float("nan")
        j = int(np.clip(np.searchsorted(self.energy, E) - 1, 0, len(self.energy) - 2))
        return float(np.nanmax(self.truncation[j:j + 2])) if np.any(np.isfinite(self.truncation[j:j + 2])) else float("nan")

    def frequency_at(self, E):
        """Skeleton frequency (Hz) at energy E (J), interpolated in log E (monotone cubic, PCHIP: 1e-7 between
        points 5 % apart in amplitude); NaN outside its range."""
        if not self.covers(E):
            return float("nan")
        if self._interp is None:
            from scipy.interpolate import PchipInterpolator
            self._interp = PchipInterpolator(np.log(self.energy), self.frequency_hz)
        return float(self._interp(math.log(E)))

    def share_at(self, E):
        """Fundamental share (tongue_skip.fundamental_share: the fraction of the modal orbit's harmonic
        amplitudes in its fundamental) of the family's orbit at energy E (J), interpolated between its two
        neighbouring points in log E; NaN outside its range."""
        from .tongue_skip import fundamental_share, harmonic_label
        if not self.covers(E):
            return float("nan")
        if self._shares is None:
            self._shares = np.full(len(self.energy), np.nan)
        x = np.log(self.energy)
        j = int(np.clip(np.searchsorted(x, math.log(E)) - 1, 0, len(x) - 2))
        for i in (j, j + 1):
            if not np.isfinite(self._shares[i]):
                self._shares[i] = fundamental_share(harmonic_label(self.problem.modal_orbit(self.orbits[i]))[3])
        t = (math.log(E) - x[j]) / (x[j + 1] - x[j])
        return float((1 - t) * self._shares[j] + t * self._shares[j + 1])

    def covers(self, E):
        return len(self.energy) >= 2 and self.energy[0] <= E <= self.energy[-1]

    def _interpolated(self, E):
        x = np.log(self.energy)
        j = int(np.clip(np.searchsorted(x, math.log(E)) - 1, 0, len(x) - 2))
        t = (math.log(E) - x[j]) / (x[j + 1] - x[j])
        return (1 - t) * self.orbits[j] + t * self.orbits[j + 1]

    def orbit_at(self, E):
        """(x0 (m, at rest), T (s)) of the skeleton orbit at energy E, or None outside its range."""
        if not self.covers(E):
            return None
        q0, _, T = self.problem.state(self._interpolated(E))
        return self.problem.sys.to_physical(q0), T

    def family_orbit(self, system, E, settings, tol):
        """(problem, u): the skeleton's orbit at energy E (J), corrected on the energy level set (condensed
        HB with SKELETON_HARMONICS on the skeleton's modal system); None outside its range or where that
        does not converge.  A first guess for the branch's own method."""
        from .tongue_skip import level_set
        if not self.covers(E):
            return None
        u, _ = level_set(self.problem, self._interpolated(E), settings, min(tol, 1e-9))
        return None if u is None else (self.problem, u)

    def targets(self, E_entry, k, f_partner, margins=(0.003, 0.01, 0.03, 0.1)):
        """Energies (J) above E_entry where the skeleton's k f crosses and leaves the k:1 band around f_partner
        (Hz, the partner's linear frequency) by the relative ``margins``, on the side the family moves to;
        [] when the skeleton does not cross it above E_entry."""
        E, f = self.energy, self.frequency_hz
        above = E > E_entry
        if k < 2 or not np.any(above) or not f_partner > 0:
            return []
        kf = k * f[above] / f_partner - 1.0                 # relative distance of k f from the partner
        side = np.sign(kf[-1])
        at_entry = k * self.frequency_at(E_entry) / f_partner - 1.0
        if np.all(np.sign(kf) == side) and not abs(at_entry) < ENTRY_BAND:
            # the skeleton neither crosses the band nor enters it where the branch did: the partner's frequency
            # has moved with the amplitude (a strongly nonlinear partner, e.g. the 2-DOF benchmark's) and the
            # linear one says nothing; the tongue is traversed or jumped by rescaled backbone orbits
            return []
        out = []
        for m in margins:
            past = np.flatnonzero((np.sign(kf) == side) & (np.abs(kf) >= m))
            if len(past):
                E_t = float(E[above][past[0]])
                if not out or E_t > out[-1] * (1 + 1e-6):
                    out.append(E_t)
        return out


def compute_skeleton(system, mode, E_reach, harmonics=SKELETON_HARMONICS):
    """The Skeleton of linear mode ``mode`` (1-based) of the ModalSystem ``system`` up to E_reach (J)."""
    from ..orbits.condensed_hb import CondensedHBProblem
    from ..orbits.hb_basis import HBBasis
    r = int(mode) - 1
    prob = CondensedHBProblem(system, r, HBBasis(harmonics, "odd" if system.elements.odd else "full"))
    # start in the linear regime: at most 1e-6 of the reach (E = w^2 a^2 / 2 for the linear mode), lower until
    # the frequency is the linear one to 1e-8
    a0 = math.sqrt(2e-6 * E_reach) / prob.w_r
    for _ in range(20):
        u = _newton(prob, prob.start(a0)[0])
        if u is None or abs(u[-1] - 1.0) < 1e-8:
            break
        a0 /= 4
    return Skeleton(prob, *amplitude_family(prob, E_reach, a0), mode)


def skeleton(model, mode, energy_max, system_of, harmonics=SKELETON_HARMONICS):
    """The Skeleton of linear mode ``mode`` (1-based) of ``model`` up to REACH x energy_max (J) with
    ``harmonics``, cached per model, mode and harmonics (a cached one that reaches far enough, or that ended,
    is reused).  system_of(model, mode) gives the ModalSystem (every mode, or a Ritz basis for a large model;
    driver/api.py)."""
    with _lock:
        for (m, h, reach), sk in _cache.get(model, {}).items():
            if m == mode and h == harmonics and (reach >= REACH * energy_max or sk.end != "reach"):
                return sk
    sk = compute_skeleton(system_of(model, mode), mode, REACH * energy_max, harmonics)
    with _lock:
        _cache.setdefault(model, {})[(mode, harmonics, REACH * energy_max)] = sk
    return sk
