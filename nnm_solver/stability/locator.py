r"""The branch between two converged points of the continuation, for event location.

Between two consecutive points u_a and u_b of the continuation (u_b reached by a step s along the
tangent p_a of u_a), the branch is parametrised by the pseudo-arclength sigma in [0, s]: u(sigma)
solves F(u) = 0 on the hyperplane (w^2 p_a)^T (u - u_a - sigma p_a) = 0, by the same corrector as the
continuation (continuation.correct_factored).  ``Locator`` gives the points (cached), their energy, energy
slope and Floquet multipliers, and, with the scalar root finders (roots.py), what the event locators use (events.py, krein.py).
"""
from __future__ import annotations

import copy

import numpy as np

from ..continuation.engine import CorrectorFailure, _energy_slope, correct_factored, tangent_factored
from ..continuation.linalg import LeastSquares, stacked
from .floquet import is_stable, real_crossing, sort_multipliers
from .roots import BracketRoots
from .settings import STABILITY
from .step_policy import event_rtol, mid_step_check  # noqa: F401 (part of this module's interface)

__all__ = ["Locator", "EVENT_RTOL", "event_rtol", "mid_step_check"]

#: an alias of settings.py's STABILITY.event_rtol (the code reads that)
EVENT_RTOL = STABILITY.event_rtol


class Locator(BracketRoots):
    """Points of the branch between a converged point a and the next one, for event location.

    problem : the continuation's problem (a shallow copy is used, so the continuation's own state --
    phase reference, last monodromy -- is untouched); settings, tol : the continuation's.
    """

    #: relative energy tolerance of the located events (set per step: event_rtol)
    rtol = STABILITY.event_rtol

    def __init__(self, problem, settings, tol, u_a, p_a, step=None, rtol=STABILITY.event_rtol):
        """step : the continuation's step from a to the next point (scaled units): located points closer
        than STABILITY.chord_reach x step to the latest one start from it (chord iterations with its factorisation).
        rtol : relative energy tolerance of the events (event_rtol)."""
        self.step = step
        self.rtol = rtol            # relative energy tolerance of located events (event_rtol)
        self.latest = None          # (sigma, u, factorisation of [J; (w^2 p_a)^T]) of the latest located point
        self.problem = copy.copy(problem)
        self.settings = settings
        self.tol = tol
        self.u_a = u_a
        self.p_a = p_a
        self.w = problem.scale(u_a) if hasattr(problem, "scale") else np.ones(len(u_a))
        self.cache = {}
        self.factors = {}           # sigma -> factorisation of [J; (w^2 p_a)^T] of a seeded point
        self.spectra = {}           # sigma -> (multipliers, collision coordinates)
        self.locals = {}            # (sigma, shift) -> the local eigen-solver's coordinates (local_collision)
        self.rough = set()          # sigmas of points kept without their own tangent (at: tangent=False)

    def seed(self, sigma, u, J, factor):
        """Record a converged point at sigma (e.g. the two points of the continuation's step, so that they
        are not computed again); factor : the factorisation of [J; (w^2 p_a)^T] at it."""
        self.cache[float(sigma)] = (u, J, tangent_factored(J, self.p_a, self.w, factor)[0])   # (the engine's J)
        self.factors[float(sigma)] = factor

    def jumped(self, limit=STABILITY.jump_limit):
        """A reason (str) if the step from a to its seeded end point b did not follow one branch, else ''.

        The branch's point at mid-step (on the hyperplane sigma = step / 2) is found by chord iterations from the
        cubic Hermite interpolant of the two ends, with b's factorisation (no new Jacobian: a few state sweeps).
        On a resolved branch it lies within a few thousandths of the step of that interpolant.  When the step's
        corrector landed on another branch running alongside (near a tongue), the interpolant joins two branches
        and the mid-step point is a sizeable part of the step away from it.  Measured on the aircraft's NNM 20
        and the 2-DOF's NNM 1: legitimate steps at most 1.7e-3 and 1.3e-2 of the step, the two jumps found 0.22
        and 0.39.  Not judged ('') when a tangent at an end is nearly parallel to the hyperplanes (no Hermite
        interpolant, e.g. at a fold) or b was not seeded."""
        s = self.step
        sigma = 0.5 * s if s is not None else None
        # (the interpolant of the two known points is also ``prediction``'s at sigma: the same numbers)
        u_pred = self._ends_interpolant(sigma) if s is not None and float(s) in self.factors else None
        if u_pred is None:
            return ""
        # (where the interpolant is on the branch already, the corrector returns it after one residual: d = 0)
        try:
            u, J, _, _, factor = correct_factored(self.problem, u_pred, self.p_a, self.settings, self.tol, self.w,
                                                  start=(u_pred, self.factors[float(s)]), refresh=False)
        except CorrectorFailure as exc:
            return f"no convergence at mid-step ({exc})"
        if J is not None:           # (a fresh Jacobian was needed on the way: keep the point for event location)
            self.latest = (sigma, u, factor)
            self._keep(sigma, u, J, factor)
        d = np.linalg.norm(self.w * (u - u_pred)) / abs(s)
        return f"the mid-step point lies {d:.2f} step lengths off the ends' interpolant" if d > limit else ""

    def strayed(self, limit=STABILITY.jump_limit):
        """A reason (str) if a point located inside the step lies farther than ``limit`` x the step from the cubic
        Hermite interpolant of the step's two ends (the measure of ``jumped``, at every located point instead of the
        mid-step one only), else ''.  No new point is computed.

        The mid-step point alone misses a step that crossed a narrow tongue near one end: the aircraft's NNM 20 (gauss6,
        the defaults), the step 1.3247 -> 1.6528 J from the backbone's sheet that enters the 3:1 tongue at 35.1336 Hz
        landed on the sheet beyond it; its mid-step point (1.480 J, on that sheet) lay 0.0499 step lengths off the
        interpolant, while the points the event location placed at 1/8 to 1/4 of the step lay 0.07-0.18 off (on that
        sheet near its own energy minimum, 1.37392 J, where the flag changes: the dense route reported that change as
        the branch's).  Points of a resolved step lie within the interpolant's error of it (the mid-step one, its
        largest: at most 1.7e-3 and 1.3e-2 of the step on the aircraft and the 2-DOF, ``jumped``).  Not judged ('')
        where an end's tangent is nearly parallel to the hyperplanes (e.g. at a fold)."""
        s = self.step
        if s is None or 0.0 not in self.cache or float(s) not in self.cache:
            return ""
        worst, where = 0.0, None
        for key in self.cache:
            if key == 0.0 or key == float(s):
                continue
            u_i = self._ends_interpolant(key)
            if u_i is None:
                return ""
            d = np.linalg.norm(self.w * (self.cache[key][0] - u_i)) / abs(s)
            if d > worst:
                worst, where = d, key
        if worst > limit:
            return (f"the point located at {where / s:.3g} of the step lies {worst:.2f} step lengths off the ends' "
                    f"interpolant")
        return ""

    def _ends_interpolant(self, sigma):
        """The cubic Hermite interpolant of the step's two ends (sigma 0 and self.step) at sigma, or None where they
        are not both known or an end's tangent is nearly parallel to the hyperplanes."""
        s = self.step
        if s is None or 0.0 not in self.cache or float(s) not in self.cache:
            return None
        d0, d1 = self._slope(0.0), self._slope(float(s))
        if d0 is None or d1 is None:
            return None
        u0, u1 = self.cache[0.0][0], self.cache[float(s)][0]
        t = sigma / s
        return ((2 * t ** 3 - 3 * t ** 2 + 1) * u0 + (t ** 3 - 2 * t ** 2 + t) * s * d0
                + (3 * t ** 2 - 2 * t ** 3) * u1 + (t ** 3 - t ** 2) * s * d1)

    def _slope(self, key):
        """d u / d sigma at a known point, or None where its tangent is nearly parallel to the hyperplanes."""
        _, _, p = self.cache[key]
        d = (self.w * self.w * self.p_a) @ p
        return p / d if abs(d) > 0.3 * np.linalg.norm(self.w * p) else None

    def prediction(self, sigma):
        """A first iterate on sigma's hyperplane: the cubic Hermite interpolant of the known points around
        sigma (values and tangents, with d u / d sigma = p / ((w^2 p_a) . p)), or the tangent line of the
        nearest known point when sigma is outside them (the tangent line of a when none is known).  The
        interpolant lies on the hyperplane exactly (sigma is linear in u)."""
        known = sorted(self.cache)
        if not known:
            return self.u_a + sigma * self.p_a
        def slope(key):
            return self.cache[key][0], self._slope(key)

        left = [k for k in known if k <= sigma]
        right = [k for k in known if k > sigma]
        if left and right:
            k0, k1 = left[-1], right[0]
            (u0, d0), (u1, d1) = slope(k0), slope(k1)
            h, t = k1 - k0, (sigma - k0) / (k1 - k0)
            if d0 is None or d1 is None:            # the tangent turns across sigma's hyperplane: the chord
                return u0 + t * (u1 - u0)
            return ((2 * t ** 3 - 3 * t ** 2 + 1) * u0 + (t ** 3 - 2 * t ** 2 + t) * h * d0
                    + (3 * t ** 2 - 2 * t ** 3) * u1 + (t ** 3 - t ** 2) * h * d1)
        k = left[-1] if left else right[0]
        u, d = slope(k)
        return u + (sigma - k) * (self.p_a if d is None else d)

    def at(self, sigma, tangent=True):
        """(u, J, p) on the branch at pseudo-arclength sigma from point a (CorrectorFailure if the
        corrector does not converge there); J is None where it is not kept (_keep).

        tangent=False: the orbit is what is needed, not its Jacobian (the Krein follower's local evaluations, where
        the multipliers are swept at the orbit itself: problem.stability_needs_jacobian False).  The corrector's
        chord iterations may then end on an older Jacobian's factorisation, with no new Jacobian (a quarter-period
        sensitivity sweep and a QR) at the converged point; p is then the latest point's tangent (a predictor's
        slope, ``rough``) until a later call asks for the point with its tangent."""
        key = float(sigma)
        rough = not tangent and not getattr(self.problem, "stability_needs_jacobian", True)
        if key in self.cache:
            if key in self.rough and not rough:     # its own tangent now: the Jacobian at the point
                u = self.cache[key][0]
                _, J = self.problem.jacobian(u)
                factor = LeastSquares(stacked(J, self.w * self.w * self.p_a))
                self.rough.discard(key)
                self.latest = (key, u, factor)
                self._keep(key, u, J, factor)
            return self.cache[key]
        u_pred = self.prediction(key)
        result = self._from_latest(sigma, u_pred, refresh=not rough)
        if result is None:
            result = correct_factored(self.problem, u_pred, self.p_a, self.settings, self.tol, self.w,
                                      refresh=not rough)
        u, J, _, _, factor = result
        if factor is None:          # converged on an older Jacobian: the point, with a neighbour's tangent
            near = min(self.cache, key=lambda k: abs(k - key)) if self.cache else None
            p = self.p_a if near is None else self.cache[near][2]
            self.cache[key] = (u, None, p)
            self.rough.add(key)
            if self.latest is not None:
                self.latest = (key, u, self.latest[2])
            return self.cache[key]
        self.latest = (key, u, factor)
        self._keep(key, u, J, factor)
        return self.cache[key]

    def _keep(self, key, u, J, factor):
        """Cache a located point: u, its Jacobian (only where the multipliers need it: problem.
        stability_needs_jacobian; else None, since a located point's Jacobian, n x (n + 1), is not used again once
        its tangent is known: at n = 4,400 a Krein collision's ~30 points kept 4.6 GB of them) and its tangent."""
        p = tangent_factored(J, self.p_a, self.w, factor)[0]
        keep = getattr(self.problem, "stability_needs_jacobian", True)
        self.cache[key] = (u, J if keep else None, p)

    def _from_latest(self, sigma, u_pred, refresh=True):
        """The point at sigma from the latest located point when it is close (the root finders' last
        iterations): chord iterations with that point's factorisation, from that point moved to sigma's hyperplane
        (all the hyperplanes are parallel), to a tighter tolerance (chord_tol: chord iterations stop just below the
        tolerance, where Newton overshoots it: fold and Krein test functions need the accuracy).  The result must
        continue the branch: within STABILITY.chord_continuity x |d sigma| of that point, and within
        STABILITY.jump_limit x the distance to the nearest known point (plus the corrector's accuracy) of the prediction
        (the interpolant of the known points).  Near a tongue a hyperplane can cut the solution curve twice within a
        step, and another branch can run alongside a few millionths away: on the aircraft's NNM 20 at 37.6 J the chord
        iterations converged there, 0.16 d sigma off the prediction (points on the branch: below 0.01).  Otherwise None
        (fresh Newton from the prediction).  (Starting the chord iterations at the prediction instead was tried:
        on the 2-DOF's 5:1 tongue it placed a branch point 14 % off and lost the tongue's inner loop.)"""
        if self.latest is None or self.step is None:
            return None
        s_l, u_l, factor = self.latest
        ds = abs(sigma - s_l)
        if ds > STABILITY.chord_reach * self.step:
            return None
        tol = self.chord_tol()
        try:
            result = correct_factored(self.problem, u_pred, self.p_a, self.settings, tol, self.w,
                                      start=(u_l + (sigma - s_l) * self.p_a, factor), refresh=refresh)
        except CorrectorFailure:
            return None
        if np.linalg.norm(self.w * (result[0] - u_l)) > STABILITY.chord_continuity * ds + 10 * self.tol:
            return None
        nearest = min(abs(sigma - k) for k in self.cache) if self.cache else ds
        if np.linalg.norm(self.w * (result[0] - u_pred)) > STABILITY.jump_limit * nearest + 10 * tol:
            return None
        return result

    def chord_tol(self):
        """The chord iterations' corrector tolerance (relative periodicity error): STABILITY.chord_tol_factor x the
        continuation's, and at most STABILITY.chord_event_fraction x the events' relative energy tolerance rtol.
        Across an event's final bracket the orbit changes by about rtol / 2 (E grows like the amplitude squared or
        faster); the located orbits' error must lie well below that, or a test function's noise exceeds its change
        across the bracket and the root finders halve the bracket on noise.  (A tolerance from each point's distance to
        the latest one instead, looser while the iterates are far apart, left the noise at the final bracket, whose
        other end was often computed far from its then neighbours: settings.py.)"""
        return min(STABILITY.chord_tol_factor * self.tol, STABILITY.chord_event_fraction * self.rtol)

    def energy(self, sigma):
        return self.problem.energy(self.at(sigma)[0])

    def slope(self, sigma):
        u, _, p = self.at(sigma)
        return _energy_slope(self.problem.energy, u, p)

    def multipliers(self, sigma):
        """Floquet multipliers at sigma (sorted, computed once per point)."""
        key = float(sigma)
        if key not in self.spectra:
            u, J, p = self.at(sigma)
            self.refresh(u, J)
            mu = sort_multipliers(self.problem.multipliers(u, p))
            self.spectra[key] = (mu, getattr(self.problem, "collision", None))
        return self.spectra[key][0]

    def prefetch(self, sigmas):
        """Compute the multipliers at several sigmas with their eigenproblems side by side: all but the last in
        the worker thread (problem.multipliers_later), the last in this one.  Only where the problem computes them
        in the background (problem.background_spectrum); else nothing is done here (multipliers computes each one
        when asked)."""
        todo = [float(x) for x in sigmas if float(x) not in self.spectra]
        if len(todo) < 2 or not getattr(self.problem, "background_spectrum", False):
            return
        jobs = []
        for key in todo[:-1]:
            u, J, p = self.at(key)
            self.refresh(u, J)
            jobs.append((key, self.problem.multipliers_later(u, p)))
        self.multipliers(todo[-1])
        for key, job in jobs:
            mu, collision = job()
            self.spectra[key] = (sort_multipliers(mu), collision)

    def refresh(self, u, J):
        """Make u the problem's accepted point; its monodromy is that of the latest Jacobian evaluation,
        so it is evaluated again when a later point was computed since (a cached u)."""
        last = self.problem.last_evaluated() if hasattr(self.problem, "last_evaluated") else None
        # (quarter-period shooting sweeps the maps of its multipliers at the accepted point itself)
        needs = getattr(self.problem, "stability_needs_jacobian", True)
        if needs and last is not None and not np.array_equal(last, u):
            _, J = self.problem.jacobian(u)
        self.problem.accept(u, J)

    def stable(self, sigma, tol=STABILITY.stability_tol):
        """The stability flag at sigma (floquet.is_stable; tol: on the multipliers' modulus excess)."""
        return is_stable(self.multipliers(sigma), tol)

    def local_collision(self, sigma, shift):
        """The problem's collision coordinates at sigma nearest ``shift`` (problem.local_collision), or None.

        Away from the trivial coordinate -1 (the family direction's, which the full spectrum deflates) the point is
        computed without its own tangent (at: tangent=False) and the map is not deflated: its eigenvalues near the
        shift are those of the deflated map (deflation by the exact family direction leaves the others unchanged;
        by a neighbour's tangent it would move them to first order in its error, which near a collision is
        amplified by the square root).  Where the trivial coordinate lies in the local solver's window after all
        (a sparse spectrum, or a small model's full one), the point's tangent is computed and the map deflated."""
        if not hasattr(self.problem, "local_collision"):
            return None
        key = (float(sigma), complex(shift))        # (asked again: a margin point of the follower's check)
        if key not in self.locals:
            self.locals[key] = self._local_collision(sigma, shift)
        return self.locals[key]

    def _local_collision(self, sigma, shift):
        reach = STABILITY.trivial_reach
        u, J, p = self.at(sigma, tangent=abs(complex(shift) + 1.0) < reach)
        self.refresh(u, J)
        if float(sigma) not in self.rough:
            return self.problem.local_collision(p, shift)
        c = self.problem.local_collision(np.zeros_like(p), shift)
        if c is None or not np.any(np.abs(np.asarray(c) + 1.0) < reach):
            return c
        u, J, p = self.at(sigma)            # the trivial coordinate is in the window: deflated by the point's tangent
        self.refresh(u, J)
        return self.problem.local_collision(p, shift)

    def collision(self, sigma):
        """Collision coordinates of the multipliers at sigma (problem.collision), or None."""
        self.multipliers(sigma)
        return self.spectra[float(sigma)][1]

    def real_crossing(self, sigma):
        """max_i |Re rho_i| - 1, rho = (mu + 1/mu) / 2 over the non-trivial multipliers:
        smooth through a real pair's collision at +1 or -1 (rho = cos(theta) on the circle, cosh or
        -cosh off it), negative while stable; its zero is where the pair leaves the circle."""
        return real_crossing(self.multipliers(sigma))

    def around(self, sigma):
        """The known points nearest sigma on each side (sigma keys; None where there is none)."""
        keys = sorted(k for k in self.cache if k != float(sigma))
        left = [k for k in keys if k < sigma]
        right = [k for k in keys if k > sigma]
        return (left[-1] if left else None), (right[0] if right else None)
