"""Krein collisions located inside a continuation step.

Two Floquet multipliers of opposite Krein signature meet on the unit circle and leave it as a complex
quadruple.  In the coordinates where they are real before the collision (the eigenvalues c of the reversible
half map's A11 block, or rho = (mu + 1/mu) / 2 of a full-period monodromy) the test function is the
discriminant of the colliding pair (floquet.krein_gap), linear in the branch parameter through a generic
collision: a secant on it, with the pair followed by the problem's local eigen-solver where it has one
(shift-invert Arnoldi, ShootingProblem.local_collision).  Several pairs can collide within one step; the
stability changes at the collision nearest the stable end, and a collision undone inside the step (complex at
neither end) is caught by probing the full flag at STABILITY.krein_probes points, when its window covers one of them.  A
pair that drifted out of the local solver's window between the step's end and the followed collision (not followed) is
found in the full spectrum of the margin point next to that collision, and followed from there.  The follower is
krein_follow.py's.
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import CorrectorFailure
from .floquet import krein_gap
from .krein_follow import follow_pair, pair_shift, per_modulus
from .settings import STABILITY

__all__ = ["locate_collision", "candidates", "probe_points"]


#: an alias of settings.py's STABILITY.krein_depth (the code reads that)
KREIN_DEPTH = STABILITY.krein_depth

#: an alias of settings.py's STABILITY.local_crowd (the code reads that)
LOCAL_CROWD = STABILITY.local_crowd


def candidates(rho, most=STABILITY.max_krein_pairs):
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


def locate_collision(loc, lo, hi, rho_stars, ends=None, depth=0):
    """sigma at a Krein collision between lo and hi (stable at one end, complex pairs at the other).

    Each candidate pair (rho_stars: the real parts of the complex collision coordinates at the unstable
    end, most unstable first) is followed by a secant on its smooth test function krein_gap (the squared
    half-distance of the two colliding coordinates, negative once they are a complex pair), evaluated by
    the problem's local eigen-solver (``local_collision``) where it has one.  Several pairs can collide
    within one step: the stability changes at the collision nearest the stable end, so a further candidate is
    followed only if it is complex already on the stable side of the nearest collision found so far (one local
    evaluation decides).  The full stability flag's change is then bracketed around that collision
    (_flag_change_near: two full spectra in most cases); where the margin point on the stable side is unstable
    already, the pairs complex there are followed on the shorter interval (_earlier_change); bisection on the full
    flag only when neither brackets the change.
    ends : optional ((stable, coordinates) at lo, at hi), known from the two points, to save their
    evaluation.  Returns (lo, hi) like bisect."""
    rho_stars = [rho_stars] if np.isscalar(rho_stars) else list(rho_stars)
    (f_lo, r_lo), (f_hi, r_hi) = ends or [(loc.stable(x), loc.collision(x)) for x in (lo, hi)]
    best = None                    # (bracket, root) of the collision nearest the stable end so far
    for rho_star in rho_stars:
        if best is None:
            far, r_far = hi if f_lo else lo, r_hi if f_lo else r_lo
        else:                      # does this pair collide before the best one?  It is complex there already if so
            far = best[1][0] if best[1] else (min(best[0]) if f_lo else max(best[0]))
            r_far = loc.local_collision(far, pair_shift(r_hi if f_lo else r_lo, rho_star))
            if r_far is None or not krein_gap(r_far, rho_star, per_modulus(loc)) < 0:
                continue
        a, b = (lo, far) if f_lo else (far, hi)
        ra, rb = (r_lo, r_far) if f_lo else (r_far, r_hi)
        bracket, local, root = follow_pair(loc, a, b, rho_star, f_lo, ra, rb)
        best = (bracket, root)
        if not local:              # followed with the full flags: its bracket is the flag's change already
            break
    (blo, bhi), root = best
    bracket = _flag_change_near(loc, lo, hi, blo, bhi, f_lo, root, windows=False)
    if bracket is None:        # the flag changed nearer the stable end: the pairs complex there are followed
        x_s = _margin_points(loc, lo, hi, blo, bhi, f_lo, root)[0]
        earlier = _earlier_change(loc, lo, hi, f_lo, r_lo if f_lo else r_hi, x_s, depth)
        if earlier is not None:
            return earlier
        bracket = _flag_change_near(loc, lo, hi, blo, bhi, f_lo, root)
    if bracket is None:        # no pair followed changed the stability (e.g. a pair left through +-1 too)
        return loc.bisect(loc.stable, lo, hi)
    # a pair that collided and separated again inside the step is complex at neither end: probe the full flag
    # between the stable end and the collision; the first change found is the event
    start, stop = (lo, min(bracket)) if f_lo else (hi, max(bracket))
    probes = probe_points(start, stop, loc.spectra)
    loc.prefetch(probes)
    for x in probes:
        if not loc.stable(x):             # (the stable end's flag is True)
            r_x = loc.collision(x)
            cands = candidates(r_x) if r_x is not None and depth < STABILITY.krein_depth else []
            if not cands:
                return loc.bisect(loc.stable, start, x)
            stable_end, unstable_x = (True, r_lo if f_lo else r_hi), (False, r_x)
            return (locate_collision(loc, start, x, cands, [stable_end, unstable_x], depth + 1) if f_lo else
                    locate_collision(loc, x, start, cands, [unstable_x, stable_end], depth + 1))
    return bracket


def probe_points(start, stop, known=()):
    """The points strictly between start (the stable end) and stop (a located collision) where the full flag is
    checked for a collision undone inside the step, ordered from start: those with a known spectrum (``known``: sigmas,
    e.g. a nested location's parent's probes and margin points) and new ones, so that no two consecutive checked points
    (start and stop included) lie farther apart than STABILITY.krein_probes evenly spaced probes would (the interval
    over krein_probes + 1), where that needs fewer new points than krein_probes; else (e.g. without known points
    inside) the krein_probes evenly spaced points.  (Known points consulted where they save nothing would only move
    the probes: on the aircraft's NNM 20 skipping tongues, a step near 2.12 J holding four collisions then found a
    pair hovering at the threshold (-0.6796, its imaginary part 3.6-3.7e-6) at 2.1365 J instead of the collision at
    2.1238 J.)"""
    n = STABILITY.krein_probes
    if n <= 0 or stop == start:
        return []
    a, b = min(start, stop), max(start, stop)
    spacing = (b - a) / (n + 1)
    inside = sorted(float(x) for x in known if a < x < b)
    checked, new = [a] + inside + [b], []
    for x0, x1 in zip(checked[:-1], checked[1:]):
        k = int(np.ceil((x1 - x0) / spacing * (1 - 1e-9))) - 1     # points needed to cut this gap to the spacing
        new += [x0 + (x1 - x0) * j / (k + 1) for j in range(1, k + 1)]
    if len(new) >= n:                   # nothing saved: the evenly spaced probes (the known points not consulted)
        inside, new = [], [a + (b - a) * j / (n + 1) for j in range(1, n + 1)]
    points = sorted(inside + new)
    return points if start < stop else points[::-1]


#: an alias of settings.py's STABILITY.krein_margin (the code reads that)
MARGIN = STABILITY.krein_margin

#: an alias of settings.py's STABILITY.flag_band (the code reads that)
FLAG_BAND = STABILITY.flag_band


def _earlier_change(loc, lo, hi, f_lo, r_stable, x_s, depth):
    """The flag's change between the step's stable end and the stable-side margin point x_s of a followed
    collision, where x_s is unstable beyond the round-off band (STABILITY.flag_band): another pair (or the followed one,
    where its secant stopped short of its root) changed the flag nearer the stable end.  The pairs complex at
    x_s, whose full spectrum is known, are followed on the shorter interval (locate_collision: local evaluations
    and a few full spectra, instead of a bisection of the full flag over the step).  r_stable : the collision
    coordinates at the stable end.  None when x_s is stable, has no complex coordinates or the nesting is
    STABILITY.krein_depth deep (the caller bisects the full flag)."""
    start = lo if f_lo else hi
    if (depth >= STABILITY.krein_depth or x_s == start
            or loc.stable(x_s, STABILITY.stability_tol * (1 + STABILITY.flag_band))):
        return None
    r_s = loc.collision(x_s)
    cands = candidates(r_s) if r_s is not None else []
    if not cands:
        return None
    stable_end, unstable_x = (True, r_stable), (False, r_s)
    return (locate_collision(loc, start, x_s, cands, [stable_end, unstable_x], depth + 1) if f_lo else
            locate_collision(loc, x_s, start, cands, [unstable_x, stable_end], depth + 1))


def _margin_points(loc, lo, hi, blo, bhi, f_lo, root=None):
    """The two margin points around a followed collision (blo, bhi) where the full flag is checked: (x_s, x_u, c,
    width), x_s on the stable side, x_u on the unstable one, STABILITY.krein_margin x the energy tolerance apart around
    the centre c (the secant's root when given: (centre, delta), or (centre, delta, x_s, x_u) with the two points
    themselves, krein_follow.follow_pair's); width: the bracket's (or 2 delta)."""
    a, b = min(lo, hi), max(lo, hi)
    width = abs(bhi - blo)
    if root is not None and len(root) == 4:
        return root[2], root[3], root[0], 2 * root[1]
    if root is not None:
        c, delta = root
        width = 2 * delta
    else:
        try:
            E_lo, E_hi = loc.energy(blo), loc.energy(bhi)
        except CorrectorFailure:
            E_lo = E_hi = None
        c, delta = 0.5 * (blo + bhi), 0.5 * width
        if E_lo is not None and width > 0 and E_hi != E_lo:
            delta = max(delta, 0.5 * STABILITY.krein_margin * loc.rtol * max(abs(E_lo), abs(E_hi)) * width
                        / abs(E_hi - E_lo))
    delta = min(delta, 1e-2 * (b - a))
    sign = 1.0 if hi > lo else -1.0             # from lo's side (flag f_lo) towards hi's
    x_lo, x_hi = min(max(c - sign * delta, a), b), min(max(c + sign * delta, a), b)
    x_s, x_u = (x_lo, x_hi) if f_lo else (x_hi, x_lo)
    return x_s, x_u, c, width


def _flag_change_near(loc, lo, hi, blo, bhi, f_lo, root=None, windows=True):
    """A bracket of the full stability flag's change next to a followed collision (blo, bhi), to the locator's
    energy tolerance; None if the flag does not change there.

    The tracked pair's threshold (its imaginary part at the stability tolerance) and the full flag's differ by
    round-off: there the imaginary part grows like the square root of the distance from the collision, so the
    two eigen-solvers' values, ~1e-4 apart relative, place the crossing up to ~1e-6 of the step apart.  The full
    spectra are computed at two margin points around the collision, STABILITY.krein_margin x the energy tolerance apart
    (_margin_points): they bracket the change when the stable side's largest modulus excess |mu| - 1 is within
    (1 + STABILITY.flag_band) x the tolerance and the unstable side's beyond (1 - STABILITY.flag_band) x it (two
    spectra).  Otherwise (another pair changed the flag nearby), with ``windows``, a bisection on the flag within 10 or
    1000 times the bracket's width around it.  f_lo : the flag at lo; root : optional (centre, delta) of the margin
    points (else around the bracket), or (centre, delta, x_s, x_u) where the follower's last two local evaluations
    bracket its pair's root (their orbits are known)."""
    a, b = min(lo, hi), max(lo, hi)
    x_s, x_u, c, width = _margin_points(loc, lo, hi, blo, bhi, f_lo, root)
    loc.prefetch([x_s, x_u])
    tol = STABILITY.stability_tol
    if loc.stable(x_s, tol * (1 + STABILITY.flag_band)) and not loc.stable(x_u, tol * (1 - STABILITY.flag_band)):
        return (x_s, x_u) if x_s < x_u else (x_u, x_s)
    if not windows:
        return None
    for k in (10.0, 1000.0):
        w = k * max(width, 1e-12 * max(1.0, abs(bhi)))
        x0, x1 = max(a, min(c, blo, bhi) - w), min(b, max(c, blo, bhi) + w)
        if loc.stable(x0) != loc.stable(x1):
            return loc.bisect(loc.stable, x0, x1)
    return None


