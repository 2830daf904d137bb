"""One pair of collision coordinates followed along a step to its Krein collision (krein.py's follower).

The pair's test function is its discriminant (floquet.krein_gap: the squared half-distance of the two coordinates
while real, minus the squared imaginary part once they are a complex pair, offset by the stability threshold), linear
in the branch parameter sigma through a generic collision: a secant on it (Dekker's, a bisection where the bracket
did not halve in three steps), each value from the problem's local eigen-solver near the pair (shift-invert Arnoldi,
Locator.local_collision), the shift moving with the pair as it drifts.  The secant's convergence is checked by one
local evaluation past the predicted root (_beyond_root) or past a converged iterate (_root_within): a secant stalled
where the gap is far from linear is not taken for converged.  A secant that stalled next to a bracket's end (a complex
pair's tiny gap beside a real side's large one) is moved clear of that end the next time (_clear_of_ends), and then
bisects.
"""
from __future__ import annotations

import numpy as np

from .floquet import krein_gap
from .settings import STABILITY

__all__ = ["follow_pair", "pair_shift", "per_modulus"]


def _spacing(rho, rho_star, count=8):
    """The mean distance between the real coordinates of rho nearest rho_star (the local eigenvalue spacing), or
    inf when there are too few."""
    if rho is None:
        return np.inf
    rho = np.asarray(rho, dtype=complex)
    real = rho.real[np.abs(rho.imag) <= 1e-12]
    if len(real) < 3:
        return np.inf
    near = np.sort(real[np.argsort(np.abs(real - rho_star))[:count]])
    return float((near[-1] - near[0]) / (len(near) - 1)) or np.inf


def _shift_for(z, spacing):
    """The local solver's shift for a pair at the complex coordinate z: its real part, or z itself when the pair
    lies so far off the real axis that the real eigenvalues nearer to its real part could fill the local solver's
    window of 6 (STABILITY.local_crowd of them within |Im z|, at the local spacing).  A 1,100-mode plate: 0.0006 between
    eigenvalues and a pair 0.01 off the axis, which the 6 eigenvalues nearest its real part missed.  A complex
    shift costs a complex LU (4x a real one) and more Arnoldi iterations, so near the collision the real part
    is used again."""
    b = abs(complex(z).imag)
    return complex(complex(z).real, b) if 2 * b >= STABILITY.local_crowd * spacing else float(complex(z).real)


def pair_shift(rho, rho_star):
    """The local solver's shift for the pair around rho_star, from the coordinates rho of a point where it is complex
    (_shift_for; rho_star itself if rho has no complex coordinate near it)."""
    if rho is None:
        return rho_star
    rho = np.asarray(rho, dtype=complex)
    z = rho[np.abs(rho.imag) > 1e-12]
    if not len(z):
        return rho_star
    z = z[np.argmin(np.abs(z.real - rho_star))]
    if abs(z.real - rho_star) > 1e-6 + abs(z.imag):
        return rho_star
    return _shift_for(complex(rho_star, z.imag), _spacing(rho, rho_star))


def per_modulus(loc):
    """The collision coordinates' imaginary part per unit modulus excess of the locator's problem (floquet.krein_gap:
    1/2 for the reversible half map's c, 1 for rho of a monodromy)."""
    return getattr(loc.problem, "collision_per_modulus", 1.0)


def _followed(r, rho_star, spacing):
    """(rho_star, shift) of the complex pair in the coordinates r nearest rho_star: the pair followed, as it drifts
    along the branch."""
    z = np.asarray(r)[np.abs(np.imag(r)) > 1e-12]
    z = z[np.argmin(np.abs(z.real - rho_star))]
    return float(z.real), _shift_for(z, spacing)


def follow_pair(loc, lo, hi, rho_star, f_lo, r_lo, r_hi):
    """Follow the pair around rho_star from lo to hi (secant with a bisection safeguard) to its collision: ((lo, hi)
    bracket, True if the problem's local eigen-solver was used; False if the full flag had to be, i.e. the bracket is
    that of the flag's change; the margin points where krein._flag_change_near checks the full flag: (centre, delta)
    when the secant converged to its root (within a quarter of the margin in energy: centre -+ delta are
    STABILITY.krein_margin x the energy tolerance apart), (centre, delta, x_s, x_u) when two local evaluations
    bracket it to the margin (the stable and the unstable one: their orbits are known), else None)."""
    pm = per_modulus(loc)
    g_lo, g_hi = krein_gap(r_lo, rho_star, pm), krein_gap(r_hi, rho_star, pm)
    r_u = r_hi if f_lo else r_lo
    shift, spacing = pair_shift(r_u, rho_star), _spacing(r_u, rho_star)    # the pair at the unstable end
    last = [(lo, g_lo), (hi, g_hi)]       # the two latest evaluations, for the secant step
    widths = [abs(hi - lo)]
    local, stalled = True, False
    beside = 0                            # secant iterates that landed next to a bracket's end and did not cross
    for _ in range(60):
        if loc._converged(lo, hi):
            if local:                # both ends' pair (local evaluations or the ends' spectra) bracket its root
                x_s, x_u = (lo, hi) if f_lo else (hi, lo)
                return (lo, hi), local, (0.5 * (lo + hi), 0.5 * abs(hi - lo), x_s, x_u)
            break
        (x1, g1), (x2, g2) = last
        c = None
        if g1 is not None and g2 is not None and g1 != g2:
            c = x2 - g2 * (x2 - x1) / (g2 - g1)          # secant (Dekker): fast where g is linear
        secant = c is not None and min(lo, hi) < c < max(lo, hi) and not stalled and not (
            len(widths) > 3 and widths[-1] > 0.5 * widths[-4])
        stalled, overshot, near = False, False, False
        if not secant:
            c = 0.5 * (lo + hi)                          # bisection keeps the bracket shrinking
        elif local:
            ahead = _beyond_root(loc, x1, x2, g2, c, lo, hi, rho_star, shift, pm)
            if ahead is not None:
                x_b, g_b = ahead
                E_b, E_2 = loc.energy(x_b), loc.energy(x2)
                if (g_b > 0) != (g2 > 0) and abs(E_b - E_2) <= STABILITY.krein_margin * loc.rtol * max(abs(E_b),
                                                                                                      abs(E_2)):
                    x_s, x_u = (x_b, x2) if g_b > 0 else (x2, x_b)   # the root between x2 and x_b: converged
                    return ((x_s, x_u) if f_lo else (x_u, x_s)), local, (0.5 * (x2 + x_b), 0.5 * abs(x_b - x2),
                                                                          x_s, x_u)
                if g_b < 0:
                    rho_star, shift = _followed(loc.local_collision(x_b, shift), rho_star, spacing)
                if (g_b > 0) == f_lo:        # the bracket shrinks by that point
                    lo = x_b
                else:
                    hi = x_b
                last = [(x2, g2), (x_b, g_b)]
                widths.append(abs(hi - lo))
                stalled = (g_b > 0) == (g2 > 0)      # the secant stalled (the root lies farther): a bisection next
                continue
            c, overshot, near = _clear_of_ends(c, lo, hi, beside > 0)
        r_c = loc.local_collision(c, shift)
        if r_c is not None:                  # this collision only: its test function is the flag
            g_c = krein_gap(r_c, rho_star, pm)
            f_c = g_c > 0
        else:
            local = False
            f_c = loc.stable(c)
            r_c = loc.collision(c)
            g_c = krein_gap(r_c, rho_star, pm)
            if g_c is not None and (g_c > 0) != f_c:
                g_c = None                   # the test function disagrees with the flag: no secant from here
        if g_c is not None and g_c < 0:     # follow the complex pair: it drifts along the branch
            rho_star, shift = _followed(r_c, rho_star, spacing)
        if f_c == f_lo:
            lo = c
        else:
            hi = c
        last = [last[1], (c, g_c)]
        widths.append(abs(hi - lo))
        if secant and local and near and g_c is not None and _stalled_beside(c, g_c, x1, g1, x2, g2):
            beside += 1
            stalled = overshot                        # (moved beyond the secant's point: the next step bisects)
        if secant and local and g_c is not None:
            # converged when the secant step moved the energy by less than a quarter of the margin: its root is
            # then within the margin points of _flag_change_near around c, which check the flag there
            E_c, E_2 = loc.energy(c), loc.energy(x2)
            if abs(E_c - E_2) <= 0.25 * STABILITY.krein_margin * loc.rtol * abs(E_c) and E_c != E_2:
                delta = 0.5 * STABILITY.krein_margin * loc.rtol * abs(E_c) * abs(c - x2) / abs(E_c - E_2)
                verdict = _root_within(loc, c, g_c, delta, lo, hi, f_lo, rho_star, shift, pm)
                if verdict is None:
                    return (lo, hi), local, (c, delta)
                x_v, g_v = verdict           # a stalled secant (g far from linear): the bracket shrinks by that point
                if (g_v > 0) == f_lo:
                    lo = x_v
                else:
                    hi = x_v
                last = [(c, g_c), (x_v, g_v)]
                widths.append(abs(hi - lo))
                stalled = True               # the next step bisects
    return (lo, hi), local, None


def _clear_of_ends(c, lo, hi, again):
    """(c', moved, near): whether a secant iterate c lies within STABILITY.krein_end_fraction of the bracket's width
    from one of its ends (near) and, where an earlier one did so and did not cross (again), c moved
    STABILITY.krein_overshoot times as far from that end (at most to the midpoint).  A secant through a complex
    pair's tiny negative gap and a real side's large positive one lands next to the complex point whether the root is
    there or not: the aircraft's NNM 20 near 212.6 J, the pair's imaginary part stationary at 5.8e-6 over the
    bracket's complex end, the root 12 % of the bracket away; two iterates 1e-5 apart before each bisection.  Where
    g is linear the root lies between the end and c' (a bracket 10 times the secant's step); where it is not, the
    bracket shrinks by c' and the next step bisects.  The first such iterate is taken as it is: where the root does
    lie next to the end (a linear g), it is found there."""
    a, b = min(lo, hi), max(lo, hi)
    reach = STABILITY.krein_end_fraction * (b - a)
    if c - a < reach:
        return (min(a + STABILITY.krein_overshoot * (c - a), 0.5 * (a + b)), True, True) if again else (c, False, True)
    if b - c < reach:
        return (max(b - STABILITY.krein_overshoot * (b - c), 0.5 * (a + b)), True, True) if again else (c, False, True)
    return c, False, False


def _stalled_beside(c, g_c, x1, g1, x2, g2):
    """Did a secant iterate c next to a bracket's end stall: its gap g_c of the same sign as that of the nearer of
    the two points it came from and at least half its size (a secant on a linear g leaves a gap much smaller)?"""
    g_near = g1 if abs(c - x1) < abs(c - x2) else g2
    return g_near is not None and (g_c > 0) == (g_near > 0) and abs(g_c) >= 0.5 * abs(g_near)


def _beyond_root(loc, x1, x2, g2, c, lo, hi, rho_star, shift, pm):
    """The secant's predicted convergence: where the step from the latest iterate x2 to the next one c moves the
    energy (interpolated linearly from x1 and x2: no orbit at c) by at most a quarter of the margin, the pair's local
    test function at the point half a margin beyond c (delta: half the margin, in sigma) -- with the other sign than
    at x2, the root lies between x2 and that point, at most 3/4 of the margin apart: the secant has converged
    without an evaluation at c itself or a separate check (_root_within), when the two points' energies are indeed
    within the margin (the caller checks).  (x, gap) of that point, or None where the step is not that small, the point
    lies outside the bracket (lo, hi) or the local solver gives nothing there.  The same sign as at x2 means a stalled
    secant (the root lies farther): the caller shrinks the bracket by it and bisects."""
    if x1 == x2:
        return None
    E_1, E_2 = loc.energy(x1), loc.energy(x2)
    E_c = E_2 + (c - x2) * (E_2 - E_1) / (x2 - x1)
    if E_c == E_2 or abs(E_c - E_2) > 0.25 * STABILITY.krein_margin * loc.rtol * abs(E_c):
        return None
    delta = 0.5 * STABILITY.krein_margin * loc.rtol * abs(E_c) * abs(c - x2) / abs(E_c - E_2)
    x = c + np.sign(c - x2) * delta
    if not min(lo, hi) < x < max(lo, hi):
        return None
    r = loc.local_collision(x, shift)
    g = krein_gap(r, rho_star, pm) if r is not None else None
    return None if g is None else (x, g)


def _root_within(loc, c, g_c, delta, lo, hi, f_lo, rho_star, shift, pm):
    """Check a secant's convergence at c: the local test function at the margin point c -+ delta towards the
    root (the side where the bracket's other end lies) must have the other sign.  A secant step is small also
    where it stalls: g far from linear, e.g. a complex pair's tiny negative gap beside a real side's large one (the
    aircraft's NNM 20 at 122.6 J: -8e-11 against 2.5e-5, the step 1e-8 of the bracket while the root lay 4e-2
    of the step away).  None when the root lies within delta of c, else (x, g) at that point; one local
    evaluation."""
    towards = hi if (g_c > 0) == f_lo else lo         # (lo's side has g > 0 where f_lo)
    x = c + np.sign(towards - c) * delta
    if not min(lo, hi) <= x <= max(lo, hi):
        return None
    r = loc.local_collision(x, shift)
    g = krein_gap(r, rho_star, pm) if r is not None else None
    if g is None or (g > 0) != (g_c > 0):
        return None
    return x, g
