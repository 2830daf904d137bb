r"""Events along a branch located between two converged points, and classified.

Between two consecutive points u_a and u_b of the continuation (u_b reached by a step s along the
tangent p_a of u_a), the branch is parametrised by the pseudo-arclength sigma in [0, s]: u(sigma)
solves F(u) = 0 on the hyperplane (w^2 p_a)^T (u - u_a - sigma p_a) = 0, by the same corrector as the
continuation (continuation.correct).  A scalar test function g(u(sigma)) that changes sign between
the two points is zeroed by the Illinois (regula falsi) method, or by bisection when it is a flag:

* fold         g = dE/ds, the energy's derivative along the local tangent (an energy extremum);
* stability    the stability flag of the non-trivial Floquet multipliers (floquet.py);
* energy_max   g = E - energy_max (the branch ends exactly at the requested energy).

Events are located to a relative energy tolerance of 5e-7 (or to a step of 1e-12 in sigma) and
stored with their orbit (x0, v0 in m, m/s; period in s).  A change of stability is classified by the
critical multiplier on its unstable side: ``branch_point`` (a real pair through +1 away from a fold:
pitchfork or transcritical), ``period_doubling`` (through -1), ``torus`` (a complex quadruple leaves
the unit circle: a Krein collision); at an energy fold the stability change is part of the ``fold``
(its key ``stability_change`` is then "loss" or "gain").
"""
from __future__ import annotations

import copy

import numpy as np

from .continuation import CorrectorFailure, _energy_slope, correct_factored, tangent_factored
from .floquet import instability_kind, is_stable, krein_gap, real_crossing, sort_multipliers

__all__ = ["Locator", "classify_multipliers", "EVENT_KINDS"]

EVENT_KINDS = ("fold", "branch_point", "period_doubling", "torus")

#: relative energy tolerance of located events
EVENT_RTOL = 5e-7

#: a stability change through +1 is a fold's when the flags on either side of the fold, this many steps from it,
#: are those of the step's two ends
FOLD_REACH = 1e-2

#: complex pairs at a step's unstable end followed to their Krein collisions (the first one changes the stability)
MAX_KREIN_PAIRS = 4

#: full-flag probes between the stable end and a located Krein collision (collisions undone inside the step)
KREIN_PROBES = 3

#: a located point within this many steps of the latest one starts from it (Locator._from_latest; 1: always)
CHORD_REACH = 1.0
#: ... to a corrector tolerance this much tighter than the continuation's
CHORD_TOL_FACTOR = 1e-2
#: ... and must lie within this many times the pseudo-arclength difference from it (the same cut of the curve)
CHORD_CONTINUITY = 3.0


#: the kind of instability of a multiplier set (floquet.instability_kind)
classify_multipliers = instability_kind


class Locator:
    """Points of the branch between a converged point a and the next one, for event location.

    problem : the continuation's problem (a shallow copy is used, so the continuation's own state --
    phase reference, last monodromy -- is untouched); settings, tol : the continuation's.
    """

    def __init__(self, problem, settings, tol, u_a, p_a, step=None):
        """step : the continuation's step from a to the next point (scaled units): located points closer
        than CHORD_REACH x step to the latest one start from it (chord iterations with its factorisation)."""
        self.step = step
        self.latest = None          # (sigma, u, factorisation of [J; (w^2 p_a)^T]) of the latest located point
        self.problem = copy.copy(problem)
        self.settings = settings
        self.tol = tol
        self.u_a = u_a
        self.p_a = p_a
        self.w = problem.scale(u_a) if hasattr(problem, "scale") else np.ones(len(u_a))
        self.cache = {}
        self.spectra = {}           # sigma -> (multipliers, collision coordinates)

    def seed(self, sigma, u, J, factor):
        """Record a converged point at sigma (e.g. the two points of the continuation's step, so that they
        are not computed again); factor : the factorisation of [J; (w^2 p_a)^T] at it."""
        self.cache[float(sigma)] = (u, J, tangent_factored(J, self.p_a, self.w, factor)[0])

    def prediction(self, sigma):
        """A first iterate on sigma's hyperplane: the cubic Hermite interpolant of the known points around
        sigma (values and tangents, with d u / d sigma = p / ((w^2 p_a) . p)), or the tangent line of the
        nearest known point when sigma is outside them (the tangent line of a when none is known).  The
        interpolant lies on the hyperplane exactly (sigma is linear in u)."""
        known = sorted(self.cache)
        if not known:
            return self.u_a + sigma * self.p_a
        row = self.w * self.w * self.p_a

        def slope(key):
            u, _, p = self.cache[key]
            d = row @ p
            return u, (p / d if abs(d) > 0.3 * np.linalg.norm(self.w * p) else None)

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

    def at(self, sigma):
        """(u, J, p) on the branch at pseudo-arclength sigma from point a (CorrectorFailure if the
        corrector does not converge there)."""
        key = float(sigma)
        if key not in self.cache:
            u_pred = self.prediction(key)
            result = self._from_latest(sigma, u_pred)
            if result is None:
                result = correct_factored(self.problem, u_pred, self.p_a, self.settings, self.tol, self.w)
            u, J, _, _, factor = result
            self.latest = (key, u, factor)
            self.cache[key] = (u, J, tangent_factored(J, self.p_a, self.w, factor)[0])
        return self.cache[key]

    def _from_latest(self, sigma, u_pred):
        """The point at sigma from the latest located point when it is close (the root finders' last
        iterations): first iterate that point moved to sigma's hyperplane (all the hyperplanes are parallel),
        chord iterations with its factorisation, to a tolerance CHORD_TOL_FACTOR tighter (chord iterations stop
        just below the tolerance, where Newton overshoots it: fold test functions need the accuracy).  The
        result must continue the branch from that point (distance at most CHORD_CONTINUITY x |d sigma|: near a
        tongue a hyperplane can cut the solution curve twice within a step); otherwise None (fresh Newton)."""
        if self.latest is None or self.step is None:
            return None
        s_l, u_l, factor = self.latest
        ds = abs(sigma - s_l)
        if ds > CHORD_REACH * self.step:
            return None
        try:
            result = correct_factored(self.problem, u_pred, self.p_a, self.settings, CHORD_TOL_FACTOR * self.tol,
                                      self.w, start=(u_l + (sigma - s_l) * self.p_a, factor))
        except CorrectorFailure:
            return None
        if np.linalg.norm(self.w * (result[0] - u_l)) > CHORD_CONTINUITY * ds + 10 * self.tol:
            return None
        return result

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

    def refresh(self, u, J):
        """Make u the problem's accepted point; its monodromy is that of the latest Jacobian evaluation,
        so it is evaluated again when a later point was computed since (a cached u)."""
        last = getattr(self.problem, "_last_residual", None)
        if last is not None and not np.array_equal(last[0], u):
            _, J = self.problem.jacobian(u)
        self.problem.accept(u, J)

    def stable(self, sigma):
        return is_stable(self.multipliers(sigma))

    def local_collision(self, sigma, shift):
        """The problem's collision coordinates at sigma nearest ``shift`` (problem.local_collision), or None."""
        if not hasattr(self.problem, "local_collision"):
            return None
        u, J, p = self.at(sigma)
        self.refresh(u, J)
        return self.problem.local_collision(p, shift)

    def collision(self, sigma):
        """Collision coordinates of the multipliers at sigma (problem.collision), or None."""
        self.multipliers(sigma)
        return self.spectra[float(sigma)][1]

    def krein(self, lo, hi, rho_stars, ends=None, depth=0):
        """sigma at a Krein collision between lo and hi (stable at one end, complex pairs at the other).

        Each candidate pair (rho_stars: the real parts of the complex collision coordinates at the unstable
        end, most unstable first) is followed by a secant on its smooth test function krein_gap (the squared
        half-distance of the two colliding coordinates, negative once they are a complex pair), evaluated by
        the problem's local eigen-solver (``local_collision``) where it has one.  Several pairs can collide
        within one step: the stability changes at the collision nearest the stable end.  The result is
        checked with the full flags around it; if they do not change there, bisection on the full flag.
        ends : optional ((stable, coordinates) at lo, at hi), known from the two points, to save their
        evaluation.  Returns (lo, hi) like bisect."""
        rho_stars = [rho_stars] if np.isscalar(rho_stars) else list(rho_stars)
        (f_lo, r_lo), (f_hi, r_hi) = ends or [(self.stable(x), self.collision(x)) for x in (lo, hi)]
        brackets = []
        for k, rho_star in enumerate(rho_stars):
            bracket, local = self._follow_pair(lo, hi, rho_star, f_lo, r_lo, r_hi)
            brackets.append(bracket)
            if not local:              # followed with the full flags: its bracket is the flag's change already
                break
        first = min if f_lo else max   # the change is at the boundary of the stable end's interval
        blo, bhi = first(brackets, key=lambda b: min(b) if f_lo else max(b))
        if self.stable(blo) != self.stable(bhi):
            # a pair that collided and separated again inside the step is complex at neither end: probe the
            # full flag between the stable end and the collision; the first change found is the event
            start, stop = (lo, min(blo, bhi)) if f_lo else (hi, max(blo, bhi))
            for x in start + (stop - start) * np.arange(1, KREIN_PROBES + 1) / (KREIN_PROBES + 1):
                if not self.stable(x):             # (the stable end's flag is True)
                    r_x = self.collision(x)
                    cands = _krein_candidates(r_x) if r_x is not None and depth < 2 else []
                    if not cands:
                        return self.bisect(self.stable, start, x)
                    stable_end, unstable_x = (True, r_lo if f_lo else r_hi), (False, r_x)
                    return (self.krein(start, x, cands, [stable_end, unstable_x], depth + 1) if f_lo else
                            self.krein(x, start, cands, [unstable_x, stable_end], depth + 1))
            return blo, bhi
        # the full flag is the same at both ends: the tracked pair's threshold and the full flag's differ by
        # round-off (look just around the bracket), or no pair followed was what changed the stability
        # (e.g. another pair left through +-1 in the same step): bisection on the full flag
        a, b = min(lo, hi), max(lo, hi)
        for k in (10.0, 1000.0):
            w = k * max(abs(bhi - blo), 1e-12 * max(1.0, abs(bhi)))
            x0, x1 = max(a, min(blo, bhi) - w), min(b, max(blo, bhi) + w)
            if self.stable(x0) != self.stable(x1):
                return self.bisect(self.stable, x0, x1)
        return self.bisect(self.stable, lo, hi)

    def _follow_pair(self, lo, hi, rho_star, f_lo, r_lo, r_hi):
        """Follow the pair around rho_star from lo to hi (secant with a bisection safeguard, Dekker) to its
        collision: ((lo, hi) bracket, True if the problem's local eigen-solver was used; False if the full
        flag had to be, i.e. the bracket is that of the flag's change)."""
        pm = getattr(self.problem, "collision_per_modulus", 1.0)
        g_lo, g_hi = krein_gap(r_lo, rho_star, pm), krein_gap(r_hi, rho_star, pm)
        last = [(lo, g_lo), (hi, g_hi)]       # the two latest evaluations, for the secant step
        widths = [abs(hi - lo)]
        local = True
        for _ in range(60):
            if self._converged(lo, hi):
                break
            (x1, g1), (x2, g2) = last
            c = None
            if g1 is not None and g2 is not None and g1 != g2:
                c = x2 - g2 * (x2 - x1) / (g2 - g1)          # secant (Dekker): fast where g is linear
            if c is None or not min(lo, hi) < c < max(lo, hi) or (len(widths) > 3 and widths[-1] > 0.5 * widths[-4]):
                c = 0.5 * (lo + hi)                          # bisection keeps the bracket shrinking
            r_c = self.local_collision(c, rho_star)
            if r_c is not None:                  # this collision only: its test function is the flag
                g_c = krein_gap(r_c, rho_star, pm)
                f_c = g_c > 0
            else:
                local = False
                f_c = self.stable(c)
                r_c = self.collision(c)
                g_c = krein_gap(r_c, rho_star, pm)
                if g_c is not None and (g_c > 0) != f_c:
                    g_c = None                   # the test function disagrees with the flag: no secant from here
            if g_c is not None and g_c < 0:     # follow the complex pair: it drifts along the branch
                z = np.asarray(r_c)[np.abs(np.imag(r_c)) > 1e-12]
                rho_star = float(z[np.argmin(np.abs(z.real - rho_star))].real)
            if f_c == f_lo:
                lo = c
            else:
                hi = c
            last = [last[1], (c, g_c)]
            widths.append(abs(hi - lo))
        return (lo, hi), local

    def real_crossing(self, sigma):
        """max_i |Re rho_i| - 1, rho = (mu + 1/mu) / 2 over the non-trivial multipliers:
        smooth through a real pair's collision at +1 or -1 (rho = cos(theta) on the circle, cosh or
        -cosh off it), negative while stable; its zero is where the pair leaves the circle."""
        return real_crossing(self.multipliers(sigma))

    def root(self, g, lo, hi, g_lo=None, g_hi=None, max_iter=60, converged=None):
        """sigma in [lo, hi] where g changes sign (Illinois variant of regula falsi).  converged(a, b, fa, fb)
        : when to stop (default: the energies at the bracket's ends agree to EVENT_RTOL)."""
        converged = converged or (lambda a_, b_, fa_, fb_: self._converged(a_, b_))
        a, fa = lo, (g(lo) if g_lo is None else g_lo)
        b, fb = hi, (g(hi) if g_hi is None else g_hi)
        side = 0
        for _ in range(max_iter):
            if fa == 0.0 or fb == 0.0 or converged(a, b, fa, fb):
                break
            c = (a * fb - b * fa) / (fb - fa)
            if not min(a, b) < c < max(a, b):
                c = 0.5 * (a + b)
            fc = g(c)
            if fc * fb > 0:
                b, fb = c, fc
                if side == -1:
                    fa *= 0.5
                side = -1
            elif fc * fa > 0:
                a, fa = c, fc
                if side == 1:
                    fb *= 0.5
                side = 1
            else:
                return c
        return a if abs(fa) <= abs(fb) else b

    def fold_converged(self, a, b, ga, gb):
        """Stop rule of a fold's root on the energy slope g = dE/dsigma: the energy of the better end lies
        below the extremum by about g^2 / (2 |dg/dsigma|) (the parabola through the extremum), within
        EVENT_RTOL / 10 of it.  (Equal energies at the bracket's ends are no test here: two points on either
        side of an extremum have them while far from it.)"""
        if abs(b - a) <= 1e-12 * max(1.0, abs(b)):
            return True
        curvature = abs((gb - ga) / (b - a))
        best = min(abs(ga), abs(gb))
        try:
            E = abs(self.energy(a if abs(ga) <= abs(gb) else b))
        except CorrectorFailure:
            return False
        return curvature > 0 and best * best / (2 * curvature) <= 0.1 * EVENT_RTOL * E

    def around(self, sigma):
        """The known points nearest sigma on each side (sigma keys; None where there is none)."""
        keys = sorted(k for k in self.cache if k != float(sigma))
        left = [k for k in keys if k < sigma]
        right = [k for k in keys if k > sigma]
        return (left[-1] if left else None), (right[0] if right else None)

    def bisect(self, flag, lo, hi, max_iter=60):
        """sigma at the change of a boolean flag between lo and hi (flag(lo) != flag(hi))."""
        f_lo = flag(lo)
        for _ in range(max_iter):
            if self._converged(lo, hi):
                break
            mid = 0.5 * (lo + hi)
            if flag(mid) == f_lo:
                lo = mid
            else:
                hi = mid
        return lo, hi

    def _converged(self, lo, hi):
        if abs(hi - lo) <= 1e-12 * max(1.0, abs(hi)):
            return True
        try:
            E_lo, E_hi = self.energy(lo), self.energy(hi)
        except CorrectorFailure:
            return False
        return abs(E_hi - E_lo) <= EVENT_RTOL * max(abs(E_lo), abs(E_hi))


def event_record(kind, index, point, detail, **extra):
    """An event dict: kind, index (first branch point after it), energy J, frequency_hz Hz, period s,
    x0, v0 (lists, m and m/s), detail, located=True, plus ``extra``."""
    rec = dict(kind=kind, index=int(index), energy=float(point.energy), frequency_hz=float(point.frequency_hz),
               period=float(point.period), x0=np.asarray(point.x0, dtype=float).tolist(),
               v0=np.asarray(point.v0, dtype=float).tolist(), detail=detail, located=True)
    rec.update(extra)
    return rec


def locate_between(loc, s, a, b, index, record, energy_max=None):
    """Events between point a (sigma = 0) and point b (sigma = s) of the continuation.

    a, b : (point, slope) with slope = dE/ds at the point; record(sigma) -> Point at sigma.
    energy_max : if the step crosses it upwards, the branch is cut there: returns the located end
    point as well.  Returns (events, end) with end = (sigma, Point) or None.  An event whose
    location fails (the corrector does not converge inside the step) is kept, bracketed by the two
    points (``located`` False, orbit of the nearer point).
    """
    (pa, slope_a), (pb, slope_b) = a, b
    events, end = [], None
    if energy_max is not None and pa.energy < energy_max <= pb.energy:
        target = energy_max * (1 + 2 * EVENT_RTOL)    # the end point is at or just above energy_max
        try:
            sig = loc.root(lambda x: loc.energy(x) - target, 0.0, s, pa.energy - target, pb.energy - target)
            end = (sig, record(sig))
            s, pb, slope_b = sig, end[1], loc.slope(sig)
        except CorrectorFailure:
            pass
    fold = None
    if slope_a * slope_b < 0:
        detail = "energy maximum" if slope_a > 0 else "energy minimum"
        try:
            sig = loc.root(loc.slope, 0.0, s, slope_a, slope_b, converged=loc.fold_converged)
            fold = (sig, record(sig))
            events.append(event_record("fold", index, fold[1], detail))
        except CorrectorFailure:
            near = pa if abs(slope_a) < abs(slope_b) else pb
            events.append(event_record("fold", index, near, detail, located=False))
    if not (np.isnan(pa.floquet).any() or np.isnan(pb.floquet).any()) and pa.stable != pb.stable:
        pu = pb if pa.stable else pa      # the bracket's unstable end: its critical multiplier has left the circle
        kind = classify_multipliers(pu.floquet) or "branch_point"
        change = "loss" if pa.stable else "gain"
        ga, gb = real_crossing(pa.floquet), real_crossing(pb.floquet)
        located = True
        if fold is not None and kind == "branch_point" and _changes_at(loc, fold[0], s, pa.stable, pb.stable):
            # at an energy fold a pair of multipliers passes through +1 (the real-crossing test function is flat
            # there, so its own root would be poorly placed): the change is the fold's when the flags on the two
            # sides of the located fold are those of the step's two ends
            events[-1]["stability_change"] = change
            return events, end
        try:
            if kind != "torus" and ga * gb < 0:      # a real pair: a smooth test function, regula falsi
                sig = loc.root(loc.real_crossing, 0.0, s, ga, gb)
            else:                                    # a Krein collision
                rho_u = getattr(pu, "_collision", None)
                if rho_u is not None and np.any(np.abs(np.imag(rho_u)) > 1e-9):
                    lo, hi = loc.krein(0.0, s, _krein_candidates(rho_u),
                                       ends=[(p.stable, getattr(p, "_collision", None)) for p in (pa, pb)])
                else:                                # no coordinates (e.g. Hill's method): bisection on the flag
                    lo, hi = loc.bisect(loc.stable, 0.0, s)
                sig = 0.5 * (lo + hi)
            pe = record(sig)
        except CorrectorFailure:
            pe, located = pu, False
        if fold is not None and abs(pe.energy - fold[1].energy) <= 1e-4 * abs(fold[1].energy):
            events[-1]["stability_change"] = change
        else:
            crit = pu.floquet[0]
            through = {"branch_point": "+1", "period_doubling": "-1", "torus": "a complex pair"}[kind]
            events.append(event_record(kind, index, pe, f"{change} of stability, multiplier through {through} "
                                                        f"(next point: {crit:.5g})", stability_change=change,
                                       **({} if located else dict(located=False))))
    return events, end


def _krein_candidates(rho, most=MAX_KREIN_PAIRS):
    """Real parts of the complex collision coordinates rho (one per conjugate pair), the most unstable (largest
    imaginary part) first, at most ``most``."""
    rho = np.asarray(rho, dtype=complex)
    z = rho[rho.imag > 1e-9]
    z = z[np.argsort(-z.imag, kind="stable")]
    out = []
    for x in z.real:
        if all(abs(x - y) > 1e-9 for y in out):
            out.append(float(x))
    return out[:most]


def _changes_at(loc, sigma, s, stable_a, stable_b, reach=FOLD_REACH):
    """Does the stability flag change at sigma (within reach x the step s): do points on its two sides within
    that distance (known ones, e.g. the root finder's last iterates, or new ones at that distance) have the
    flags of the step's ends a (sigma = 0) and b (sigma = s)?"""
    delta = reach * abs(s)
    left, right = loc.around(sigma)
    if left is None or sigma - left > delta:
        left = max(sigma - delta, 0.0)
    if right is None or right - sigma > delta:
        right = min(sigma + delta, s)
    try:
        return loc.stable(left) == stable_a and loc.stable(right) == stable_b
    except CorrectorFailure:
        return False


def stability_changes(events):
    """The events where the stability changes (classified bifurcations, and folds where it changes)."""
    return [e for e in events if e.get("stability_change")]
