r"""The backbone family stepped in the followed mode's modal amplitude (the skeleton's points, skeleton.py).

The family is the set of orbits whose fundamental component in the followed mode r is a cos(w t) (a in
sqrt(kg) m, mass-normalised modal coordinates).  For a rising geometrically (s.step_min..STEP_MAX a step, up to
s.step_max_linear in the linear regime, the step halved where ln f moves more than the trend allows) the condensed
harmonic-balance equations (orbits/condensed_hb.py) are solved at fixed a by Newton's method
(``solve_at_amplitude``) from the secant predictor.
Where the frequency jumps or Newton fails at the smallest step, amplitude jumps (s.jumps, with frequency shifts
s.jump_shifts) are tried and kept when they land on the family's frequency trend with s.share_kept of its
fundamental share (``family_share``); the family ends at the reach, at its energy maximum (s.peak_run steps of falling
energy with s.peak_share kept, or a fold in amplitude where the family, followed past it by arclength with no
partner growing, turns back in energy too: _past_fold; when that cannot tell, the slope test _folds_at_peak after
the jumps fail),
where a partner takes the orbit over (s.share_min) or where no jump lands.  With more than one harmonic the
stepping is guided by the one-harmonic family (family_guide.py): it moves onto the backbone's sheet where it had
slid onto a tongue's, halves the steps that jump away from the guide, and jumps from the guide's orbits first.
``amplitude_family`` returns the raw points and how the family ended; skeleton.Skeleton reads them.
"""
from __future__ import annotations

import itertools
import math

import numpy as np

from ..continuation.engine import ContinuationSettings, pseudo_arclength, scale_of
from ..continuation.natural import LogStepper, LogSteps
from .amplitude_orbit import solve_at_amplitude, family_share, fundamental_shares
from .family_guide import OneHarmonicGuide, nearer_sheet, sheet_start, guided_jump
from .settings import SkeletonSettings

__all__ = ["amplitude_family", "solve_at_amplitude", "family_share", "fundamental_shares"]










def _partner(prob, u):
    """(k, 1-based mode) of the strongest higher-harmonic (k >= 2) amplitude of another mode in the orbit u
    (velocity-weighted)."""
    A = np.abs(prob.amplitudes(u)[0]) * prob.basis.h[:, None]
    A[prob.basis.h == 1] = 0.0
    A[:, prob.r] = 0.0
    if not np.max(A, initial=0.0) > 0:
        return 1, 0                                  # no other mode carries a higher harmonic: no partner
    j, m = np.unravel_index(int(np.argmax(A)), A.shape)
    return int(prob.basis.h[j]), int(m) + 1


def _folds_at_peak(prob, pts, s):
    """Is the end of the stepping (no solution at a larger amplitude, no jump past it) a fold of the family
    itself, with its energy maximum there?  True when the followed mode keeps s.peak_share of the orbit (no
    partner mode takes it over) and d ln E / d ln a stays between 0 and s.fold_slope over the last step: the
    amplitude a reaches its maximum along the family while E grows at a finite rate with a, so E reaches its
    maximum at the same fold (dE/ds = dE/da da/ds = 0).  An energy growing ever faster as a stalls is
    another mode taking the energy (a resonance), not a fold of the family."""
    if len(pts) < 3 or family_share(prob, pts[-1][3]) < s.peak_share:
        return False
    (a1, E1, _, _), (a0, E0, _, _) = pts[-2], pts[-1]
    slope = math.log(E0 / E1) / math.log(a0 / a1) if a0 > a1 and E0 > 0 and E1 > 0 else math.inf
    return 0.0 < slope < s.fold_slope


def _null_direction(J, along):
    """The unit tangent of the solution curve (null vector of the n x (n + 1) Jacobian J), oriented along ``along``."""
    t = np.linalg.svd(J)[2][-1]
    return t if t @ along >= 0 else -t


def _past_fold(prob, pts, s, tol=1e-10):
    """Where the stepping in a found no solution at a larger amplitude: read what the family does past that
    fold in a by following it with the continuation engine (continuation/engine.pseudo_arclength, in the
    problem's balanced norm) in (orbit, a) from the last point, steps at most the last step's length, first
    tangent the Jacobian's null vector, with no partner harmonic growing (family_share above s.peak_share, else
    None: a k:1 resonance, the caller's jumps).  The verdict is

    * ``("peak", points)``: the energy falls s.fold_probe_drop below the largest on the way while the followed
      mode keeps s.fund_share of the fundamental: the family's energy maximum (points: from the last one up to it);
    * ``("locked", (1, mode))``: the energy comes back above that maximum, or another mode takes more than
      1 - s.fund_share of the fundamental first (its energy folds and recovers as that mode's motion grows): a 1:1
      internal resonance with that mode (1-based), which ends the followed mode's family;
    * None when the path cannot tell within s.fold_probe_steps steps or the engine stops (its step below
      1e-3 of the first)."""
    nD = prob.nb * prob.ns
    (_, _, _, u1), (_, E0, _, u0) = pts[-2], pts[-1]
    h0 = float(np.linalg.norm(scale_of(prob, u0) * (u0 - u1)))
    if not h0 > 0:
        return None
    share0 = fundamental_shares(prob, u0)
    settings = ContinuationSettings(step=h0, step_min=1e-3 * h0, step_max=h0, max_iter=s.fold_probe_iterations)
    path, E_top, fell = [], E0, False
    try:
        steps = pseudo_arclength(prob, u0, _null_direction(prob.jacobian(u0)[1], u0 - u1), settings, tol)
        next(steps, None)                                     # u0 itself
        for point in itertools.islice(steps, s.fold_probe_steps):
            v = point.u
            if not v[-1] > 0 or family_share(prob, v) < s.peak_share:
                return None                      # a partner harmonic grows: a k:1 resonance, not this fold
            E = prob.energy(v)
            path.append((v[nD] / prob.beta, E, v[-1] * prob.w_r / (2 * math.pi), v))
            shares = fundamental_shares(prob, v)
            if (fell and E > E_top * (1 + s.fold_energy_rtol)) or shares[prob.r] < s.fund_share:
                grown = shares - share0
                grown[prob.r] = -np.inf
                return "locked", (1, int(np.argmax(grown)) + 1)
            if E > E_top and not fell:
                E_top = E
            elif E < E_top:
                fell = True
                if E < E_top * (1 - s.fold_probe_drop):
                    top = int(np.argmax([p[1] for p in path]))
                    return "peak", (path[:top + 1] if path[top][1] > E0 else [])
    except np.linalg.LinAlgError:
        return None
    return None


def _jump(prob, pts, slope, s):
    """Past a resonance the family does not pass smoothly: from the last point, the amplitudes a (1 + delta),
    delta in s.jumps, the orbit scaled and its frequency moved along the trend ``slope`` = d ln f / d ln a
    (or by s.jump_shifts); accepted when Newton converges onto an orbit whose frequency keeps the trend (within
    3 times the move expected + s.jump_limit) and whose fundamental share is at least s.share_kept of the last
    point's.  (a, E, f, u) or None."""
    a0, E0, f0, u0 = pts[-1]
    nD = prob.nb * prob.ns
    share0 = family_share(prob, u0)
    for delta in s.jumps:
        expected = slope * math.log(1 + delta)
        for shift in (expected,) + s.jump_shifts:
            guess = u0.copy()
            guess[:nD] *= 1 + delta
            guess[-1] *= math.exp(shift)
            guess[nD] = a0 * (1 + delta) * prob.beta
            v = solve_at_amplitude(prob, guess, iterations=60)
            if v is None:
                continue
            f = v[-1] * prob.w_r / (2 * math.pi)
            E = prob.energy(v)
            if (abs(math.log(f / f0) - expected) <= 3 * abs(expected) + s.jump_limit
                    and family_share(prob, v) >= s.share_kept * share0 and E <= E0 * (1 + delta) ** s.jump_energy_power):
                return a0 * (1 + delta), E, f, v
    return None


def amplitude_family(prob, E_reach, a_start, s=SkeletonSettings()):
    """Step the condensed problem ``prob`` in its modal amplitude from a_start (sqrt(kg) m, linear regime)
    until the energy exceeds E_reach (J) or the family ends (module docstring).  Returns (a, E, f (Hz), u,
    end, message, gaps, partner) with the raw points (blips inside tongues included) as lists; gaps: the
    (E_before J, E_after J, a_after, kind) of the resonances jumped (kind "jump") and of the moves onto the
    backbone's sheet (kind "sheet", family_guide.py); partner: (k, 1-based mode) of the k:1
    resonance that ended the family ((1, 0) when none did)."""
    u = solve_at_amplitude(prob, prob.start(a_start)[0])
    if u is None:
        return [], [], [], [], "stuck", "no harmonic-balance solution at the linear mode", [], (1, 0)
    pts = [(a_start, prob.energy(u), u[-1] * prob.w_r / (2 * math.pi), u)]
    dlnf_prev, falls = 0.0, 0
    end, message, gaps = "reach", "", []
    partner = (1, 0)                   # (k, 1-based mode) of the resonance that ends the family
    nD = prob.nb * prob.ns
    shares = {}                        # id of a point's orbit -> (the orbit, its family_share): the orbit is kept
                                       # with it (points are dropped at a sheet switch: a freed id is reused)
    guide = OneHarmonicGuide(prob, s) if prob.basis.harmonics > 1 else None
    dev_checked, ddev_prev, switches = 0.0, 0.0, 0

    def at_amplitude(a, guess):
        guess[nD] = a * prob.beta
        return solve_at_amplitude(prob, guess)

    # the stepping in ln a (continuation/natural.py): secant predictor, Newton at the fixed amplitude, step control
    stepper = LogStepper(at_amplitude, LogSteps(s.step_max, s.step_min, s.step_max, s.step_growth, clamp=False))

    def share_of(u):
        if id(u) not in shares or shares[id(u)][0] is not u:
            shares[id(u)] = (u, family_share(prob, u))
        return shares[id(u)][1]

    def to_sheet(a, found):
        """Go on from the backbone's sheet found at amplitude a (found: (orbit, share)), from where it begins
        (family_guide.sheet_start): the stepping's points above that amplitude are left out."""
        nonlocal falls, ddev_prev, dlnf_prev, dev_checked, switches
        a, v, share = sheet_start(prob, guide, pts, a, found)
        del pts[next((i for i, p in enumerate(pts) if p[0] >= a), len(pts)):]
        gaps[:] = [g for g in gaps if g[2] < a]
        shares[id(v)] = (v, share)
        E = prob.energy(v)
        gaps.append((pts[-1][1], E, a, "sheet"))
        pts.append((a, E, v[-1] * prob.w_r / (2 * math.pi), v))
        falls, ddev_prev, dlnf_prev, switches = 0, 0.0, 0.0, switches + 1
        stepper.restart(s.sheet_ratio)
        dev_checked = guide.deviation(a, v) or 0.0

    def resonance(v, what, off_trend=False):
        """The family met a resonance at the last point: jump it (True) or end the family (False).  off_trend: the
        step found v but only left the one-harmonic family's trend (the partner is then read from the last point)."""
        nonlocal end, message, falls, partner, ddev_prev
        a0, E0, f0, u0 = pts[-1]
        if guide is not None and switches < s.max_switches:
            landed = guided_jump(prob, guide, pts, share_of(u0), s.jumps)
            if landed is not None:             # the backbone's sheet beyond: where it begins, from there on
                to_sheet(*landed)
                return True
        # no solution at a larger amplitude, or one a partner took over (the step may have passed the family's own
        # fold in a and landed on a tongue's sheet: the aircraft's mode 19 at 6.2 J, by the reach): past the fold
        past = v is None or share_of(v) < s.share_min
        beyond = _past_fold(prob, pts, s) if past and len(pts) >= 2 else None
        if beyond is not None and beyond[0] == "peak":    # the family's own fold, its energy folding with a
            pts.extend(beyond[1])
            end = "peak"
            a_p, E_p, f_p, _ = pts[-1]
            message = (f"the family folds back at E = {E_p:.4g} J, f = {f_p:.5g} Hz: followed past the largest "
                       f"amplitude it reaches, its energy turns back too and falls, with no partner mode in the "
                       f"orbit: the family's energy maximum")
            return False
        if beyond is not None:                 # its energy folds and recovers as another mode's fundamental grows
            end, partner = "locked", beyond[1]
            message = (f"the family ends at E = {E0:.4g} J, f = {f0:.5g} Hz: past its largest amplitude the "
                       f"energy folds and recovers as mode {partner[1]}'s motion at the same frequency grows (a "
                       f"1:1 internal resonance with mode {partner[1]}), no backbone of the followed mode beyond")
            return False
        base = [p for p in pts if math.log(a0 / p[0]) <= 0.3]     # the trend over the last 30 % in amplitude
        slope = math.log(f0 / base[0][2]) / math.log(a0 / base[0][0]) if base[0] is not pts[-1] else 0.0
        jumped = _jump(prob, pts, slope, s) if sum(g[3] == "jump" for g in gaps) < s.max_jumps else None
        if jumped is not None:
            gaps.append((E0, jumped[1], jumped[0], "jump"))
            pts.append(jumped)
            stepper.ratio, falls, ddev_prev = s.step_max, 0, 0.0
            return True
        if v is None and _folds_at_peak(prob, pts, s):
            end = "peak"
            message = (f"the family folds back at E = {E0:.4g} J, f = {f0:.5g} Hz: no solution at a larger amplitude, "
                       f"with no partner mode in the orbit and its energy still growing with the amplitude there, so "
                       f"the energy turns back with it: the family's energy maximum")
            return False
        # the partner: the strongest in the orbit the stepping found (it jumped there, or a partner took it over),
        # but in the last orbit where no solution was found or the step only left the one-harmonic family's trend
        k, p = partner = _partner(prob, u0 if v is None or off_trend else v)
        end = "stuck" if v is None else "locked"
        message = (f"the family ends at E = {E0:.4g} J, f = {f0:.5g} Hz: {what} (a {k}:1 internal resonance with "
                   f"mode {p}) and no jump of up to {100 * s.jumps[-1]:g} % in amplitude passes it")
        return False

    while len(pts) < 3000:
        a0, _, f0, u0 = pts[-1]
        a, v = stepper.trial([(p[0], p[3]) for p in pts[-2:]])
        dlnf = math.log(v[-1] * prob.w_r / (2 * math.pi) / f0) if v is not None else math.inf
        dev = guide.deviation(a, v) if guide is not None and v is not None else None
        dev = dev if dev is not None and abs(dev) <= s.guide_trust else None          # the guide trusted there only
        dev_last = guide.deviation(a0, u0) if dev is not None else None
        ddev = dev - dev_last if dev_last is not None and abs(dev_last) <= s.guide_trust else 0.0
        if (v is None or abs(dlnf) > s.jump_factor * abs(dlnf_prev) + s.jump_floor
                or abs(ddev) > s.jump_factor * abs(ddev_prev) + s.dev_jump):
            if stepper.shorter():
                continue
            jumps = abs(dlnf) > s.jump_factor * abs(dlnf_prev) + s.jump_floor
            what = ("no solution at a larger amplitude" if v is None else
                    f"its frequency jumps by {100 * dlnf:.2g} %" if jumps else
                    f"its frequency moves by {100 * ddev:.2g} % from the one-harmonic family's in one step")
            if resonance(v, what, off_trend=v is not None and not jumps):
                continue
            break
        if share_of(v) < s.share_min and stepper.shorter():
            continue                   # a partner took the orbit over: a shorter step may stay on the family
        E = prob.energy(v)
        pts.append((a, E, f0 * math.exp(dlnf), v))
        dlnf_prev, ddev_prev = dlnf, ddev
        # the next step: grown by at most s.step_growth, at most s.step_max (s.step_max_linear while the frequency is
        # within s.linear_shift of the first point's), and moving the frequency by about s.dlnf_max at most (the
        # skeleton's interpolation between points stays at ~1e-7, Skeleton.frequency_at)
        cap = s.step_max_linear if abs(v[-1] / pts[0][3][-1] - 1.0) < s.linear_shift else s.step_max
        stepper.accept(s.dlnf_max / max(abs(dlnf), 1e-300), cap)
        share = share_of(v)
        if (dev is not None and switches < s.max_switches
                and abs(dev - dev_checked) > max(s.dev_check, s.dev_check_rel * abs(dev_checked))):
            other = nearer_sheet(guide, a, v)
            if other is not None:      # the backbone's sheet beyond a tongue the stepping slid onto
                to_sheet(a, other)
                continue
            dev_checked = dev
        # the energy falling while no partner grows (the points inside a narrow tongue are not the family's: their
        # energy rises above it and falls back, with the partner's share)
        kept = share >= s.peak_share and share_of(pts[-2][3]) >= s.peak_share
        falls = falls + 1 if E < pts[-2][1] and kept else 0
        if falls >= s.peak_run:
            end, message = "peak", "the family's energy turns back: its maximum"
            break
        # (a partner taking the orbit over is read before the reach: such an orbit's energy is the partner's, e.g.
        # 1e5 x the family's on the aircraft's mode 19 past 6.1 J, where a 9:1 partner, mode 238, holds it)
        if share < s.share_min:
            pts.pop()                  # a partner takes the orbit over: jump from the last point before
            landed = gaps[-1][2] if gaps else 0.0
            if pts[-1][0] > landed and resonance(v, "a partner mode takes the orbit over"):
                continue
            if not message:
                k, p = partner = _partner(prob, v)
                end, message = "locked", (f"the family passes into a {k}:1 internal resonance with mode {p} at E = "
                                          f"{pts[-1][1]:.4g} J, f = {pts[-1][2]:.5g} Hz: that mode takes over "
                                          f"more than {1 - s.share_min:.0%} of the orbit")
            break
        if E > E_reach and falls == 0:
            break
    a, E, f, us = (list(c) for c in zip(*pts))
    return a, E, f, us, end, message, gaps, partner
