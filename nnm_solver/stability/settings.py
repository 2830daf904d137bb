"""The stability layer's settings: every threshold of stability/, written once, with the measurement behind it.

``STABILITY`` is the instance the code reads (``STABILITY.stability_tol``); names of earlier releases that were public
(``STABILITY_TOL``, ``DECOUPLED_TOL``, ``EVENT_RTOL``, ``RETAIN_LIMIT``, ``LINEAR_BAND``, krein's ``KREIN_DEPTH``,
``LOCAL_CROWD``, ``MARGIN``, ``FLAG_BAND``) stay importable from their modules as aliases of its fields.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["StabilitySettings", "STABILITY"]


@dataclass(frozen=True)
class StabilitySettings:
    """Thresholds of the Floquet multipliers and of the location of events along a step."""

    # ------------------------------------------------------------------ the multipliers (floquet.py)
    #: stability tolerance on the modulus of the non-trivial Floquet multipliers
    stability_tol: float = 1e-5
    #: a mode whose column of the modal element matrix Bq (n_s, n) is at most this fraction of the largest column's
    #: norm does not see the nonlinear elements: its equation q_i'' + w_i^2 q_i = 0 is decoupled from the others, so
    #: its row and column of A11 = dq(T/2)/dq0 are zero but for the diagonal, which is an eigenvalue exactly
    #: (reversible_blocks).  Dropping a coupling of relative size eps moves an eigenvalue by at most ~eps even where
    #: two coincide (the row's and the column's eps multiply), far below the stability tolerance (a pair's imaginary
    #: part at the tolerance: 4e-7 and more); the aircraft: 78 of its 548 modes at most 2e-13 of the largest (the
    #: next 1.5e-12, 7.5e-12, 1e-8)
    decoupled_tol: float = 1e-12

    # ------------------------------------------------------------------ events (events.py, locator.py)
    #: a stability change through +1 is a fold's when the flags on either side of the fold, this many steps from
    #: it, are those of the step's two ends
    fold_reach: float = 1e-2
    #: ... and a located +1 crossing within this many steps of a fold (along the branch) is the fold's too
    fold_merge: float = 5e-2
    #: relative energy tolerance of located events (the finest; see locator.event_rtol)
    event_rtol: float = 1e-8
    #: ... the coarsest, where the time discretisation's error is large anyway
    event_rtol_max: float = 5e-7
    #: a step whose mid-step point lies farther than this from the cubic interpolant of its ends (relative to the
    #: step, balanced norm) jumped onto another branch (Locator.jumped)
    jump_limit: float = 0.05
    #: the mid-step check (locator.mid_step_check) runs where the step is long (at least jump_check_long in the
    #: continuation's balanced norm, a relative change of the orbit: a long step can cross a tongue's entrance and
    #: exit unseen) or a tongue is near (at either end the point's distance from the skeleton's family is at least
    #: jump_check_near x its label's tolerance, labels.Verdict), and wherever no skeleton measures the distance.
    #: Measured (condensed HB, H = 9 on the aircraft, default H on the 2-DOF, shooting on the 2-DOF; 2026-12-07): the
    #: 10 jumps found on the aircraft's NNM 20 (to 6 J skipping tongues, to 20 J following them) were at steps of
    #: 0.0025-0.04 with a distance of 0.049-0.17 of the tolerance; on the smooth stretches the distance is below 5e-4
    #: of it.  With these values the check ran at every step of the aircraft's three runs (to 3, 6 and 20 J: 38, 46
    #: and 40 steps, the same 5 jumps found in each), at 18 of 82 steps on the 2-DOF (HB, to 200 J skipping) and 11 of
    #: 73 (shooting, to 50 J); the same branches
    jump_check_long: float = 0.25
    jump_check_near: float = 0.01
    #: a located point within this many steps of the latest one starts from it (Locator._from_latest; 1: always)
    chord_reach: float = 1.0
    #: ... to a corrector tolerance this much tighter than the continuation's
    chord_tol_factor: float = 1e-2
    #: ... and at most this fraction of the events' relative energy tolerance (Locator.rtol; Locator.chord_tol): a
    #: Krein pair's test function must change across the events' tolerance by more than its noise from the located
    #: orbits' error.  Measured on the aircraft's NNM 20 (gauss6, the defaults; tol 1e-6, rtol 1e-8) at its torus near
    #: 212.8 J: with orbits to 1e-8 (chord_tol_factor alone) the pair's imaginary part (2.8e-6 to 3.9e-6, the threshold
    #: 3.5e-6) jumped between evaluations 1.5e-8 of the step apart by more than it changes over the tolerance's
    #: 2e-8 (the noise ~7e-12 in the squared part against a change of ~4e-14), and the follower ended in 6-10
    #: one-sided halvings; with 1e-10 none.  Its cost is state sweeps (the chord iterations' residuals, ~2 ms each
    #: on the aircraft): to NNM 20's first energy fold 648 -> 775 in the event location, against 73 -> 58 local
    #: evaluations and 217 -> 191 sensitivity sweeps (~17 ms each); NNM 20 skipping tongues to 200 J 4577 -> 4996
    #: state sweeps in the run, the same sensitivity sweeps.  A tolerance from each point's distance to the latest
    #: one instead (looser while the iterates are far apart): 4587 state sweeps there, but to the fold 67 local
    #: evaluations and the halvings back (the final bracket's other end computed far from its neighbours)
    chord_event_fraction: float = 1e-2
    #: ... and must lie within this many times the pseudo-arclength difference from it (the same cut of the curve)
    chord_continuity: float = 3.0
    #: (roots.py) Locator.root bisects once Illinois halved the same end's value this many times running (the
    #: iterates did not cross the root: g is far from linear there, e.g. a jump) ...
    retain_limit: int = 3
    #: ... until a midpoint's value lies within this fraction of |g(b) - g(a)| of the chord (g looks linear again)
    linear_band: float = 0.1

    # ------------------------------------------------------------------ Krein collisions (krein.py)
    #: how a stability change through a complex pair (a Krein collision) is located inside a step: "local" (the
    #: default: krein.locate_collision, the colliding pair followed by the problem's local eigen-solver, the full
    #: spectrum at a few points; the multipliers' eigenproblem of the modes that see the elements) or "dense" (the
    #: reference: bisection on the full stability flag, every eigenproblem of all modes).  Both give the same flags
    #: and the events to the event tolerance (tests/test_krein_routes.py; benchmarks/bench_stability.py on the
    #: aircraft)
    krein_route: str = "local"
    #: complex pairs at a step's unstable end followed to their Krein collisions (the first one changes the
    #: stability)
    max_krein_pairs: int = 4
    #: full-flag probes between the stable end and a located Krein collision (collisions undone inside the step)
    krein_probes: int = 3
    #: nested Krein locations within one step (a pair found complex at a probe or at the stable-side margin point is
    #: followed on the shorter interval), beyond which the full flag is bisected
    krein_depth: int = 3
    #: real coordinates nearer to a complex pair's real part than its imaginary part from which the pair is followed
    #: with a complex shift (the local solver's window holds 6 eigenvalues)
    local_crowd: int = 3
    #: the Krein follower's local evaluations at a shift within this distance of the trivial coordinate c = -1 deflate
    #: the map by the point's own family tangent (a Jacobian at the point); farther away neither is needed
    #: (Locator.local_collision)
    trivial_reach: float = 0.1
    #: the Krein follower's secant iterate within this fraction of the bracket's width from one of its ends is moved
    #: krein_overshoot times as far from that end (krein_follow._clear_of_ends)
    krein_end_fraction: float = 1e-2
    krein_overshoot: float = 10.0
    #: the full flag's change is bracketed around a located collision to this fraction of the locator's energy
    #: tolerance (the two margin points of _flag_change_near)
    krein_margin: float = 0.8
    #: the flag's round-off band at the margin points: relative to stability_tol, the modulus excess |mu| - 1 that
    #: counts as at the threshold (two eigen-solvers' imaginary parts of a pair near its collision differ by ~1e-4
    #: relative)
    flag_band: float = 1e-3

    def __post_init__(self):
        if self.krein_route not in ("local", "dense"):
            raise ValueError(f"krein_route must be 'local' or 'dense', not {self.krein_route!r}")


#: the stability layer's settings (the defaults above, written once)
STABILITY = StabilitySettings()
