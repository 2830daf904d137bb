r"""Scalar root finders along the pseudo-arclength sigma of a step (the ``Locator``'s, locator.py): where a test
function g(sigma) changes sign (Illinois regula falsi safeguarded by bisection), where a boolean flag changes, and
their stop rules on the energy (the events' relative energy tolerance ``rtol``).  A class using them provides
``energy(sigma)`` (J) and ``rtol``."""
from __future__ import annotations

from ..continuation.engine import CorrectorFailure
from .settings import STABILITY

__all__ = ["BracketRoots", "RETAIN_LIMIT", "LINEAR_BAND"]

#: an alias of settings.py's STABILITY.retain_limit (the code reads that)
RETAIN_LIMIT = STABILITY.retain_limit
#: an alias of settings.py's STABILITY.linear_band (the code reads that)
LINEAR_BAND = STABILITY.linear_band


class BracketRoots:
    """The root finders (module docstring); mixed into locator.Locator."""

    def root(self, g, lo, hi, g_lo=None, g_hi=None, max_iter=60, converged=None):
        """sigma in [lo, hi] where g changes sign: the Illinois variant of regula falsi, safeguarded by bisection.
        converged(a, b, fa, fb) : when to stop (default: the energies at the bracket's ends agree to the locator's
        rtol).

        Regula falsi keeps one end while the other creeps towards the root; Illinois halves the kept end's value
        so that the next iterate lands on its other side.  Where STABILITY.retain_limit halvings running do not do it, g
        is far from linear across the bracket -- typically a jump (a selected multiplier changing identity:
        Hill's truncated spectrum near a fold, where g goes from -1e-3 to +1e-10 in one step of sigma), where
        Illinois needs ~log2 of the ends' ratio in halvings per move.  The iterates are then midpoints until one
        lies within STABILITY.linear_band x |g(b) - g(a)| of the chord through the ends' true values (g looks linear
        again: Illinois resumes).  A jump is located at bisection's cost; a smooth g keeps Illinois' order.
        Measured on NLvib's beam (example 09, HB H = 5) at its loss of stability next to the 5:1 tongue's fold:
        60 evaluations without convergence before (the event reported 0.0449549 J, unconverged), 26 after
        (0.04495513 J, converged); on synthetic jumps to a 1e-9 bracket 36 evaluations instead of 100-200,
        on smooth convex g 12-18 (Illinois alone 12-18; tests/test_locator_root.py)."""
        converged = converged or (lambda a_, b_, fa_, fb_: self._converged(a_, b_))
        a, fa = lo, (g(lo) if g_lo is None else g_lo)
        b, fb = hi, (g(hi) if g_hi is None else g_hi)
        ta, tb = fa, fb                         # the ends' true values (fa, fb: Illinois' halved ones)
        side, kept, bisecting = 0, 0, False
        for _ in range(max_iter):
            if fa == 0.0 or fb == 0.0 or converged(a, b, ta, tb):
                break
            bisecting = bisecting or kept >= STABILITY.retain_limit
            c = (a * fb - b * fa) / (fb - fa)
            if bisecting or not min(a, b) < c < max(a, b):
                c = 0.5 * (a + b)
            fc = g(c)
            linear = bisecting and (abs(fc - (ta + (c - a) / (b - a) * (tb - ta)))
                                    <= STABILITY.linear_band * abs(tb - ta))
            if fc * fb > 0:
                b, fb, tb = c, fc, fc
                if side == -1:
                    fa *= 0.5
                    kept += 1
                else:
                    kept = 0
                side = -1
            elif fc * fa > 0:
                a, fa, ta = c, fc, fc
                if side == 1:
                    fb *= 0.5
                    kept += 1
                else:
                    kept = 0
                side = 1
            else:
                return c
            if linear:                          # g looks linear across the bracket again: Illinois afresh
                bisecting, kept, side, fa, fb = False, 0, 0, ta, tb
        return a if abs(ta) <= abs(tb) else b

    def fold_converged(self, a, b, ga, gb):
        """Stop rule of a fold's root on the energy slope g = dE/dsigma: the energy of the better end lies
        below the extremum by about g^2 / (2 |dg/dsigma|) (the parabola through the extremum), within
        rtol / 10 of it.  (Equal energies at the bracket's ends are no test here: two points on either
        side of an extremum have them while far from it.)"""
        if abs(b - a) <= 1e-12 * max(1.0, abs(b)):
            return True
        curvature = abs((gb - ga) / (b - a))
        best = min(abs(ga), abs(gb))
        try:
            E = abs(self.energy(a if abs(ga) <= abs(gb) else b))
        except CorrectorFailure:
            return False
        return curvature > 0 and best * best / (2 * curvature) <= 0.1 * self.rtol * E

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
        return abs(E_hi - E_lo) <= self.rtol * max(abs(E_lo), abs(E_hi))
