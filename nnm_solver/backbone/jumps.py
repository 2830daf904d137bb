r"""A jump over a tongue: the backbone family's orbits beyond it, found by the branch's own method.

Where the continuation has left the family at energy E_0 (J), the family beyond is where the skeleton (skeleton.py)
has its points above E_0: its orbits there (condensed harmonic balance) are first guesses that the branch's method
(shooting or harmonic balance, any truncation) corrects on the energy level set E = E_t (the continuation
engine's corrector, with its corrections on the hyperplane tangent to the level set, so that the energy stays E_t).
``candidates`` gives the energies to try, nearest first; ``land`` the corrected orbit.  Whether it is on
the family is the labels' verdict (labels.py), asked by the policy (policy.py); the iterator restarts the
continuation there along the tangent that goes up in energy (``upward_tangent``).
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import CorrectorFailure, _energy_slope, correct, tangent

__all__ = ["candidates", "land", "find_landing", "level_set", "upward_tangent"]


def candidates(skeleton, E_0, jumps):
    """Energies (J) to jump to from a departure at E_0, nearest first: E_0 (1 + delta) for delta in ``jumps``
    (relative) where the skeleton covers them, and in each interval between them the skeleton's first and last own
    points (its orbits there need no interpolation: the better guesses next to the gaps it leaves at tongues), after
    its sheet starts within that range (where its stepping moved onto the backbone's sheet beyond a tongue it had
    slid onto)."""
    if skeleton is None or len(skeleton.energy) < 2:
        return []
    grid = [E_0 * (1 + d) for d in jumps if skeleton.covers(E_0 * (1 + d))]
    if not grid:
        return []
    nodes = np.asarray(skeleton.energy, dtype=float)
    starts = [float(e) for e in skeleton.sheet_starts if E_0 * (1 + 1e-9) < e <= grid[-1]]
    out = list(grid)
    for lo, hi in zip([E_0] + grid[:-1], grid):
        inside = nodes[(nodes > lo * (1 + 1e-9)) & (nodes < hi * (1 - 1e-9))]
        out += [float(inside[0]), float(inside[-1])] if len(inside) else []
    out = sorted({round(e, 12) for e in out if all(abs(e / x - 1) > 1e-6 for x in starts)})
    return starts + out


def level_set(prob, guess, settings, tol, w=None):
    """(u, J): the orbit of ``prob`` nearest ``guess`` on its energy level set (corrected on the hyperplane
    tangent to it), or (None, None) when the corrector fails."""
    w = prob.scale(guess) if w is None else w
    row = prob.energy_gradient(guess) / (w * w)          # correct() constrains (w^2 row)^T (u - guess) = 0
    try:
        u, J, _, _ = correct(prob, guess, row / np.linalg.norm(w * row), settings, tol, w)
    except (CorrectorFailure, np.linalg.LinAlgError):      # no convergence, or a singular Jacobian on the way
        return None, None
    return u, J


def land(prob, system, skeleton, E_t, settings, tol):
    """(u, J, (E, f)): the branch problem ``prob``'s orbit on the energy level set E_t (J), from the skeleton's orbit
    there, and that skeleton orbit's energy (J) and frequency (Hz); (None, None, None) where the skeleton has none or the corrector
    fails.  system : the branch's ModalSystem."""
    refined = skeleton.family_orbit(system, E_t, settings, tol)
    if refined is None:
        return None, None, None
    fam, u = refined
    family = (float(fam.energy(u)), 1.0 / fam.state(u)[2])
    if not skeleton.is_family(*family):        # the skeleton's own correction slid onto a tongue's sheet
        return None, None, None
    if hasattr(prob, "from_family") and getattr(prob, "sys", None) is fam.sys:
        guess = prob.from_family(fam, u)       # harmonic balance: the family's harmonics as they are
    elif hasattr(prob, "from_state"):
        q0, v0, T = fam.state(u)
        if fam.sys is not system:              # the skeleton's basis is not the branch's (a Ritz basis)
            q0, v0 = (system.to_modal(fam.sys.to_physical(x)) for x in (q0, v0))
        guess = prob.from_state(q0, v0, T)
    else:
        return None, None, None
    return (*level_set(prob, guess, settings, tol), family)


def find_landing(prob, system, policy, labels, jump, run, settings, tol):
    """((u, J, E J, f Hz) or None, energies tried): the first of the Jump's targets whose orbit, corrected by the
    branch problem ``prob`` (``land``), the policy accepts as on the family (the labels' verdict, the same as the
    points', at the problem's time step, with the lock test from ``run``, the kept points before the jump)."""
    from .content import content_of
    tried = []
    for E_t in jump.targets:
        tried.append(E_t)
        u, J, _ = land(prob, system, policy.skeleton, E_t, settings, tol)
        if u is None:
            continue
        E, f = float(prob.energy(u)), float(1.0 / prob.state(u)[2])
        verdict = labels.verdict(E, f, content_of(prob.modal_orbit(u), policy.mode - 1), run=run,
                                 steps=int(getattr(prob, "spp", 0)))
        if policy.landed(verdict, E, jump.base):
            return (u, J, E, f), tried
    return None, tried


def upward_tangent(prob, u, J, previous):
    """The branch's tangent at the orbit u (Jacobian J), oriented so that the energy increases.  After a jump the
    old backbone tangent ``previous`` (only used to pick the null direction of J) may point either way at the
    landing orbit, and a restart that goes down in energy re-enters the tongue just jumped: the backbone continued
    in energy has no fold, so beyond a tongue it goes on upwards."""
    w = prob.scale(u) if hasattr(prob, "scale") else np.ones(len(u))
    p = tangent(J, previous, w)
    return -p if _energy_slope(prob.energy, u, p) < 0 else p
