r"""The one-harmonic guide of the skeleton's stepping (amplitude_family.py): which sheet is the backbone.

With the fundamental alone (H = 1) the harmonic-balance family of a mode has no k:1 internal resonance with
k >= 2 (no harmonic k exists to resonate with a partner mode), so it passes every tongue smoothly.  The skeleton
with s.harmonics harmonics does not: near a k:1 resonance its family is a tongue's sheet, on which the
partner's k-th harmonic grows and the frequency moves away from the one-harmonic family, while the backbone
beyond the tongue is another sheet, nearer the one-harmonic family, that the stepping does not reach by small
steps (measured on the 2-DOF benchmark's NNM 1 at its 5:1 tongue: the sheet stepped into lies 3.2e-3 above the
one-harmonic frequency at 1e5 J with 0.6 % of the orbit in partner harmonics, the backbone 6e-5 below it with
0.12 %; the stepping followed the sheet to its fold at 1.3e5 J and beyond onto other sheets).

The guide steps the one-harmonic family to the amplitudes asked (``OneHarmonicGuide.at``) and
``nearer_sheet`` solves the skeleton's equations at the same modal amplitude from the one-harmonic orbit: where
that lands on another orbit, nearer the one-harmonic frequency and with less of the orbit in partner harmonics
(``family_share``), the stepping continues from there (the backbone beyond the tongue), from where that sheet
begins (``sheet_start``); the stepping's points above that amplitude are dropped.
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.natural import LogStepper, LogSteps
from .amplitude_orbit import solve_at_amplitude, family_share
from .settings import SkeletonSettings

__all__ = ["OneHarmonicGuide", "nearer_sheet", "better_of", "sheet_start", "guided_jump"]








class OneHarmonicGuide:
    """The followed mode's family with the fundamental alone, on the skeleton problem ``prob``'s modal system
    (module docstring), stepped upward in the modal amplitude a (sqrt(kg) m) as it is asked; ends (``at`` gives
    None) where its Newton fails (a 1:1 resonance or a fold of the one-harmonic family)."""

    def __init__(self, prob, settings=SkeletonSettings()):
        from ..orbits.condensed_hb import CondensedHBProblem
        from ..orbits.hb_basis import HBBasis
        self.skeleton_problem = prob
        self.prob = CondensedHBProblem(prob.sys, prob.r, HBBasis(1, prob.basis.kind), prob.lin)
        self._nD = self.prob.nb * self.prob.ns
        self._a, self._u = [], []
        self._end = math.inf
        self.s = settings
        # its stepping in ln a (continuation/natural.py); at a first step the orbit is scaled with a
        self._stepper = LogStepper(self._solve, LogSteps(settings.guide_step_min, settings.guide_step_min,
                                                         settings.guide_step_max, settings.guide_step_growth),
                                   scaled_first=slice(0, self._nD))

    def _solve(self, a, guess):
        guess = guess.copy()
        guess[self._nD] = a * self.prob.beta
        return solve_at_amplitude(self.prob, guess)

    def _points(self):
        return list(zip(self._a[-2:], self._u[-2:]))

    def _step(self, a1):
        """(orbit, predictor's relative frequency error) of the guide at a1 above its last point, from the secant
        predictor in ln a; (None, inf) where Newton fails."""
        guess = self._stepper.predict(self._points(), a1)
        u = self._solve(a1, guess)
        return (None, math.inf) if u is None else (u, abs(u[-1] / guess[-1] - 1.0))

    def _cover(self, a):
        """Solve the guide up to modal amplitude a (or at a, below its first point); False beyond its end."""
        s = self.s
        if not a < self._end:
            return False
        if not self._a or a < self._a[0]:        # the first point (or one below the first)
            guess = self.prob.start(a)[0] if not self._a else self._u[0].copy()
            if self._a:
                guess[:self._nD] *= a / self._a[0]
            u = self._solve(a, guess)
            if u is None:
                self._end = a if not self._a else self._end
                return False
            self._a.insert(0, a)
            self._u.insert(0, u)
        while self._a[-1] < a:                   # step the family up past a
            a1 = self._a[-1] * self._stepper.ratio
            u, err = self._step(a1)
            if u is None or (err > s.guide_prediction and len(self._a) > 1):
                if self._stepper.shorter():      # too far for the interpolation (or for Newton): shorter
                    continue
                if u is None:                        # the family ends between: at a itself, if there
                    u = self._step(a)[0] if a < a1 else None
                    if u is None:
                        self._end = min(a, a1)
                        return False
                    a1 = a
            # the next step: the secant predictor's error grows as the square of the step
            self._stepper.accept(math.sqrt(s.guide_prediction / max(err, 1e-300)) if len(self._a) > 1 else 2.0)
            self._a.append(a1)
            self._u.append(u)
        return True

    def at(self, a):
        """The guide's orbit (u of its one-harmonic problem) at modal amplitude a, or None beyond its end: solved at
        amplitudes s.guide_step_min..GUIDE_STEP_MAX apart and interpolated between them (degree s.guide_order in ln a;
        the skeleton asks at every step, for a frequency to compare and a first guess, which need no Newton solve of
        their own)."""
        if not self._cover(a):
            return None
        j = int(np.searchsorted(self._a, a))
        if self._a[j] == a:
            return self._u[j]
        x, w = self._weights(j, a)
        u = sum(wk * self._u[k] for k, wk in zip(x, w))
        u[self._nD] = a * self.prob.beta
        return u

    def _weights(self, j, a):
        """The stored points around a (a between points j - 1 and j) and their Lagrange weights in ln a."""
        n = min(len(self._a), self.s.guide_order + 1)  # the nearest n points around a
        i = min(max(j - n // 2, 0), len(self._a) - n)
        x = range(i, i + n)
        t = [math.log(self._a[k]) for k in x]
        s = math.log(a)
        w = []
        for m in range(n):
            p = 1.0
            for q in range(n):
                if q != m:
                    p *= (s - t[q]) / (t[m] - t[q])
            w.append(p)
        return x, w

    def deviation(self, a, u):
        """Relative frequency distance f / f_guide(a) - 1 of the skeleton's orbit u at modal amplitude a from the
        guide's (its frequency interpolated alone); None beyond the guide's end."""
        if not self._cover(a):
            return None
        j = int(np.searchsorted(self._a, a))
        if self._a[j] == a:
            return float(u[-1] / self._u[j][-1] - 1.0)
        x, w = self._weights(j, a)
        return float(u[-1] / sum(wk * self._u[k][-1] for k, wk in zip(x, w)) - 1.0)


def nearer_sheet(guide, a, v):
    """The skeleton's orbit at modal amplitude a solved from the guide's orbit there, when it is better_of v (the
    stepping's orbit there): (u, family_share) of the backbone's sheet; else None."""
    prob = guide.skeleton_problem
    g = guide.at(a)
    if g is None:
        return None
    c = solve_at_amplitude(prob, prob.from_family(guide.prob, g), iterations=60)
    if c is None or not better_of(guide, a, c, v):
        return None
    return c, family_share(prob, c)


def better_of(guide, a, c, v):
    """Is the skeleton's orbit c at modal amplitude a another orbit than v, within s.sheet_frequency of its frequency,
    nearer the guide's (where the guide is trusted, s.guide_trust), with less of its orbit in partner harmonics and no
    more energy, to s.energy_slack (a tongue's sheet holds the partner's energy besides the followed mode's; an orbit
    at the same amplitude with more is another mode's motion at the fundamental, which family_share does not
    count)?"""
    s = guide.s
    g = guide.at(a)
    prob = guide.skeleton_problem
    return (g is not None and np.linalg.norm(c - v) > 1e-6 * np.linalg.norm(v)
            and abs(math.log(c[-1] / v[-1])) <= s.sheet_frequency
            and abs(c[-1] / g[-1] - 1.0) < min(abs(v[-1] / g[-1] - 1.0), s.guide_trust)
            and family_share(prob, c) > family_share(prob, v)
            and prob.energy(c) <= prob.energy(v) * (1 + s.energy_slack))


def _stepping_orbit(prob, pts, a):
    """The stepping's orbit at modal amplitude a between its points (solved from their interpolation in ln a), or
    None above its last point or where that does not converge."""
    j = next((i for i, p in enumerate(pts) if p[0] >= a), None)
    if j is None or j == 0:
        return None
    (a0, _, _, u0), (a1, _, _, u1) = pts[j - 1], pts[j]
    t = math.log(a / a0) / math.log(a1 / a0)
    guess = (1 - t) * u0 + t * u1
    guess[prob.nb * prob.ns] = a * prob.beta
    return solve_at_amplitude(prob, guess)


def sheet_start(prob, guide, pts, a, found):
    """Where the backbone's sheet found at amplitude a (found: (orbit, share) from nearer_sheet or guided_jump)
    begins along the stepping's points pts: that sheet followed down in amplitude (steps of s.sheet_resolution,
    secant predictor) while it is still better_of the stepping's sheet at the same amplitude (above the stepping's
    last point: while it converges).  (a, u, share) of its lowest such orbit."""
    s = guide.s
    nD = prob.nb * prob.ns

    def at_amplitude(a_t, guess):
        guess[nD] = a_t * prob.beta
        return solve_at_amplitude(prob, guess)

    # down in ln a by fixed steps (continuation/natural.py: secant predictor, Newton at the fixed amplitude)
    down = LogStepper(at_amplitude, LogSteps(1 / s.sheet_resolution, 1 / s.sheet_resolution, 1 / s.sheet_resolution))
    (v, share), path = found, [(a, found[0])]
    while a / s.sheet_resolution > pts[0][0]:
        a_t, c = down.trial(path)
        if c is None or abs(math.log(c[-1] / v[-1])) > s.sheet_frequency / 3:    # no solution, or another family
            break
        if a_t <= pts[-1][0]:
            w = _stepping_orbit(prob, pts, a_t)
            if w is None or not better_of(guide, a_t, c, w):
                break
        a, v, share = a_t, c, family_share(prob, c)
        path = [path[-1], (a, v)]
    return a, v, share


def guided_jump(prob, guide, pts, share0, jumps):
    """Past the stepping's last point (a0, E0, f0, u0) = pts[-1], where its family folds or jumps: the skeleton's
    orbits at a0 (1 + delta), delta in ``jumps``, solved from the guide's orbits there (where the guide is trusted,
    s.guide_trust); the first that lies within s.sheet_frequency of the last point's frequency, nearer the guide's than
    the last point (or within s.dev_check of it), holds no more of its orbit in partner harmonics (family_share, share0
    the last point's) and no more energy than s.jump_energy_power allows: (a, (u, share)); else None."""
    s = guide.s
    a0, E0, _, u0 = pts[-1]
    dev0 = guide.deviation(a0, u0)
    if dev0 is None or not abs(dev0) <= s.guide_trust:
        return None
    for delta in jumps:
        a = a0 * (1 + delta)
        g = guide.at(a)
        if g is None:
            return None
        c = solve_at_amplitude(prob, prob.from_family(guide.prob, g), iterations=60)
        if c is None:
            continue
        share = family_share(prob, c)
        if (abs(c[-1] / g[-1] - 1.0) < max(abs(dev0), s.dev_check) and share >= share0
                and abs(math.log(c[-1] / u0[-1])) <= s.sheet_frequency
                and prob.energy(c) <= E0 * (1 + delta) ** s.jump_energy_power):
            return a, (c, share)
    return None
